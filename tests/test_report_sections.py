"""The sections added for a fair reading (lateral distance, significance, per-joint energy,
balance margin, sensitivity) render from synthetic results with intact tables. No simulation."""

from __future__ import annotations

import dataclasses

from app.experiments import paper, sections
from app.experiments.claims import evaluate
from app.experiments.definitions import QUICK
from app.experiments.report import joint_groups, render
from app.experiments.results import (
    EnergyCell,
    EnergySection,
    KappaSection,
    Meta,
    StudyResults,
    WaistSection,
    YawSection,
    ZmpSection,
    case_key,
    length_key,
)
from app.experiments.results_more import (
    BalanceCase,
    BalanceSection,
    LateralCase,
    LateralSection,
    SensitivityRow,
    SensitivitySection,
)
from app.experiments.sections_more import gain_percent, sine_share
from app.sim.world import JOINTS

METHODS = ("fixed", "redundancy", "mpc")


def _cell(mean: float, runs: list[float]) -> EnergyCell:
    per_joint = [mean / len(JOINTS)] * len(JOINTS)
    return EnergyCell(mean, 1.0, 8, 2, 2, 2, None, None, False, runs, 2.5 * mean, 2.0, per_joint)


def synthetic() -> StudyResults:
    ms = {m: sections.MaxStep(0.3, 0.3, 0.31, 0.01, [], None, [], 0.32, 0.33) for m in METHODS}
    table = {
        m: {length_key(0.3): _cell(40.0 + i, [39.0 + i, 41.0 + i])} for i, m in enumerate(METHODS)
    }
    energy = EnergySection(
        table, [0.3], 2, 6, p_values={"0.30:fixed-mpc": 0.01}, joints=list(JOINTS)
    )
    lat = {
        case_key(mode, 0.3): LateralCase(
            mode, 0.3, mode == "current", True, True, 40.0, -2.0, 0.05, True, 60.0, 200.0, 30.0
        )
        for mode in ("current", "nominal", "predicted")
    }
    lateral = LateralSection(
        0.2,
        sine_share(0.2),
        "current",
        lat,
        {"current": {"walks_limit": 0.45, "clean_limit": 0.43}},
    )
    balance = BalanceSection(
        [0.3],
        {case_key(m, 0.3): BalanceCase(m, 0.3, True, False, 0.0, 3.0, 0.4) for m in METHODS},
    )
    rows = [
        SensitivityRow("", "", "fixed", 0.33, 0.34, 0.31, 0.32, 8, 10.0),
        SensitivityRow("", "", "mpc", 0.45, 0.46, 0.43, 0.44, 8, 10.0),
        SensitivityRow("walk.dsp_split", "both_ends", "fixed", 0.35, 0.36, 0.33, 0.34, 8, 10.0),
        SensitivityRow("walk.dsp_split", "both_ends", "mpc", 0.5, None, 0.47, 0.48, 8, 10.0),
        SensitivityRow("pelvis.k_pel", 0.15, "mpc", None, 0.1, None, 0.1, 1, 1.0),
    ]
    sens = SensitivitySection(4, 0.01, (0.1, 0.6), {"walk.dsp_split": "start"}, rows, 33, 60.0)
    r = StudyResults(
        meta=Meta("cmd", "quick", "date", 1.0, 1.0, 0, 1, 1, "m", {}, None, 0.5, 3.0),
        kinematics=sections.kinematics(),
        max_step=ms,
        equivalent_lengths=sections.equivalent_lengths(QUICK, ms),
        waist=WaistSection({}),
        yaw_momentum=YawSection({}, paper.ARM_REDUCTION_PERCENT),
        energy=energy,
        kappa=KappaSection([], [], {}, {}, {}),
        zmp=ZmpSection(0.3, available=False),
        lateral=lateral,
        balance=balance,
        sensitivity=sens,
    )
    return dataclasses.replace(r, claims=evaluate(QUICK, r))


def test_new_sections_render_with_intact_tables():
    md = render(QUICK, synthetic())
    for n in range(1, 9):
        assert f"## {n}. " in md
    width = None
    for line in md.splitlines():  # every row has its header's number of cells
        if not line.startswith("|"):
            width = None
            continue
        cells = line.replace("\\|", "").count("|")
        width = width or cells
        assert cells == width, line
    assert "current (default)" in md and "9.5 %" in md  # a sine's share in a 20 % DSP
    assert "p = 0.01 *" in md  # significance over the runs
    assert "both_ends" in md and "+0.14" in md  # MPC - fixed clean gain of that cell
    assert "0.0 / 3.0, 0.40" in md  # balance margin min / 5 %, tilt
    assert "J per two-step window" in md


def test_helpers():
    assert abs(sine_share(0.2) - 0.0955) < 1e-3 and sine_share(0.0) == 0.0
    assert gain_percent(0.30, 0.40) == 100 * (0.40 / 0.30 - 1) and gain_percent(None, 0.4) is None
    groups = joint_groups([1.0] * len(JOINTS), list(JOINTS))
    assert sum(groups.values()) == len(JOINTS)  # every joint in exactly one group
    assert groups["knee"] == 2 and groups["arms"] == 6 and groups["waist"] == 1


def _summary(**changes):
    from app.experiments.results import RunSummary

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
    """A run not clean only because a knee went straight (kappa of the 12 leg columns over
    1000, J_low's own kappa 82, as the fixed pelvis at 0.38 m) says so, not 'not clean'; a
    large J_low kappa alone is no reason (the criterion does not read it)."""
    from app.experiments.sections import failure_reasons

    knee = _summary(clean=False, condition_number_legs_max=5629.0)
    assert knee.condition_number_legs_max == 5629.0
    (reason,) = failure_reasons(knee)
    assert "knee nearly straight" in reason and "5.63e+03" in reason
    assert failure_reasons(_summary(condition_number_max=5e3, condition_number_legs_max=40.0)) == []
    # a cause the list does not know still reads "not clean", never an empty list
    assert failure_reasons(_summary(clean=False, condition_number_legs_max=40.0)) == ["not clean"]
