"""Section 10: what the MPC buys. The paper's MPC beside strategies that turn the pelvis more
simply, on the same measures from the same kind of run.

The rows: the fixed pelvis and the MPC (the study's own runs), then each strategy of
:attr:`Study.ablation_methods`: the checkout's two examples (``examples/track_reference.py``,
a gain on the MPC's own reference theta_ref with no plan over the horizon;
``examples/feedforward_sine.py``, a sine over the step that reads neither the reference nor
the predicted CoM) and every ``experiments --strategy`` file. Each row is measured the same way:

- the longest clean step and the longest that walks, from the unseeded runs of the sweep grid
  and its refinement (:func:`limits.max_step`'s rule, the same resolution for every row);
- at each figure length: whether the run is clean, the peak |waist angle| and the energy of
  the two-step windows (sampled at 200 Hz, and from every 1 ms substep), from the same
  unseeded 10-step runs (not Table 1's seeded repeats, which only the paper's three run);
- at the longer figure length: the early turn's size before lift-off (share of the waist's
  range and of a sine's, :mod:`waist`), the peak change of the waist rate, kappa(legs) at
  landing (median);
- the largest sideways push survived, both directions, at ``Ablations.push_length``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from app.experiments.definitions import Study, sweep_bracket
from app.experiments.kappa import kappa_case
from app.experiments.limits import figure_lengths_run
from app.experiments.outcomes import Results, RunSummary, length_key, step_of, summary_of
from app.experiments.robustness import PushCell, push_key
from app.experiments.waist import waist_case
from controller import strategy
from pelvic_walk.core.measure import walks


@dataclass(frozen=True)
class AblationRow:
    """One strategy on section 10's measures (None: not measured, e.g. the run fell)."""

    method: str
    label: str
    role: str  # "paper" (fixed, redundancy, mpc), "example" (examples/), "yours" (--strategy)
    source: str | None  # the strategy's file (None: a built-in)
    longest_clean: float | None  # [m]
    first_failed: float | None  # [m]
    walks_limit: float | None  # [m] the longest step it walks (may be unclean)
    clean: dict[str, bool]  # figure length -> the run is clean
    waist_peak_deg: dict[str, float | None]  # figure length -> peak |waist angle|
    energy: dict[str, float | None]  # figure length -> two-step energy mean, 200 Hz [J]
    energy_substep: dict[str, float | None]  # the same from every 1 ms substep [J]
    energy_std: dict[str, float | None]  # figure length -> std over the run's windows, 200 Hz
    early_turn_share: float | None  # at the longer figure length, share of the range
    early_turn_of_sine: float | None  # the same / a sine's over the step
    peak_rate_change_deg_s2: float | None
    kappa_legs_landing: float | None  # median at landing, the longer figure length
    pushes: dict[str, PushCell | None] = field(default_factory=dict)  # direction -> survival
    strategy_ms_median: float | None = None  # the strategy's median time a tick [ms]
    energy_std_substep: dict[str, float | None] = field(default_factory=dict)  # ... 1 ms


@dataclass(frozen=True)
class AblationSection:
    lengths: list[float]  # [m] the figure lengths
    turn_length: float  # [m] where the waist's turn and kappa are read
    push_length: float  # [m]
    resolution: float  # [m] of the longest step
    rows: list[AblationRow]
    push_resolution: float = 0.0  # [N] of the push bisection


def _role(m: str, study: Study) -> str:
    if m in study.methods:
        return "paper"
    source = strategy.info(m).source or ""
    return "yours" if any(source.startswith(_abs(s)) for s in study.strategies) else "example"


def _abs(source: str) -> str:
    return os.path.abspath(os.path.expanduser(strategy.parse_source(source)[0]))


