"""Each claim's verdict rule on small synthetic results: it holds, it fails, and (where the rule
has one) it is partly met. No simulation: the section dataclasses are built by hand."""

from __future__ import annotations

import dataclasses
import math

import pytest

from app.experiments import paper, sections
from app.experiments.claims import CLAIMS, evaluate
from app.experiments.definitions import QUICK
from app.experiments.report import escape_cell, header, render, row
from app.experiments.results import (
    EnergyCell,
    EnergySection,
    KappaCase,
    KappaSection,
    KinematicsSection,
    MaxStep,
    Meta,
    StudyResults,
    WaistCase,
    WaistSection,
    YawCase,
    YawRun,
    YawSection,
    ZmpSection,
    case_key,
    length_key,
)
from app.experiments.results_more import BalanceCase, BalanceSection
from app.experiments.verdicts import (
    FAILS,
    HOLDS,
    NOT_MEASURED,
    PARTLY,
    Bound,
    Rule,
    above,
    is_,
    verdict,
)

METHODS = ("fixed", "redundancy", "mpc")
BY_ID = {c.id: c for c in CLAIMS}


# -- synthetic results ------------------------------------------------------------------------
def _max_step(longest: float | None, first_failed: float | None = None) -> MaxStep:
    return MaxStep(0.3, longest, first_failed, None, [], None, [])


def empty() -> StudyResults:
    """Results with no run: every claim is "not measured" (or does not apply)."""
    ms = {m: _max_step(None) for m in METHODS}
    return StudyResults(
        meta=Meta("cmd", "quick", "date", 1.0, 1.0, 0, 1, 1, "m", {}),
        kinematics=sections.kinematics(),  # eq. (1)-(5): needs no run
        max_step=ms,
        equivalent_lengths=sections.equivalent_lengths(QUICK, ms),
        waist=WaistSection({}),
        yaw_momentum=YawSection({}, paper.ARM_REDUCTION_PERCENT),
        energy=EnergySection({m: {} for m in METHODS}, [], 2, 6),
        kappa=KappaSection([], [], {}, {}, {}),
        zmp=ZmpSection(0.3, available=False),
    )


def kinematics(fixed: float, rotation: float) -> StudyResults:
    d = {"step_max_fixed_static": fixed, "step_max_rotation_static": rotation}
    d["increase_percent"] = 100 * (rotation / fixed - 1)
    return dataclasses.replace(empty(), kinematics=KinematicsSection(paper.KINEMATICS, d, d, d, d))


def max_step(fixed: float, mpc: float) -> StudyResults:
    ms = {"fixed": _max_step(fixed), "redundancy": _max_step(None), "mpc": _max_step(mpc)}
    return dataclasses.replace(empty(), max_step=ms)


def _waist(
    m: str,
    peak: float = 22.0,
    lead: float = 0.1,
    rate: float = 5.0,
    acc: float = 100.0,
    toward: float = 0.0,
):
    """A step turning from +peak to -peak; ``toward``: the DSP's share of the range moved
    toward the swing (< 0: away)."""
    return WaistCase(
        method=m,
        step_length=0.4,
        complete=True,
        angle_start_deg=peak,
        angle_dsp_end_deg=peak,
        angle_end_deg=-peak,
        angle_min_deg=-peak,
        angle_max_deg=peak,
        peak_abs_angle_deg=peak,
        dsp_change_deg=-toward * 2 * peak,
        range_deg=2 * peak,
        dsp_share_of_range=abs(toward),
        peak_abs_rate_deg_s=50.0,
        peak_abs_rate_change_deg_s2=acc,
        rate_at_liftoff_toward_swing_deg_s=rate,
        reversal_before_liftoff_s=lead,
        dsp_time=0.24,
        step_time=1.2,
        step_index=4,
    )


def waist(mpc: WaistCase, red: WaistCase) -> StudyResults:
    cases = {case_key("mpc", 0.4): mpc, case_key("redundancy", 0.4): red}
    return dataclasses.replace(empty(), waist=WaistSection(cases))


def _run(peak: float | None, fell: bool = False) -> YawRun:
    return YawRun(peak, None, not fell, fell, [])


def yaw(*cases: tuple[str, float, float, float, bool]) -> StudyResults:
    """Cases (method, length, peak arms on, peak arms off, fell)."""
    out = {}
    for m, x, on, off, fell in cases:
        out[case_key(m, x)] = YawCase(m, x, _run(on, fell), _run(off), 100 * (1 - on / off), None)
    return dataclasses.replace(empty(), yaw_momentum=YawSection(out, 60.0))


