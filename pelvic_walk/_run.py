"""One headless walk from Python (:func:`simulate` -> :class:`Run`), tables of runs
(:func:`compare`) and the kinematic analysis (:func:`analyze`).

A run is ``pelvic-walk simulate``'s run: the same parameters, seed and checks
(``pelvic_walk.core.run.spec_of``: the study's run of the same cell), so ``Run.summary`` equals
``simulate --json`` for the same arguments.
"""

from __future__ import annotations

import dataclasses
import html
import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from controller.analysis import (
    PAPER_L_LEG,
    PAPER_L_PEL,
    PAPER_THETA_PEL_DEG,
    PAPER_W_STEP,
    PAPER_Z0,
)
from controller.params import ControllerParams
from pelvic_walk import _params
from pelvic_walk._plots import differing_params, labels, param_value
from pelvic_walk.core.metrics import COLUMN_UNITS, COLUMNS, with_unit
from pelvic_walk.core.summary import COMPARE_KEYS
from pelvic_walk.core.summary import outcome as summary_outcome

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.figure import Figure

    from controller.explain import TickExplain
    from pelvic_walk.core.capture import Capture
    from pelvic_walk.core.frames import LiveFrame

HORIZON_COLUMNS = (  # Run.horizon(): (column, unit)
    ("t", "s"),
    ("ahead", "s"),
    ("com_x", "m"),
    ("com_y", "m"),
    ("zmp_x", "m"),
    ("zmp_y", "m"),
    ("zmp_ref_x", "m"),
    ("zmp_ref_y", "m"),
    ("zmp_min_x", "m"),
    ("zmp_max_x", "m"),
    ("zmp_min_y", "m"),
    ("zmp_max_y", "m"),
    ("left_foot_x", "m"),
    ("left_foot_y", "m"),
    ("right_foot_x", "m"),
    ("right_foot_y", "m"),
    ("theta_ref", "rad"),
    ("theta", "rad"),
)
NOTEBOOK_EXTRA = "pip install 'pelvic-walk[notebook]'"


def pandas() -> Any:
    """The pandas module, or ImportError saying how to install it (the notebook extra)."""
    try:
        import pandas as pd
    except ImportError:
        raise ImportError(
            f"tables of runs need pandas, which is not installed: {NOTEBOOK_EXTRA}"
        ) from None
    return pd