def row(
    study: Study, results: Results, pushes: dict[str, PushCell | None], m: str, push_length: float
) -> AblationRow:
    """Section 10's measures of strategy ``m`` from the study's runs (its pushes at
    ``push_length``)."""
    info = strategy.info(m)
    sums = {
        x: summary_of(results, study.figure_run(m, x))
        for x in figure_lengths_run(study, results, m)
    }
    longest, failed = sweep_bracket({x: bool(s and s.clean) for x, s in sums.items()})
    walks_limit, _ = sweep_bracket({x: bool(s and walks(s.as_dict())) for x, s in sums.items()})
    at = {x: summary_of(results, study.figure_run(m, x)) for x in study.figure_lengths}
    x_turn = max(study.figure_lengths)
    ex = step_of(results, study.figure_run(m, x_turn))
    turn = waist_case(m, x_turn, ex) if ex is not None and len(ex.t) >= 3 else None
    kc = kappa_case(study, results, m, x_turn)
    directions = study.pushes.directions if study.pushes else ()
    return AblationRow(
        method=m,
        label=info.label,
        role=_role(m, study),
        source=info.source,
        longest_clean=longest,
        first_failed=failed,
        walks_limit=walks_limit,
        clean={length_key(x): bool(s and s.clean) for x, s in at.items()},
        waist_peak_deg={length_key(x): s.waist_yaw_max_deg if s else None for x, s in at.items()},
        energy={length_key(x): _energy(s, substep=False) for x, s in at.items()},
        energy_substep={length_key(x): _energy(s, substep=True) for x, s in at.items()},
        energy_std={length_key(x): _energy_std(s) for x, s in at.items()},
        energy_std_substep={length_key(x): _energy_std(s, substep=True) for x, s in at.items()},
        early_turn_share=turn.early_turn_share if turn else None,
        early_turn_of_sine=turn.early_turn_of_sine if turn else None,
        peak_rate_change_deg_s2=turn.peak_abs_rate_change_deg_s2 if turn else None,
        kappa_legs_landing=kc.kappa_legs_landing_median if kc else None,
        pushes={d: pushes.get(push_key(m, push_length, d)) for d in directions},
        strategy_ms_median=_ms(at.get(x_turn)),
    )


def _energy(s: RunSummary | None, substep: bool) -> float | None:
    """The mean of a run's two-step windows [J] (None: no window)."""
    if s is None:
        return None
    windows = s.energy_two_step_windows_substep if substep else s.energy_two_step_windows
    return float(np.mean(windows)) if windows else None


def _energy_std(s: RunSummary | None, substep: bool = False) -> float | None:
    w = (s.energy_two_step_windows_substep if substep else s.energy_two_step_windows) if s else []
    return float(np.std(w, ddof=1)) if len(w) > 1 else None


def _ms(s: RunSummary | None) -> float | None:
    return None if s is None else s.other.get("strategy_ms_median")


def ablation(
    study: Study, results: Results, pushes: dict[str, PushCell | None] | None
) -> AblationSection | None:
    """Section 10 (None when the study runs no strategy beside the paper's)."""
    others = study.ablation_methods()
    if not others:
        return None
    paper = [m for m in (strategy.FIXED, strategy.REDUNDANCY, strategy.MPC) if m in study.methods]
    x_push = study.ablations.push_length if study.ablations else max(study.figure_lengths)
    return AblationSection(
        lengths=list(study.figure_lengths),
        turn_length=max(study.figure_lengths),
        push_length=x_push,
        resolution=study.sweep_resolution,
        rows=[row(study, results, pushes or {}, m, x_push) for m in (*paper, *others)],
        push_resolution=study.pushes.resolution if study.pushes else 0.0,
    )


def _diff(a: float | None, b: float | None, unit: str, spec: str = "+.2f") -> str:
    return "—" if a is None or b is None else f"{a - b:{spec}} {unit}"