def _cell(mean: float, std: float = 1.0, n: int = 1000) -> EnergyCell:
    return EnergyCell(mean, std, n, 2, 2, 2, None, None, False)


def energy(cells: dict[tuple[str, float], tuple[float, float]]) -> StudyResults:
    """Cells (method, length) -> (mean, std) [J]."""
    table: dict[str, dict[str, EnergyCell]] = {m: {} for m in METHODS}
    for (m, x), (mean, std) in cells.items():
        table[m][length_key(x)] = _cell(mean, std)
    lengths = sorted({x for _, x in cells})
    return dataclasses.replace(empty(), energy=EnergySection(table, lengths, 2, 6))


def _kappa(m: str, x: float, run_max: float, clean: bool = True) -> KappaCase:
    return KappaCase(m, x, clean, False, [], run_max, run_max, run_max, run_max, run_max, run_max)


def kappa_ratio(x: float, ratio: float, fixed_limit: float = 0.35) -> StudyResults:
    section = KappaSection([x], [], {}, {}, {length_key(x): {"mpc": ratio, "redundancy": ratio}})
    ms = {m: _max_step(fixed_limit if m == "fixed" else 0.4, 0.4) for m in METHODS}
    return dataclasses.replace(empty(), kappa=section, max_step=ms)


def kappa_035(fixed_max: float, mpc_max: float, fixed_clean: bool) -> StudyResults:
    x = paper.KAPPA_DIVERGES_LENGTH
    cases = {
        case_key("fixed", x): _kappa("fixed", x, fixed_max, fixed_clean),
        case_key("mpc", x): _kappa("mpc", x, mpc_max),
    }
    return dataclasses.replace(empty(), kappa=KappaSection([x], [], cases, {}, {}))


def kappa_own_limit(at_limit: float, past: float, mpc_past: float) -> StudyResults:
    lc, ff = 0.35, 0.40
    near = {
        case_key("fixed", lc): _kappa("fixed", lc, at_limit),
        case_key("fixed", ff): _kappa("fixed", ff, past, clean=False),
        case_key("mpc", ff): _kappa("mpc", ff, mpc_past),
    }
    ms = {m: _max_step(lc, ff) for m in METHODS}
    return dataclasses.replace(empty(), kappa=KappaSection([], [lc, ff], {}, near, {}), max_step=ms)


def zmp(p5_mm: float, tilt_deg: float) -> StudyResults:
    case = BalanceCase("mpc", 0.3, True, False, p5_mm / 2, p5_mm, tilt_deg)
    return dataclasses.replace(
        empty(),
        zmp=ZmpSection(0.3, True, True, 1.0, 1.0, 1.0, 0.95),
        balance=BalanceSection([0.3], {case_key("mpc", 0.3): case}),
    )


def kappa_events(lift: tuple[float, float], land: tuple[float, float]) -> StudyResults:
    """(MPC, redundancy) median kappa at lift-off and at landing, at 0.4 m."""
    cases = {}
    for i, m in enumerate(("mpc", "redundancy")):
        k = _kappa(m, 0.4, 100.0)
        cases[case_key(m, 0.4)] = dataclasses.replace(
            k, kappa_liftoff_median=lift[i], kappa_landing_median=land[i]
        )
    return dataclasses.replace(empty(), kappa=KappaSection([0.4], [], cases, {}, {}))


def yaw_030(on: tuple[float, float, float], off: tuple[float, float, float]) -> StudyResults:
    return yaw(*((m, 0.3, a, b, False) for m, a, b in zip(METHODS, on, off, strict=True)))


def least(means: dict[float, tuple[float, float, float]]) -> StudyResults:
    """Length -> (fixed, redundancy, MPC) means."""
    return energy(
        {(m, x): (v, 1) for x, row in means.items() for m, v in zip(METHODS, row, strict=True)}
    )


