"""The report's sections beyond the claims (lateral distance, significance, per-joint energy,
balance margin, robustness, the sensitivity grid, the summary, the glossary) render from
synthetic results with intact tables. No simulation."""

from __future__ import annotations

import dataclasses
import re

from app.experiments import limits, paper
from app.experiments.balance import BalanceCase, BalanceSection, ZmpSection
from app.experiments.claims import evaluate
from app.experiments.definitions import AUTHORS, QUICK, Falls, Pushes
from app.experiments.energy import EnergyCell, EnergySection, joint_groups
from app.experiments.kappa import KappaSection
from app.experiments.outcomes import RunSummary, case_key, failure_reasons, length_key
from app.experiments.report import render
from app.experiments.results import Meta, StudyResults
from app.experiments.robustness import (
    FallsCell,
    PushCell,
    RepeatsCell,
    RobustnessSection,
    push_key,
    trade,
    trade_cells,
    trade_jobs,
)
from app.experiments.sensitivity import SensitivityRow, SensitivitySection, effective, reads
from app.experiments.waist import LateralCase, LateralSection, WaistSection, sine_share
from app.experiments.yaw import YawSection
from pelvic_walk.core.world import JOINTS

METHODS = ("fixed", "redundancy", "mpc")
K, D = "pelvis.k_pel", "walk.dsp_ratio"


def _cell(mean: float, runs: list[float]) -> EnergyCell:
    per_joint = [mean / len(JOINTS)] * len(JOINTS)
    windows = [[r - 1.0, r + 1.0] for r in runs]
    return EnergyCell(
        mean, 1.0, 8, 2, 2, 2, None, None, False, runs, 2.5 * mean, 2.0, per_joint, windows, windows
    )


def _row(method: str, ov: list, clean: float | None, walks: float | None = None) -> SensitivityRow:
    limits_ = {"walks": walks or clean, "clean": clean, "clean@1cm": clean, "clean@kappa300": clean}
    fails = {k: None if v is None else round(v + 0.01, 2) for k, v in limits_.items()}
    return SensitivityRow(
        method, ov, limits_, fails, 8, 10.0, None, 25.0 if method == "mpc" else 0.0
    )


def sensitivity() -> SensitivitySection:
    """A 2 x 2 grid (k_pel 0.25, 0.45 x DSP 0.2, 0.3) and the authors' cell. The MPC-only row
    at k_pel 0.45 gains +0.12 m over the fixed pelvis's row at the same DSP share."""
    rows = [
        _row("fixed", [], 0.31, 0.33),
        _row("fixed", [[D, 0.3]], 0.30),
        _row("mpc", [], 0.40),
        _row("mpc", [[D, 0.3]], 0.38),
        _row("mpc", [[K, 0.45]], 0.43),
        _row("mpc", [[K, 0.45], [D, 0.3]], 0.39),
        _row("fixed", [list(a) for a in AUTHORS], 0.28),
        _row("mpc", [list(a) for a in AUTHORS], 0.36),
    ]
    return SensitivitySection(
        n_steps=4,
        resolution=0.01,
        search=(0.2, 0.6),
        first=0.4,
        defaults={K: 0.25, D: 0.2},
        rows_axis=(K, [0.25, 0.45]),
        columns_axis=(D, [0.2, 0.3]),
        cells=[("the authors' DSP and step width", [list(a) for a in AUTHORS])],
        criteria=["walks", "clean", "clean@1cm", "clean@kappa300"],
        methods=["fixed", "mpc"],
        rows=rows,
        n_runs=64,
        duration_s=120.0,
    )