class Run:
    """One finished walk: its summary, time series, plots and 3-D player.

    Attributes:
        summary: the keys of ``pelvic-walk simulate --json`` (docs/REFERENCE.md), e.g.
            ``run.summary["waist_yaw_max_deg"]``.
        method: the strategy's name. params: every parameter of the run
            (``run.params.pelvis.k_pel``). seed: the study's repeat number, or None.
    """

    def __init__(
        self,
        params: ControllerParams,
        seed: int | None,
        summary: dict[str, Any],
        columns: dict[str, np.ndarray],
        frames: Sequence[LiveFrame],
        capture: Capture,
    ):
        self.params = params
        self.method = params.method
        self.seed = seed
        self.summary = summary
        self._columns = columns
        self._frames = tuple(frames)
        self._capture = capture
        self._player: Player | None = None

    # -- numbers ---------------------------------------------------------------------------
    @property
    def series(self) -> pd.DataFrame:
        """One row per control tick (5 ms), columns named with their units (``"t [s]"``,
        ``"waist_angle [rad]"``, ``"yaw_momentum [kg m^2/s]"``, ``"kappa_legs"``): the columns of
        ``simulate --csv`` (docs/REFERENCE.md, "simulate CSV"). NaN where a value does not
        exist (no foot on the floor). A new DataFrame each time: change it freely."""
        pd = pandas()
        return pd.DataFrame(
            {with_unit(c, COLUMN_UNITS[c]): self._columns[c] for c in COLUMNS}, copy=True
        )

    def column(self, name: str) -> np.ndarray:
        """One column of :attr:`series` by its bare name (``"waist_angle"``), as an array."""
        if name not in self._columns:
            raise ValueError(f"no column {name!r} (one of: {', '.join(COLUMNS)})")
        return self._columns[name].copy()

    def horizon(self, t: float) -> pd.DataFrame:
        """The plan over the MPC horizon as the controller saw it at time ``t`` [s] (the
        nearest recorded instant, 20 a second): one row per horizon sample, N = horizon / MPC
        sample; ``t [s]`` the sample's time in the walk, ``ahead [s]`` its time from the
        instant; the predicted CoM and ZMP (eq. 25-26, 16-17), the ZMP reference and bounds
        (eq. 18), the planned feet (eq. 20-21), the reference pelvic angle theta_ref (eq. 33)
        and theta, the pelvic MPC's optimised angle (eq. 35; for a method that does not plan,
        the angle now held). ``df.attrs["t"]`` is the instant's time."""
        pd = pandas()
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"t must be a finite time [s], got {t}")
        frames = [f for f in self._frames if f.robots[0].horizon is not None]
        if not frames:
            raise ValueError("the run recorded no horizon (it stopped before its first tick)")
        times = np.array([f.robots[0].t for f in frames])
        if t < times[0] - 0.05 or t > times[-1] + 0.05:
            raise ValueError(
                f"t = {t:g} s is outside the run ({times[0]:.2f} to {times[-1]:.2f} s)"
            )
        robot = frames[int(np.argmin(np.abs(times - t)))].robots[0]
        h = robot.horizon
        assert h is not None
        values = {
            # on the MPC's sample grid: rounded to the microsecond, so == 1.0 finds a sample
            "t": np.round(robot.t + h.t, 6),
            "ahead": np.round(h.t, 6),
            **h.plane_columns(),
            "theta_ref": h.theta_ref,
            "theta": h.theta,
        }
        df = pd.DataFrame({with_unit(c, u): np.asarray(values[c]) for c, u in HORIZON_COLUMNS})
        df.attrs["t"] = round(robot.t, 6)
        return df

    def qp(self, t: float) -> TickExplain:
        """What each layer's optimisation did at time ``t`` [s] (the nearest recorded
        instant: 20 a second, and every tick at which a layer's count of active constraints
        changed, so the instant a bound starts binding is exact; ``.t`` is its time): for the
        CoM MPC, the pelvic MPC, the IK
        and the arm swing (``rec["ik"]``), the solver's status, iterations and time, the cost
        split into its named terms (``.terms``, adding up to ``.objective``), every active
        constraint by name with its multiplier (``.active``, ``.names()``), and what the
        fallback did when a solve failed. ``rec.to_dict()`` is ``GET /api/qp``'s ``layers``.
        The series' ``active_*`` columns count the active constraints at every tick."""
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"t must be a finite time [s], got {t}")
        recs = [f.robots[0].qp for f in self._frames if f.robots[0].qp is not None]
        recs = sorted([*recs, *self._capture.qp_records], key=lambda r: r.t)
        if not recs:
            raise ValueError("the run recorded no QP (it stopped before its first tick)")
        times = np.array([r.t for r in recs])
        if t < times[0] - 0.05 or t > times[-1] + 0.05:
            raise ValueError(
                f"t = {t:g} s is outside the run ({times[0]:.2f} to {times[-1]:.2f} s)"
            )
        return recs[int(np.argmin(np.abs(times - t)))]

    @property
    def command(self) -> str:
        """The ``pelvic-walk simulate`` command line that makes the same run."""
        from pelvic_walk.core.run import spec_of

        return spec_of(self.params, self.seed).command()

    @property
    def label(self) -> str:
        return self.method

    # -- pictures --------------------------------------------------------------------------
    def plot(self, *panels: str, others: Iterable[Run] = ()) -> Figure:
        """The usual plots against time (a matplotlib Figure), one line per run: by default
        waist yaw, waist rate, yaw momentum, kappa of the legs (log) and energy; name panels
        to choose (``run.plot("waist", "theta_ref")``; ``pelvic_walk.PANELS`` lists them).
        ``others``: more runs drawn beside this one (``pelvic_walk.plot(runs)`` the same)."""
        from pelvic_walk._plots import plot

        return plot([self, *others], *panels)

    def player(self) -> Player:
        """The run's 3-D scene as the recording's page plays it (viser's client in one
        self-contained page: no server, no internet); shows itself in a notebook."""
        if self._player is None:
            from app.web import recording  # the viewer, a face: loaded only here

            rec = recording.of_capture(self._capture, f"pelvic_walk.simulate: {self.command}")
            with _quiet():  # the scene's viser server announces itself (rich, in a notebook)
                page = recording.scene_html(rec)
            self._player = Player(page, rec.duration, self.label)
        return self._player

    def show(self, height: int = 480) -> None:
        """Play the run's 3-D scene inline in a notebook (drag to turn, scroll to zoom; the
        bar at the bottom pauses and scrubs). Outside a notebook: :meth:`player` and
        ``Player.save("walk.html")``, then open the file in a browser."""
        player = self.player()
        player.height = height
        if _ipython() is None:
            raise RuntimeError(
                "show() plays the scene in a notebook; here use run.player().save('walk.html') "
                "and open the file in a browser"
            )
        from IPython.display import display

        display(player)

    def __repr__(self) -> str:
        s = self.summary
        outcome = summary_outcome(s)
        le = s["landing_error_max"]
        landing = f"{le * 100:.1f} cm" if le is not None else "- (none measured)"
        return (
            f"<Run {self.method}: {s['step_length']:.2f} m x {s['steps_planned']} steps, "
            f"{outcome}, {s['steps_completed']}/{s['steps_planned']} landed, landing error max "
            f"{landing}, waist max "
            f"{s['waist_yaw_max_deg']:.1f} deg, yaw momentum peak {s['yaw_momentum_peak']:.2f} "
            f"kg m^2/s, kappa(legs) max {s['condition_number_legs_max']:.0f}>"
        )