L1, L2 = paper.ENERGY_MPC_BELOW_REDUNDANCY  # 0.35, 0.40
# claim id -> verdict -> synthetic results that must give it
CASES: dict[str, dict[str, StudyResults]] = {
    "kinematics": {HOLDS: kinematics(0.312, 0.418), FAILS: kinematics(0.31, 0.45)},
    "max_step": {
        HOLDS: max_step(0.30, 0.40),
        PARTLY: max_step(0.30, 0.33),
        FAILS: max_step(0.30, 0.30),
    },
    "waist_amplitude": {
        HOLDS: waist(_waist("mpc", peak=24.0), _waist("redundancy")),
        FAILS: waist(_waist("mpc", peak=12.0), _waist("redundancy")),
    },
    "waist_turns_in_dsp": {  # a sine moves 9.5 % of its range in a 20 % DSP
        HOLDS: waist(_waist("mpc", toward=0.09), _waist("redundancy", toward=0.0)),
        PARTLY: waist(_waist("mpc", toward=0.05), _waist("redundancy", toward=0.0)),
        FAILS: waist(_waist("mpc", toward=0.001), _waist("redundancy", toward=0.0)),
    },
    "waist_rate_sharp": {
        HOLDS: waist(_waist("mpc", acc=100.0), _waist("redundancy", acc=300.0)),
        PARTLY: waist(_waist("mpc", acc=100.0), _waist("redundancy", acc=120.0)),
        FAILS: waist(_waist("mpc", acc=100.0), _waist("redundancy", acc=80.0)),
    },
    "arm_swing": {
        HOLDS: yaw(("mpc", 0.3, 0.4, 1.0, False), ("mpc", 0.4, 0.1, 1.0, True)),
        PARTLY: yaw(("mpc", 0.3, 0.8, 1.0, False), ("mpc", 0.4, 0.1, 1.0, True)),
        FAILS: yaw(("mpc", 0.3, 0.95, 1.0, False), ("fixed", 0.3, 1.2, 1.0, False)),
    },
    "yaw_redundancy_higher": {
        HOLDS: yaw(("redundancy", 0.4, 0.5, 1.3, False), ("mpc", 0.4, 0.5, 1.0, False)),
        FAILS: yaw(("redundancy", 0.4, 0.5, 1.0, False), ("mpc", 0.4, 0.5, 1.3, False)),
    },
    "energy_std": {
        HOLDS: energy({("mpc", 0.15): (10, 1), ("redundancy", 0.15): (10, 2)}),
        PARTLY: energy(
            {
                ("mpc", 0.15): (10, 1),
                ("redundancy", 0.15): (10, 2),
                ("mpc", 0.3): (10, 3),
                ("redundancy", 0.3): (10, 2),
            }
        ),
        FAILS: energy(
            {
                ("mpc", 0.15): (10, 3),
                ("redundancy", 0.15): (10, 2),
                ("mpc", 0.3): (10, 3),
                ("redundancy", 0.3): (10, 2),
                ("mpc", 0.4): (10, 1),
                ("redundancy", 0.4): (10, 2),
            }
        ),
    },
    "energy_std_gap_grows": {
        HOLDS: energy(
            {
                **{("mpc", x): (10, 1) for x in (0.15, 0.3, 0.4)},
                **{("redundancy", x): (10, s) for x, s in ((0.15, 2), (0.3, 3), (0.4, 9))},
            }
        ),
        PARTLY: energy(
            {
                **{("mpc", x): (10, 1) for x in (0.15, 0.3, 0.4)},
                **{("redundancy", x): (10, s) for x, s in ((0.15, 2), (0.3, 9), (0.4, 3))},
            }
        ),
        FAILS: energy(
            {
                **{("mpc", x): (10, 1) for x in (0.15, 0.3, 0.4)},
                **{("redundancy", x): (10, s) for x, s in ((0.15, 9), (0.3, 3), (0.4, 2))},
            }
        ),
    },
    "energy_mean_long": {
        HOLDS: energy(
            {
                ("mpc", L1): (300, 9),
                ("redundancy", L1): (400, 9),
                ("mpc", L2): (400, 9),
                ("redundancy", L2): (900, 9),
            }
        ),
        PARTLY: energy(
            {
                ("mpc", L1): (300, 9),
                ("redundancy", L1): (400, 9),
                ("mpc", L2): (950, 9),
                ("redundancy", L2): (900, 9),
            }
        ),
        FAILS: energy(
            {
                ("mpc", L1): (500, 9),
                ("redundancy", L1): (400, 9),
                ("mpc", L2): (950, 9),
                ("redundancy", L2): (900, 9),
            }
        ),
    },
    "energy_short": {
        HOLDS: energy(
            {("fixed", 0.15): (15, 1), ("redundancy", 0.15): (13, 1), ("mpc", 0.15): (10, 1)}
        ),
        PARTLY: energy(
            {("fixed", 0.15): (15, 1), ("redundancy", 0.15): (16, 1), ("mpc", 0.15): (10, 1)}
        ),
        FAILS: energy(
            {("fixed", 0.15): (15, 1), ("redundancy", 0.15): (16, 1), ("mpc", 0.15): (17, 1)}
        ),
    },
    "energy_mid": {
        HOLDS: energy(
            {("fixed", 0.3): (50, 1), ("redundancy", 0.3): (60, 1), ("mpc", 0.3): (150, 1)}
        ),
        PARTLY: energy(
            {("fixed", 0.3): (50, 1), ("redundancy", 0.3): (40, 1), ("mpc", 0.3): (150, 1)}
        ),
        FAILS: energy(
            {("fixed", 0.3): (50, 1), ("redundancy", 0.3): (40, 1), ("mpc", 0.3): (45, 1)}
        ),
    },
    "kappa_030": {
        HOLDS: kappa_ratio(0.30, 2.1),
        PARTLY: kappa_ratio(0.30, 1.3),
        FAILS: kappa_ratio(0.30, 0.9),
    },
    "kappa_035": {
        HOLDS: kappa_035(5e8, 40.0, fixed_clean=False),
        FAILS: kappa_035(60.0, 40.0, fixed_clean=True),
    },
    "kappa_030_equivalent": {
        HOLDS: kappa_ratio(0.35, 1.8),
        PARTLY: kappa_ratio(0.35, 1.2),
        FAILS: kappa_ratio(0.35, 1.0),
    },
    "kappa_own_limit": {
        HOLDS: kappa_own_limit(50.0, 5e8, 45.0),
        PARTLY: kappa_own_limit(50.0, 80.0, 45.0),
        FAILS: kappa_own_limit(50.0, 80.0, 120.0),
    },
    "zmp": {HOLDS: zmp(12.0, 0.5), PARTLY: zmp(12.0, 1.5), FAILS: zmp(1.0, 0.5)},
    "energy_least": {
        HOLDS: least({0.15: (15, 13, 10), 0.3: (50, 60, 150), 0.4: (900, 800, 400)}),
        PARTLY: least(
            {0.15: (15, 13, 10), 0.2: (19, 18, 17), 0.3: (50, 60, 150), 0.35: (50, 60, 150)}
        ),
        FAILS: least({0.15: (15, 13, 17), 0.3: (50, 60, 150), 0.4: (900, 800, 400)}),
    },
    "yaw_030_similar": {
        HOLDS: yaw_030((1.0, 1.05, 1.1), (2.0, 2.1, 2.2)),
        PARTLY: yaw_030((1.0, 1.05, 1.1), (2.0, 2.1, 2.9)),
        FAILS: yaw_030((0.5, 1.05, 1.1), (2.0, 2.1, 2.2)),
    },
    "kappa_040_events": {
        HOLDS: kappa_events(lift=(80.0, 60.0), land=(50.0, 70.0)),
        PARTLY: kappa_events(lift=(80.0, 60.0), land=(70.0, 50.0)),
        FAILS: kappa_events(lift=(60.0, 80.0), land=(70.0, 50.0)),
    },
}