def synthetic() -> StudyResults:
    ms = {m: limits.MaxStep(0.3, 0.3, 0.31, 0.01, [], None, [], 0.32, 0.33) for m in METHODS}
    table = {
        m: {length_key(0.3): _cell(40.0 + i, [39.0 + i, 41.0 + i])} for i, m in enumerate(METHODS)
    }
    energy = EnergySection(
        table, [0.3], 2, 6, p_values={"0.30:fixed-mpc": 0.01}, joints=list(JOINTS)
    )
    lat = {
        case_key(mode, 0.3): LateralCase(
            mode,
            0.3,
            mode == "current",
            True,
            True,
            40.0,
            -2.0,
            0.05,
            True,
            0.2,
            0.05,
            15.0,
            60.0,
            200.0,
            30.0,
        )
        for mode in ("current", "nominal", "predicted")
    }
    ablation = {
        case_key("current", 0.3): dataclasses.replace(
            lat[case_key("current", 0.3)],
            early_turn_share=-0.05,
            anticipates=False,
            reference="now",
        )
    }
    lateral = LateralSection(
        0.2,
        sine_share(0.2),
        "current",
        lat,
        {"nominal": {"walks_limit": 0.45, "clean_limit": 0.43}},
        ablation,
    )
    balance = BalanceSection(
        [0.3],
        {
            case_key(m, 0.3): BalanceCase(
                m, 0.3, True, False, 0.0, 3.0, 0.4, 0.07, {"outer": 12}, 171
            )
            for m in METHODS
        },
    )
    rob = RobustnessSection(
        repeats=2,
        steps=6,
        lengths=[0.3],
        cells={
            case_key(m, 0.3): RepeatsCell(m, 0.3, 2, int(m == "mpc"), 1, 14, 2, 4.5, [1], [0])
            for m in METHODS
        },
        pushes={
            push_key(m, 0.3, d): PushCell(
                m, 0.3, d, 0.1, 90.0 - 10 * (m == "mpc"), 92.0 - 10 * (m == "mpc"), "tilt", 7
            )
            for m in METHODS
            for d in ("left", "right")
        },
        push_setup=Pushes(lengths=(0.3,)),
        falls={
            "15 N": {
                m: FallsCell(m, 15.0, [0.3], 40, n, list(range(n)))
                for m, n in zip(METHODS, (19, 22, 28), strict=True)
            }
        },
        falls_setup=Falls(),
    )
    study = dataclasses.replace(QUICK, pushes=Pushes(lengths=(0.3,)))
    sens = sensitivity()
    cell_pushes = {
        (m, reads(m, ov), d): PushCell(m, 0.3, d, 0.1, 70.0, 72.0, "tilt", 7)
        for _, ov in trade_cells(study, sens)
        for m in ("fixed", "mpc")
        for d in ("left", "right")
    }
    rob = dataclasses.replace(rob, trade=trade(study, sens, rob.pushes, cell_pushes))
    r = StudyResults(
        meta=Meta("cmd", "quick", "date", 1.0, 1.0, 0, 1, 1, "m", {}, "pool", 0.5, 3.0),
        kinematics=limits.kinematics(),
        max_step=ms,
        equivalent_lengths=limits.equivalent_lengths(QUICK, ms),
        waist=WaistSection({}),
        yaw_momentum=YawSection({}, paper.ARM_REDUCTION_PERCENT),
        energy=energy,
        kappa=KappaSection([], [], {}, {}, {}),
        zmp=ZmpSection(0.3, available=False),
        lateral=lateral,
        balance=balance,
        robustness=rob,
        sensitivity=sens,
    )
    return dataclasses.replace(r, claims=evaluate(QUICK, r))


def _tables_intact(md: str) -> None:
    width = None
    for line in md.splitlines():  # every row has its header's number of cells
        if not line.startswith("|"):
            width = None
            continue
        cells = line.replace("\\|", "").count("|")
        width = width or cells
        assert cells == width, line


def test_sections_render_with_intact_tables():
    md = render(QUICK, synthetic())
    for n in range(1, 10):
        assert f"## {n}. " in md
    _tables_intact(md)
    assert "current (default)" in md and "9.5 %" in md  # a sine's share in a 20 % DSP
    assert "p = 0.01 *" in md  # significance over the runs
    assert "0.0 / 3.0, 0.40; 12 of 171 (outer)" in md  # balance margin, tilt, edge share
    assert "J per two-step window" in md
    assert "1 / 1 / 2; 4.5" in md  # robustness: fell / off / runs; worst landing
    eight = md.split("## 8. ")[1].split("## 9. ")[0]
    assert "| N(0, 15 N) | 0.30 m | 19 / 40 | 22 / 40 | 28 / 40 |" in eight
    assert "| 0.30 | right | — | 90 / 92 | 90 / 92 | 80 / 82 |" in eight  # both directions
    assert "| push left at 0.30 m | 80-82 N | 90-92 N | less |" in eight
    # the stability claim: the MPC survives less in both directions, falls as often (n.s.)
    # two conditions against the MPC cannot pass a sign test, the falls are n.s.: the
    # evidence cannot tell
    assert "- **inconclusive**: the MPC's pelvic rotation is more stable" in eight
    assert (
        "pushes: cannot tell (largest push survived in 2 conditions: the MPC more in 0, " in eight
    )
    # what the default gain costs, stated beside it
    assert "k_pel = 0.25, the MPC's waist peaks at 25.0 deg over a walk of 0.40 m steps" in eight
    assert "80 against 90 N to the left (-10 N)" in eight


