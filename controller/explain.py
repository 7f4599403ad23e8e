"""What a layer's optimisation did at one tick: the explain record the four QPs share.

Each layer (the CoM MPC, the pelvic-rotation MPC, the QP inverse kinematics, the arm-swing QP)
solves ``min 1/2 x'Px + q'x  s.t.  l <= A x <= u`` (:mod:`controller.qp`). Its *explanation*
(:class:`QpExplain`) says, in words a student reads:

- how the solve went: solved or not, the solver's status text, iterations and solve time;
- the cost at the solution split into its named terms (tracking, regularisation, each task of
  the IK). The terms are the layer's cost as written in the paper, constants included, so
  they add up to :attr:`QpExplain.objective`; the QP's own objective ``1/2 x'Px + q'x``
  leaves the constants out: ``objective - constant`` (:attr:`QpExplain.constant`);
- every *active* constraint (a row held at its bound) by name ("left knee at its straight
  limit", "ZMP x upper bound at +0.4 s") with its Lagrange multiplier: how much the cost would
  fall per unit the bound were relaxed. A constraint that is not active could be removed
  without changing the solution; the active set is what stops the layer;
- when the solve failed, what the layer's fallback did instead.

Multipliers: DAQP's dual ``lam`` of the last solve when the solver still holds it (the
explanation is made right after the tick, the display's and the recording's case), else
recovered from the KKT conditions at the solution on the active rows, ``P x + q + A_act'
lam = 0``, by a small least-squares solve. Sign as DAQP's: ``lam > 0`` pushes against an
upper bound, ``lam < 0`` against a lower one; :attr:`ActiveConstraint.multiplier` is its size.

Nothing here runs in a tick: a layer keeps references to its last QP and solution (the
solver's :attr:`~controller.qp.QpSolver.last_qp`, ``last_x``) and the explanation is computed
only when something asks (:func:`controller.tick_explain.explain_tick`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.qp import QP, QpSolver

LAYER_NAMES = ("com_mpc", "pelvis_mpc", "ik", "arm_swing")
LAYER_TITLES = {
    "com_mpc": "CoM MPC (eq. 18)",
    "pelvis_mpc": "pelvic-rotation MPC (eq. 37)",
    "ik": "QP inverse kinematics (eq. 39)",
    "arm_swing": "arm-swing QP (eq. 43)",
}
ACTIVE_SET_MEANING = (
    "A constraint is active when the solution sits on its bound: it is what stops the "
    "optimisation from doing better. Its multiplier says how much the cost would fall per unit "
    "the bound were relaxed; every constraint not listed could be removed without changing "
    "this tick's answer."
)
ACTIVE_TOL = 1e-7  # a row is at its bound within this (scaled by 1 + |bound|)


@dataclass(frozen=True)
class ActiveConstraint:
    """One active constraint of a layer's QP at the solution."""

    name: str  # what a student reads: "left knee at its straight limit"
    kind: str  # "joint limit", "speed limit", "pinned", "ZMP bound", "angle limit", ...
    side: str  # "upper", "lower" or "pinned" (an equality row)
    lam: float  # Lagrange multiplier, DAQP's sign (> 0 upper, < 0 lower)
    bound: float  # the bound's value (the row's unit: m, rad, rad/s ...)
    row: int  # the row of the layer's QP
    joint: str | None = None  # the joint (models.dyros_jet name) it holds, if any
    ahead_s: float | None = None  # [s] how far ahead in the horizon (the MPCs' rows)
    axis: str | None = None  # "x" / "y" (the CoM MPC's ZMP rows)

    @property
    def multiplier(self) -> float:
        """|lam|: the cost saved per unit the bound were relaxed (the row's unit)."""
        return abs(self.lam)