# -- the rules --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("claim_id", "expected"), [(cid, v) for cid, cases in CASES.items() for v in cases]
)
def test_rule_on_synthetic_results(claim_id, expected):
    claim = BY_ID[claim_id]
    result = claim.judge(QUICK, CASES[claim_id][expected])
    assert result.verdict == expected, (result.ours, result.measured, result.rule)
    assert result.ours != "-" and result.rule.startswith("holds if ")


@pytest.mark.parametrize("claim", CLAIMS, ids=lambda c: c.id)
def test_every_rule_can_fail_and_is_tested(claim):
    """Each claim has a synthetic case that holds, one that does not, and one partly iff its
    rule has a partly level; with no runs at all it is "not measured" (eq. 1-5 need none)."""
    expected = {HOLDS, FAILS} | ({PARTLY} if claim.rule.partly else set())
    assert set(CASES.get(claim.id, {})) == expected
    if claim.applies(QUICK, empty()) and claim.id != "kinematics":
        assert claim.judge(QUICK, empty()).verdict == NOT_MEASURED


def test_claims_table():
    ids = [c.id for c in CLAIMS]
    assert len(ids) == len(set(ids)) >= 17
    assert {c.section for c in CLAIMS} == {str(n) for n in range(1, 8)}
    for c in CLAIMS:  # every bound reads a number the claim names
        assert c.rule.measures() <= set(c.names)