def test_the_sensitivity_summary_reads_every_row():
    """The MPC-only row (k_pel 0.45) is compared with the fixed pelvis's row at the same DSP
    share: +0.12 m, the largest gain, found though no fixed row has k_pel = 0.45."""
    s = sensitivity()
    assert s.gain([[K, 0.45], [D, 0.2]]) == 0.12
    assert s.gain([[K, 0.25], [D, 0.2]]) == 0.09  # the default k_pel: the baseline rows
    assert s.best_gain() == (0.12, "pelvis.k_pel = 0.45, walk.dsp_ratio = 0.2")
    assert s.cells_with_gain(0.10) == ["pelvis.k_pel = 0.45, walk.dsp_ratio = 0.2"]
    assert s.gain([list(a) for a in AUTHORS]) == 0.08
    assert effective("fixed", ((K, 0.45), (D, 0.3))) == ((D, 0.3),)
    assert effective("mpc", ((K, 0.45), (D, 0.3))) == ((K, 0.45), (D, 0.3))
    md = render(QUICK, synthetic())
    nine = md.split("## 9. ")[1]
    assert "+0.12 * " in nine or "+0.12 *" in nine
    assert "the largest MPC - fixed gain in the clean limit is +0.12 m" in nine
    assert "the authors' DSP and step width | 0.28 / 0.28 | 0.36 / 0.36 | +0.08" in nine
    assert "landing < 1 cm, kappa(legs) < 1000" in nine
    # every gain beside its cost: the largest gain's cell, with its own pushes
    assert "(pelvis.k_pel = 0.45, walk.dsp_ratio = 0.2, where k_pel = 0.45" in nine
    assert "| pelvis.k_pel = 0.45, walk.dsp_ratio = 0.2 | 0.45 | +0.12 | 25.0 |" in nine
    assert "| the defaults | 0.25 | +0.09 | 25.0 | 90 / 92 | 80 / 82 |" in nine


def test_summary_and_glossary_at_the_top():
    md = render(QUICK, synthetic())
    top = md.split("## Claims of the paper")[0]
    summary = top.split("## Summary")[1].split("## Words used")[0]
    lines = [x for x in summary.splitlines() if x.startswith("- ")]
    assert 3 <= len(lines) <= 10
    assert "+0.12 m (pelvis.k_pel = 0.45" in summary
    assert "runs that fell: fixed 0/2, redundancy 0/2, mpc 1/2" in summary
    # the plain paragraphs first (the answer, then the tally), then the gain with its cost,
    # then the stability verdict
    paragraphs = summary.strip().split("\n\n")
    answer = paragraphs[1]
    assert not answer.startswith("- ") and answer.startswith("**The answer.**")
    assert "longest step" in answer
    assert "the MPC falls in 28 of 40 walks against 19 of 40" in answer
    assert "Of the paper's" in paragraphs[2] and "inconclusive" in paragraphs[2]
    assert "The cost of that gain: k_pel = 0.25" in summary
    assert (
        "**Stability (Sec. VII, section 8): the MPC more stable than redundancy: inconclusive"
        in summary
    )
    glossary = top.split("## Words used in this report")[1]
    for word in ("**clean**", "**walks**", "**DSP / SSP**", "**J_low**", "kappa(legs)", "tie"):
        assert word in glossary
    assert "pelvic-walk simulate --method M --step-length L --steps 6 --seed S" in top


def test_no_reference_outside_the_repository():
    """The report names no design input a clone lacks, and no issue number."""
    md = render(QUICK, synthetic())
    for bad in ("SPEC", "INTERFACES" + ".md", "STYLE" + ".md", "../"):
        assert bad not in md, bad
    assert not re.search(r"shared[/]", md)  # the design inputs' folder
    assert not re.search(r"\bissue\s*#?\d", md, re.IGNORECASE)
    assert "kappa(J)" not in md  # one name per kappa: kappa(J_low) or kappa(legs)