@dataclass(frozen=True)
class QpExplain:
    """What one layer's QP did at one tick (module docstring)."""

    layer: str  # one of LAYER_NAMES
    title: str
    ran: bool  # the layer solved a QP this tick (the pelvic MPC runs for method mpc only)
    ok: bool  # solved (False: failed, and the fallback was used)
    status: str  # the solver's status text
    iterations: int  # active-set iterations (-1 unknown)
    solve_ms: float  # [ms] the solver's time (NaN unknown)
    objective: float  # the layer's cost at the solution: the sum of ``terms``
    constant: float  # the part of it the QP leaves out (objective - (1/2 x'Px + q'x))
    terms: dict[str, float] = field(default_factory=dict)  # named cost terms
    active: tuple[ActiveConstraint, ...] = ()
    fallback: str = ""  # what the layer did instead when the solve failed ("" when solved)
    n_variables: int = 0
    n_constraints: int = 0
    note: str = ""  # one sentence more (e.g. why the layer did not run)

    @property
    def qp_objective(self) -> float:
        """1/2 x'Px + q'x, the QP's objective at the solution."""
        return self.objective - self.constant

    def names(self) -> list[str]:
        """The active constraints' names."""
        return [c.name for c in self.active]

    def to_dict(self) -> dict:
        """Plain JSON-able data (the API's and the recordings' form)."""
        return {
            "layer": self.layer,
            "title": self.title,
            "ran": self.ran,
            "ok": self.ok,
            "status": self.status,
            "iterations": self.iterations,
            "solve_ms": _finite(self.solve_ms),
            "objective": _finite(self.objective),
            "qp_objective": _finite(self.qp_objective),
            "terms": {k: _finite(v) for k, v in self.terms.items()},
            "active": [
                {
                    "name": c.name,
                    "kind": c.kind,
                    "side": c.side,
                    "multiplier": _finite(c.multiplier),
                    "lam": _finite(c.lam),
                    "bound": _finite(c.bound),
                    "row": c.row,
                    "joint": c.joint,
                    "ahead_s": c.ahead_s,
                    "axis": c.axis,
                }
                for c in self.active
            ],
            "fallback": self.fallback,
            "n_variables": self.n_variables,
            "n_constraints": self.n_constraints,
            "note": self.note,
        }


@dataclass(frozen=True)
class TickExplain:
    """The four layers' explanations at one tick."""

    t: float  # [s] the robot's time after the tick (as the series' ``t``)
    method: str
    layers: tuple[QpExplain, ...]  # in LAYER_NAMES order

    def layer(self, name: str) -> QpExplain:
        for e in self.layers:
            if e.layer == name:
                return e
        raise KeyError(f"no layer {name!r} (layers: {', '.join(LAYER_NAMES)})")

    def __getitem__(self, name: str) -> QpExplain:
        return self.layer(name)

    def counts(self) -> dict[str, int]:
        """Active constraints per layer."""
        return {e.layer: len(e.active) for e in self.layers}

    def to_dict(self) -> dict:
        return {
            "t": self.t,
            "method": self.method,
            "meaning": ACTIVE_SET_MEANING,
            "layers": [e.to_dict() for e in self.layers],
        }