def _ipython() -> Any:
    """The running IPython shell (a notebook's kernel), or None."""
    try:
        from IPython import get_ipython
    except ImportError:
        return None
    return get_ipython()


def _quiet() -> Any:
    """A context that keeps prints and displays out of a notebook's output (a no-op outside)."""
    import contextlib

    if _ipython() is None:
        return contextlib.nullcontext()
    from IPython.utils.capture import capture_output

    return capture_output(display=True)


class Player:
    """A run's 3-D scene: one self-contained HTML page (:attr:`html`). In a notebook it shows
    itself in a frame (``srcdoc``: nothing is written or served); :meth:`save` writes the
    page, which any browser opens offline."""

    def __init__(self, page: str, duration: float, label: str, height: int = 480):
        self.html = page
        self.duration = duration
        self.label = label
        self.height = height

    def _repr_html_(self) -> str:
        return (
            f'<iframe srcdoc="{html.escape(self.html, quote=True)}" style="width:100%;'
            f'height:{int(self.height)}px;border:1px solid #ccc" title="pelvic-walk: '
            f'{html.escape(self.label)}, {self.duration:.1f} s"></iframe>'
        )

    def save(self, path: Any) -> Any:
        """Write the page to ``path`` (open it in a browser); returns the path."""
        from pathlib import Path

        p = Path(path)
        p.write_text(self.html)
        return p

    def __repr__(self) -> str:
        return f"<Player {self.label}, {self.duration:.1f} s, {len(self.html) / 1e6:.1f} MB>"


def simulate(
    method: str | None = None,
    *,
    strategy: Any = None,
    step_length: float | None = None,
    steps: int | None = None,
    seed: int | None = None,
    disturbance: float | None = None,
    backend: str = "daqp",
    **params: Any,
) -> Run:
    """One headless closed-loop walk, as ``pelvic-walk simulate`` makes it.

    Args:
        method: ``"fixed"``, ``"redundancy"``, ``"mpc"`` (the default) or a strategy loaded
            before.
        strategy: instead of ``method``: your own pelvis, a ``PelvisStrategy`` subclass
            (defined in the notebook) or a file ``"FILE.py[:Class]"`` (docs/STRATEGIES.md).
        step_length: [m] (default 0.2). steps: walking steps (default 10).
        seed: the study's repeat ``seed``: a small start perturbation and seeded pushes of
            ``disturbance`` N (default 5) on the torso; None: deterministic, no pushes.
        backend: the QP solver of every layer, ``"daqp"`` or ``"osqp"``.
        **params: any other parameter by its command-line name with underscores
            (``step_time=1.0``, ``horizon=1.2``, ``arms=False``, ``pelvis_k_pel=0.3``) or by
            its dotted name (``**{"pelvis.k_pel": 0.3}``), a strategy's own parameter by
            ``NAME.FIELD`` (``**{"gain.k": 12}``: its ``Params``, docs/STRATEGIES.md);
            ``pelvic-walk simulate --help`` lists the paper's with their ranges.

    Raises:
        ValueError: a bad value, with the one line the command line prints.
    """
    from pelvic_walk.core.capture import Capture
    from pelvic_walk.core.run import run, spec_of, summarize

    name = _params.method_of(method, strategy)
    cfg_params = _params.controller_params(
        name, {"step_length": step_length, "steps": steps, **params}
    )
    seed = _params.check_seed(seed)
    if backend not in _params.BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(_params.BACKENDS)}, got {backend!r}")
    if disturbance is not None:
        if seed is None:
            raise ValueError("disturbance needs a seed (the pushes are drawn from the seed)")
        d = _params._plain(disturbance)
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d < 0:
            raise ValueError(f"disturbance must be a number of newtons >= 0, got {disturbance!r}")
    cfg = spec_of(cfg_params, seed).config()  # the CLI's and the study's run of this cell
    if disturbance is not None:
        cfg = dataclasses.replace(cfg, disturbance=float(disturbance))
    cfg = dataclasses.replace(cfg, backend=backend)
    capture = Capture(name)
    session = run(cfg, on_tick=capture.capture)
    summary = summarize(session)
    columns = {c: session.series.column(c) for c in COLUMNS}
    # on the 5 ms grid to the microsecond (a sum of periods drifts by 1e-15): == 2.0 finds a tick
    columns["t"] = np.round(columns["t"], 6)
    return Run(cfg.params, seed, summary, columns, capture.frames, capture)