def reading(section: AblationSection) -> list[str]:
    """One sentence per strategy beside the paper's: what it does against the MPC, and
    against the fixed pelvis, on the section's measures."""
    by = {r.method: r for r in section.rows}
    mpc, fixed = by.get(strategy.MPC), by.get(strategy.FIXED)
    if mpc is None:
        return []
    x = length_key(section.turn_length)
    out = []
    for r in section.rows:
        if r.role == "paper":
            continue
        parts = [
            f"longest clean step {_m(r.longest_clean)} against the MPC's {_m(mpc.longest_clean)}"
            + (f" and the fixed pelvis's {_m(fixed.longest_clean)}" if fixed else "")
        ]
        parts.append(
            f"waist at {section.turn_length:.2f} m {_deg(r.waist_peak_deg.get(x))} "
            f"(MPC {_deg(mpc.waist_peak_deg.get(x))})"
        )
        if r.early_turn_share is not None and mpc.early_turn_share is not None:
            parts.append(
                f"turn before lift-off {100 * r.early_turn_share:.1f} % of its range "
                f"(MPC {100 * mpc.early_turn_share:.1f} %)"
            )
        margins = [
            f"{_diff(push_n(c), push_n(mpc.pushes.get(d)), 'N', '+.0f')} {d}"
            for d, c in r.pushes.items()
        ]
        if margins:
            parts.append(
                f"largest push survived at {section.push_length:.2f} m against the MPC's: "
                + ", ".join(margins)
            )
        e, em = r.energy.get(x), mpc.energy.get(x)
        if e is not None and em is not None:
            parts.append(f"energy at {section.turn_length:.2f} m {e:.1f} J (MPC {em:.1f} J)")
        out.append(f"**{r.label}** (`{r.method}`): " + "; ".join(parts) + ".")
    return out


def buys(section: AblationSection, w: AblationRow) -> str:
    """What the MPC's plan buys over strategy ``w``, in words: the longest clean step (against
    the grid's resolution), the largest shove survived (against the bisection's), the energy at
    the turn length (against the walks' spread), the time a tick."""
    by = {r.method: r for r in section.rows}
    mpc = by[strategy.MPC]
    parts = []
    if mpc.longest_clean is not None and w.longest_clean is not None:
        d = mpc.longest_clean - w.longest_clean
        if abs(d) < 1e-9:
            parts.append("the same longest clean step")
        else:
            grid = " (one step of the grid)" if abs(d) <= section.resolution + 1e-9 else ""
            parts.append(f"{d:+.2f} m of longest clean step{grid}")
    gaps = {
        d: push_n(mpc.pushes.get(d)) - push_n(c)  # type: ignore[operator]
        for d, c in w.pushes.items()
        if push_n(c) is not None and push_n(mpc.pushes.get(d)) is not None
    }
    if gaps:
        if all(abs(g) <= section.push_resolution + 1e-9 for g in gaps.values()):
            parts.append(
                f"the same largest shove within the bisection's {section.push_resolution:g} N"
            )
        else:
            parts.append("a largest shove " + ", ".join(f"{g:+.0f} N {d}" for d, g in gaps.items()))
    x = length_key(section.turn_length)
    e, em = w.energy.get(x), mpc.energy.get(x)
    spread = max(
        (v for v in (w.energy_std.get(x), mpc.energy_std.get(x)) if v is not None), default=None
    )
    if e is not None and em is not None:
        less = e - em
        if spread is not None and abs(less) <= spread:
            parts.append(
                f"the same energy at {section.turn_length:.2f} m within the windows' spread "
                f"({less:+.1f} J, spread {spread:.1f} J)"
            )
        else:
            parts.append(f"{less:+.1f} J less energy per two steps at {section.turn_length:.2f} m")
    if w.strategy_ms_median and mpc.strategy_ms_median:
        parts.append(f"at {mpc.strategy_ms_median / w.strategy_ms_median:.0f} x its time a tick")
    return "; ".join(parts)


def _m(v: float | None) -> str:
    return "—" if v is None else f"{v:.2f} m"


def _deg(v: float | None) -> str:
    return "—" if v is None else f"{v:.1f} deg"


def push_n(c: PushCell | None) -> float | None:
    return c.survived if c is not None else None