def test_paper_numbers_typed_once():
    by = {c.id: c for c in CLAIMS}
    assert by["kinematics"].paper == "0.31 / 0.42 m, +35 %"
    assert by["max_step"].paper == "0.30 / 0.40 / 0.40 m (fixed / redundancy / MPC), +33 %"
    assert by["energy_mean_long"].paper.startswith("309.6 vs 411.")
    assert by["energy_short"].paper == "0.15: 12.8 / 10.1 vs 14.8 J; 0.20: 18.2 / 16.9 vs 19.1 J"
    assert by["energy_std"].paper == "smaller at all 6 lengths"
    assert by["energy_std_gap_grows"].paper == "2.2 -> 563 J from 0.15 to 0.40 m"


def test_equivalent_length_claim_only_where_our_limit_differs():
    ids = [c.id for c in evaluate(QUICK, kappa_ratio(0.30, 2.0, fixed_limit=0.30))]
    assert "kappa_030_equivalent" not in ids and "kappa_030" in ids
    ids = [c.id for c in evaluate(QUICK, kappa_ratio(0.30, 2.0, fixed_limit=0.35))]
    assert "kappa_030_equivalent" in ids


def test_verdict_helper():
    rule = Rule((above("x", 1.0), above("y", 0.0)), (above("x", 0.5),))
    assert verdict({"x": 2.0, "y": 1.0}, rule) == HOLDS
    assert verdict({"x": 2.0, "y": -1.0}, rule) == PARTLY  # partly needs x > 0.5 only
    assert verdict({"x": 0.4, "y": 1.0}, rule) == FAILS
    assert verdict({"x": math.nan, "y": 1.0}, rule) == FAILS  # NaN meets no bound
    assert verdict({"x": None, "y": 1.0}, rule) == FAILS
    assert verdict(None, rule) == NOT_MEASURED
    either = Rule((is_("clean", False), above("x", 5.0)), any_holds=True)
    assert verdict({"clean": False, "x": 1.0}, either) == HOLDS
    assert verdict({"clean": True, "x": 6.0}, either) == HOLDS
    assert verdict({"clean": True, "x": 1.0}, either) == FAILS
    with pytest.raises(ValueError):
        Bound("x", "~", 1.0)
    assert rule.words({"x": "the ratio"}).startswith("holds if the ratio > 1")


# -- the report's tables ----------------------------------------------------------------------
def test_table_cells_escape_pipes():
    assert escape_cell("peak |d rate/dt|") == "peak \\|d rate/dt\\|"
    assert row("a|b", 1, None) == "| a\\|b | 1 | None |"
    assert header("x", "|y|").splitlines() == ["| x | \\|y\\| |", "|---|---|"]


def _cells(line: str) -> int:
    """Columns of a markdown table row, ``\\|`` not counting as a separator."""
    return line.replace("\\|", "").count("|") - 1


def test_report_from_synthetic_results_keeps_rows_intact():
    r = CASES["waist_rate_sharp"][HOLDS]
    r = dataclasses.replace(r, claims=evaluate(QUICK, r))
    md = render(QUICK, r)
    for n in range(1, 8):
        assert f"## {n}. " in md
    assert "not drawn: runs missing" in md
    table = md.split("## Claims of the paper")[1].split("\n## ")[0]
    rows = [line for line in table.splitlines() if line.startswith("|")]
    assert len(rows) == 2 + len(r.claims)
    assert {_cells(line) for line in rows} == {5}
    assert "\\|d rate/dt\\|" in table


def test_energy_partly_needs_half_of_the_comparisons():
    """One comparison of four in the paper's direction is not "partly"."""
    one_of_four = energy(
        {
            ("fixed", 0.25): (20, 1),
            ("redundancy", 0.25): (25, 1),
            ("mpc", 0.25): (18, 1),
            ("fixed", 0.3): (50, 1),
            ("redundancy", 0.3): (40, 1),
            ("mpc", 0.3): (45, 1),
        }
    )
    assert BY_ID["energy_mid"].judge(QUICK, one_of_four).verdict == FAILS


def test_significance_is_over_the_repeats():
    """Welch's t-test on the repeats' means: a gap the repeats' spread covers is n.s."""
    a = dataclasses.replace(_cell(10.0, 5.0), run_means=[5.0, 15.0, 8.0, 12.0])
    b = dataclasses.replace(_cell(11.0, 5.0), run_means=[6.0, 16.0, 9.0, 13.0])
    c = dataclasses.replace(_cell(30.0, 5.0), run_means=[29.0, 31.0, 30.5, 29.5])
    assert not sections.significant(a, b)
    assert sections.significant(a, c)
    assert sections.welch_p([1.0], [2.0, 3.0]) is None