def test_helpers():
    assert abs(sine_share(0.2) - 0.0955) < 1e-3 and sine_share(0.0) == 0.0
    groups = joint_groups([1.0] * len(JOINTS), list(JOINTS))
    assert sum(groups.values()) == len(JOINTS)  # every joint in exactly one group
    assert groups["knee"] == 2 and groups["arms"] == 6 and groups["waist"] == 1


def _summary(**changes):
    base = dict(
        method="fixed",
        arms=True,
        step_length=0.38,
        steps_planned=10,
        steps_completed=10,
        success=True,
        fell=False,
        fall_time=None,
        fall_reason=None,
        clean=True,
        landing_error_max=0.008,
        condition_number_max=82.0,
        speed_limited_ticks=0,
        servo_saturation_substeps=0,
        solver_failures=0,
        solver_failures_by_layer={},
        waist_yaw_max_deg=0.0,
        yaw_momentum_peak=0.2,
        zmp_in_support_ratio=1.0,
        energy_two_step_windows=[],
        sim_time=15.0,
        kappa_liftoff=[],
        kappa_landing=[],
    )
    return RunSummary.from_run({**base, **changes})


def test_failure_reasons_name_the_clean_criterions_kappa_the_leg_columns():
    """A run not clean only because a knee went straight (kappa(legs) over 1000, kappa(J_low)
    82, as the fixed pelvis at 0.38 m) says so, not 'not clean'; a large kappa(J_low) alone is
    no reason (the criterion does not read it)."""
    knee = _summary(clean=False, condition_number_legs_max=5629.0)
    assert knee.condition_number_legs_max == 5629.0
    (reason,) = failure_reasons(knee)
    assert "knee nearly straight" in reason and "kappa(legs) up to 5.63e+03" in reason
    assert failure_reasons(_summary(condition_number_max=5e3, condition_number_legs_max=40.0)) == []
    # a cause the list does not know still reads "not clean", never an empty list
    assert failure_reasons(_summary(clean=False, condition_number_legs_max=40.0)) == ["not clean"]


def test_the_kappa_legs_cells_read_the_run_summary_field():
    """kappa(legs) is a field of RunSummary, not one of its other keys: the report's cells
    read it (they printed "-" when it was looked up among the other keys)."""
    from app.experiments.definitions import Study
    from app.experiments.kappa import kappa_case
    from app.experiments.outcomes import RunResult

    study = Study("t", 4, 1, (0.3,), 0.05, (0.3,), 1, 4)
    s = _summary(condition_number_legs_max=76.0, kappa_legs_landing=[70.0, 72.0])
    spec = study.figure_run("fixed", 0.3)
    case = kappa_case(study, {spec: RunResult(spec, s)}, "fixed", 0.3)
    assert case is not None and case.kappa_legs_run_max == 76.0


def test_the_trade_pushes_run_once_each():
    """The push bisections of the trade: one per distinct run. The fixed pelvis reads no
    pelvis parameter, so the k_pel cell at the default DSP share is the section's own push;
    the defaults' cell is never run again when the section measures that length."""
    study = dataclasses.replace(QUICK, pushes=Pushes(lengths=(0.3,)))
    cells = trade_cells(study, sensitivity())
    assert [n for n, _ in cells] == [
        "pelvis.k_pel = 0.45, walk.dsp_ratio = 0.2",
        "the authors' DSP and step width",
    ]
    jobs = trade_jobs(study, cells)
    methods = sorted((m, ov) for m, ov, _ in jobs)
    assert ("fixed", ()) not in methods and ("mpc", ()) not in methods
    assert set(methods) == {
        ("fixed", tuple(sorted(AUTHORS))),
        ("mpc", tuple(sorted(AUTHORS))),
        ("mpc", (("pelvis.k_pel", 0.45),)),
    }
    assert len(jobs) == 3 * 2  # both directions
    away = dataclasses.replace(study, pushes=Pushes(lengths=(0.2,)))  # not the trade's length
    assert ("fixed", (), "left") in trade_jobs(away, cells)