def _finite(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def not_run(layer: str, note: str) -> QpExplain:
    """The explanation of a layer that solved no QP this tick."""
    return QpExplain(
        layer, LAYER_TITLES[layer], False, True, "not run", -1, math.nan, 0.0, 0.0, note=note
    )


# -- the generic part ---------------------------------------------------------------------
def active_rows(qp: QP, x: np.ndarray, tol: float = ACTIVE_TOL) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``qp`` at a bound at ``x``: (indices, side) with side +1 upper, -1 lower,
    0 an equality row (l == u)."""
    ax = qp.A @ x
    l, u = qp.l, qp.u
    eq = np.abs(u - l) <= tol * (1.0 + np.abs(u))
    at_u = np.abs(ax - u) <= tol * (1.0 + np.abs(u))
    at_l = np.abs(ax - l) <= tol * (1.0 + np.abs(l))
    rows = np.flatnonzero(eq | at_u | at_l)
    side = np.where(eq[rows], 0, np.where(at_u[rows], 1, -1))
    return rows, side


def kkt_multipliers(qp: QP, x: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Multipliers of the active ``rows`` from ``P x + q + A_act' lam = 0`` (least squares)."""
    if len(rows) == 0:
        return np.zeros(0)
    grad = qp.P @ x + qp.q
    lam, *_ = np.linalg.lstsq(qp.A[rows].T, -grad, rcond=None)
    return lam


def multipliers(qp: QP, x: np.ndarray, solver: QpSolver | None) -> tuple[np.ndarray, np.ndarray]:
    """(rows, lam) of the active constraints: DAQP's duals when ``solver`` still holds them
    for this very QP (non-zero ones, and every equality row), else the rows at a bound with
    their KKT multipliers (rows whose multiplier is ~0 dropped: weakly active)."""
    duals = solver.last_duals(qp) if solver is not None else None
    if duals is not None:
        eq = np.abs(qp.u - qp.l) <= ACTIVE_TOL * (1.0 + np.abs(qp.u))
        rows = np.flatnonzero((duals != 0.0) | eq)
        return rows, duals[rows].copy()
    rows, side = active_rows(qp, x)
    lam = kkt_multipliers(qp, x, rows)
    # a multiplier of the wrong sign or ~0: the row is at its bound but not holding the answer
    scale = 1e-9 * (1.0 + float(np.abs(qp.P @ x + qp.q).max(initial=0.0)))
    keep = (side == 0) | ((side * lam) > scale)
    return rows[keep], lam[keep]


def solver_stats(solver: QpSolver | None, qp: QP) -> tuple[int, float]:
    """(iterations, solve time [ms]) of the solver's last solve when it was ``qp``."""
    if solver is None:
        return -1, math.nan
    return solver.last_stats(qp)


def explain_qp(
    layer: str,
    qp: QP,
    x: np.ndarray,
    ok: bool,
    status: str,
    solver: QpSolver | None,
    terms: dict[str, float],
    name_row: Callable[[int, float, float], ActiveConstraint],
    fallback: str,
    constant: float,
    note: str = "",
) -> QpExplain:
    """The explanation of one solve: ``terms`` (named cost terms at ``x``, constants
    included; ``constant``: their part the QP leaves out, computed by the layer from its own
    data, so ``sum(terms) - constant == 1/2 x'Px + q'x`` checks the split), each active row
    named by ``name_row(row, lam, bound)``."""
    iterations, solve_ms = solver_stats(solver, qp)
    objective = float(sum(terms.values()))
    active: Sequence[ActiveConstraint] = ()
    if ok:
        rows, lam = multipliers(qp, x, solver)
        active = [
            name_row(int(r), float(lm), float(qp.u[r] if lm >= 0 else qp.l[r]))
            for r, lm in zip(rows, lam, strict=True)
        ]
        active = sorted(active, key=lambda c: -c.multiplier)
    return QpExplain(
        layer,
        LAYER_TITLES[layer],
        True,
        ok,
        status,
        iterations,
        solve_ms,
        objective,
        float(constant),
        terms,
        tuple(active),
        "" if ok else fallback,
        qp.P.shape[0],
        qp.A.shape[0],
        note,
    )


def side_of(lam: float, pinned: bool) -> str:
    if pinned:
        return "pinned"
    return "upper" if lam >= 0 else "lower"


def ahead_text(seconds: float) -> str:
    """ "+0.4 s" (up to two decimals, trailing zeros dropped)."""
    return f"+{seconds:.2f}".rstrip("0").rstrip(".") + " s"


def joint_words(name: str) -> str:
    """A joint's name as a student reads it: "L_knee" -> "left knee", "waist_yaw" -> "waist"."""
    if name == "waist_yaw":
        return "waist"
    side = {"L_": "left ", "R_": "right "}.get(name[:2], "")
    rest = name[2:] if side else name
    return side + rest.replace("_", " ")


# the limit that straightens a joint, by the joint's name without its side (the knees bend
# positive, the elbows negative: models/dyros_jet/README.md)
_STRAIGHT = {"knee": "lower", "elbow": "upper"}


def joint_bound(
    row: int,
    joint: str,
    lam: float,
    bound: float,
    speed_limit: float,
    q_limit: tuple[float, float],
) -> ActiveConstraint:
    """A velocity bound row of the IK or the arm QP, named: a joint limit reached within this
    tick ("left knee at its straight limit") or the speed limit."""
    side = side_of(lam, False)
    words = joint_words(joint)
    if abs(abs(bound) - speed_limit) <= 1e-9 * (1.0 + speed_limit):
        return ActiveConstraint(
            f"{words} at its speed limit ({bound:+.1f} rad/s)",
            "speed limit", side, lam, bound, row, joint,
        )  # fmt: skip
    limit = q_limit[1] if side == "upper" else q_limit[0]
    straight = _STRAIGHT.get(joint[2:] if joint[:2] in ("L_", "R_") else joint)
    if straight is not None:
        which = "straight" if side == straight else "fully bent"
    else:
        which = side
    deg = round(math.degrees(limit))
    return ActiveConstraint(
        f"{words} at its {which} limit ({f'{deg:+d}' if deg else '0'} deg)",
        "joint limit", side, lam, bound, row, joint,
    )  # fmt: skip
