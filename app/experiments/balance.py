"""Section 7: the ZMP in the footholds (paper Fig. 15) and the balance margin.

- *LIPM ZMP*: the ZMP of the linear inverted pendulum from the measured CoM (its acceleration
  by finite differences at 200 Hz), as the paper's Fig. 15 computes it from the robot's
  measured CoM; the claim is judged on the share of walking ticks it lies in the *planned
  support* (the soles the plan has on the ground, their convex hull in the DSP);
- *CoP*: the centre of pressure of the foot contact forces (the measured ZMP). It always lies
  in the hull of the contact points, so "inside" cannot fail in a simulation; what can is its
  *margin*, the distance to the edge of the support polygon of the soles in contact (a finding
  beside the claim). MuJoCo's box-on-plane contact touches at the sole's corners: when a foot
  rolls even a fraction of a degree only one edge's two corners touch, and the CoP lies on
  that edge (margin 0). :class:`BalanceCase` counts those ticks by edge.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from app.experiments.definitions import Study
from app.experiments.outcomes import Results, case_key, summary_of, zmp_of
from controller.strategy import MPC

BALANCE_LENGTHS = (0.15, 0.20, 0.25, 0.30, 0.35, 0.40)  # [m] Table 1's lengths
EDGES = ("outer", "inner", "toe", "heel", "two feet")  # where a CoP on an edge sits
EDGE_MARGIN = 5e-4  # [m] a CoP closer than this to the support polygon's edge is on the edge


@dataclass(frozen=True)
class ZmpSection:
    """The MPC's ZMP run (the shares are None when the run is missing)."""

    step_length: float
    available: bool
    clean: bool | None = None
    cop_in_support_ratio_run: float | None = None
    cop_in_measured_support_walking: float | None = None
    cop_in_planned_support_walking: float | None = None
    lipm_in_planned_support_walking: float | None = None
    lipm_outside_max_mm: float | None = None  # farthest the LIPM ZMP left the planned support


@dataclass(frozen=True)
class BalanceCase:
    method: str
    step_length: float  # [m]
    clean: bool
    fell: bool
    margin_min_mm: float | None  # CoP to the support polygon's edge, walking ticks
    margin_p5_mm: float | None  # its 5th percentile
    tilt_max_deg: float | None  # largest tilt of a foot in contact
    edge_share: float | None = None  # walking ticks with the CoP on an edge (margin < 0.5 mm)
    edges: dict[str, int] = field(default_factory=dict)  # those ticks by edge (EDGES)
    walking_ticks: int = 0


@dataclass(frozen=True)
class BalanceSection:
    lengths: list[float]
    cases: dict[str, BalanceCase | None]  # "<method>@<length>"


def zmp(study: Study, results: Results) -> ZmpSection:
    spec = study.figure_run(MPC, study.zmp_length)
    s, ex = summary_of(results, spec), zmp_of(results, spec)
    if not s or not ex:
        return ZmpSection(study.zmp_length, available=False)
    return ZmpSection(
        step_length=study.zmp_length,
        available=True,
        clean=s.clean,
        cop_in_support_ratio_run=s.zmp_in_support_ratio,
        cop_in_measured_support_walking=ex.cop_in_measured_support,
        cop_in_planned_support_walking=ex.cop_in_planned_support,
        lipm_in_planned_support_walking=ex.lipm_in_planned_support,
        lipm_outside_max_mm=ex.lipm_outside_max_mm,
    )


def balance(study: Study, results: Results) -> BalanceSection:
    """Margin, tilt and the CoP's edge ticks of the unseeded figure runs at Table 1's lengths
    (where they ran)."""
    lengths = [
        x
        for x in BALANCE_LENGTHS
        if any(s.step_length == x and study.is_figure_run(s) for s in results)
    ]
    cases: dict[str, BalanceCase | None] = {}
    for x in lengths:
        for m in study.methods:
            s = summary_of(results, study.figure_run(m, x))
            if s is None:
                cases[case_key(m, x)] = None
                continue
            o = s.other

            def mm(key: str, o: dict = o) -> float | None:
                return None if o.get(key) is None else 1000.0 * o[key]

            walking = s.cop_edge_ticks.get("walking", 0)
            edges = {k: v for k, v in s.cop_edge_ticks.items() if k in EDGES}
            cases[case_key(m, x)] = BalanceCase(
                method=m,
                step_length=x,
                clean=s.clean,
                fell=s.fell,
                margin_min_mm=mm("balance_margin_min"),
                margin_p5_mm=mm("balance_margin_p5"),
                tilt_max_deg=o.get("sole_tilt_max_deg"),
                edge_share=sum(edges.values()) / walking if walking else None,
                edges=edges,
                walking_ticks=walking,
            )
    return BalanceSection(lengths, cases)