def compare(runs: Iterable[Run], keys: Sequence[str] | None = None) -> pd.DataFrame:
    """One table, a row per run: the parameters that differ between the runs, then the
    summary keys that compare walks (``keys`` to choose others: any of ``run.summary``).
    Timing keys (``wall_time``, ``tick_ms_*``) depend on the machine; ask for them by name."""
    pd = pandas()
    runs = list(runs)
    if not runs or not all(isinstance(r, Run) for r in runs):
        raise ValueError("compare() takes a list of runs made by pelvic_walk.simulate")
    keys = COMPARE_KEYS if keys is None else tuple(keys)
    unknown = [k for k in keys if k not in runs[0].summary]
    if unknown:
        raise ValueError(
            f"unknown summary key {unknown[0]!r} (one of: {', '.join(runs[0].summary)})"
        )
    differing = differing_params(runs)
    rows = []
    for r in runs:
        row: dict[str, Any] = {"method": r.method, "step_length": r.params.walk.step_length}
        row |= {d: param_value(r, d) for d in differing if d != "walk.step_length"}
        row |= {k: r.summary[k] for k in keys}
        rows.append(row)
    return pd.DataFrame(rows, index=pd.Index(labels(runs), name="run"))


def analyze(
    l_leg: float = PAPER_L_LEG,
    z0: float = PAPER_Z0,
    l_pel: float = PAPER_L_PEL,
    w_step: float = PAPER_W_STEP,
    theta_pel_deg: float = PAPER_THETA_PEL_DEG,
    rule: str = "paper",
) -> dict[str, float]:
    """The kinematic analysis of eq. (1)-(5) (``pelvic-walk analyze``): the longest step
    without and with a pelvic turn of ``theta_pel_deg``, the paper's inputs by default.

    Returns the keys of ``analyze --json``: the inputs, ``step_max_fixed_static`` (eq. 4),
    ``step_max_rotation_static`` (eq. 5), ``step_max_fixed_stretched`` (eq. 1),
    ``step_max_rotation_stretched`` (eq. 3) [m] and ``increase_percent`` (eq. 5 over 4).
    ``rule="literal"`` evaluates eq. (5)'s offset as printed (docs/DESIGN.md)."""
    from controller.analysis import RULES, kinematic_analysis

    inputs = {"l_leg": l_leg, "z0": z0, "l_pel": l_pel, "w_step": w_step}
    for name, value in inputs.items():
        value = _params._plain(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{name} must be a number [m], got {value!r}")
        if not math.isfinite(value) or value <= 0:
            raise ValueError(f"{name} must be a positive length [m], got {value!r}")
    theta = _params._plain(theta_pel_deg)
    if isinstance(theta, bool) or not isinstance(theta, (int, float)) or not math.isfinite(theta):
        raise ValueError(f"theta_pel_deg must be a finite angle [deg], got {theta_pel_deg!r}")
    if not -90 <= theta <= 90:
        raise ValueError(f"theta_pel_deg must be within -90..90 deg, got {theta}")
    if rule not in RULES:
        raise ValueError(f"rule must be one of {', '.join(RULES)}, got {rule!r}")
    return kinematic_analysis(
        float(l_leg), float(z0), float(l_pel), float(w_step), float(theta), rule
    )


def robot() -> dict[str, float]:
    """Our robot's numbers for :func:`analyze` (models/dyros_jet, docs/DESIGN.md): ``l_leg``
    hip to ankle with the knee straight, ``z0`` the walking hip height above the ankle,
    ``l_pel`` the distance between the hip joints, ``w_step`` the feet's lateral distance [m]."""
    from models.dyros_jet import HIP_HEIGHT_Z0, HIP_OFFSET, LEG_LENGTH, W_STEP

    return {
        "l_leg": float(LEG_LENGTH),
        "z0": float(HIP_HEIGHT_Z0),
        "l_pel": float(2 * HIP_OFFSET[1]),
        "w_step": float(W_STEP),
    }
