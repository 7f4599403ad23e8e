"""Section 10 (strategies beside the MPC) as data: which runs it adds, and its reading on
synthetic rows (the end-to-end run is in test_experiments' quick study)."""

from __future__ import annotations

import dataclasses

import pytest

from app.experiments import ablation
from app.experiments.definitions import FULL, QUICK, Ablations, planned_runs
from app.experiments.robustness import PushCell
from controller import strategy


@pytest.fixture(autouse=True, scope="module")
def _forget_the_examples():
    """The examples this module loads leave the registry after it (their colours are free)."""
    before = set(strategy.names())
    yield
    for name in set(strategy.names()) - before:
        strategy.unregister(name)


def _push(m: str, d: str, survived: float) -> PushCell:
    return PushCell(m, 0.3, d, 0.1, survived, survived + 2.0, "fell", 7)


def _row(m: str, role: str, longest: float, waist: float, left: float, right: float):
    return ablation.AblationRow(
        method=m,
        label=f"label of {m}",
        role=role,
        source=None,
        longest_clean=longest,
        first_failed=longest + 0.01,
        walks_limit=longest + 0.02,
        clean={"0.30": True, "0.40": longest >= 0.4},
        waist_peak_deg={"0.30": waist * 0.7, "0.40": waist},
        energy={"0.30": 40.0, "0.40": 50.0},
        energy_substep={"0.30": 60.0, "0.40": 70.0},
        energy_std={"0.30": 1.0, "0.40": 1.0},
        early_turn_share=0.05,
        early_turn_of_sine=0.5,
        peak_rate_change_deg_s2=200.0,
        kappa_legs_landing=40.0,
        pushes={"left": _push(m, "left", left), "right": _push(m, "right", right)},
        strategy_ms_median=0.02 if m == "mpc" else 0.005,
    )


def test_the_study_runs_the_examples_beside_the_mpc():
    names = FULL.ablation_methods()
    assert names == ("track_ref", "sine")
    req = planned_runs(FULL)
    for m in names:
        lengths = {s.step_length for s in req if s.method == m}
        assert lengths == {*FULL.sweep_grid, *FULL.figure_lengths}
        assert all(s.seed is None and "step" in req[s] for s in req if s.method == m)
    # a study without section 10 runs no other strategy
    bare = dataclasses.replace(QUICK, ablations=None)
    assert bare.ablation_methods() == ()
    assert {s.method for s in planned_runs(bare)} == set(strategy.BUILTINS)


def test_a_missing_example_is_skipped(tmp_path):
    study = dataclasses.replace(
        QUICK, ablations=Ablations(files=(str(tmp_path / "gone.py"), "track_reference.py"))
    )
    assert study.ablation_methods() == ("track_ref",)


def test_reading_compares_each_strategy_with_the_mpc():
    section = ablation.AblationSection(
        lengths=[0.3, 0.4],
        turn_length=0.4,
        push_length=0.3,
        resolution=0.01,
        rows=[
            _row("fixed", "paper", 0.37, 0.0, 100.0, 74.0),
            _row("mpc", "paper", 0.43, 25.1, 96.0, 76.0),
            _row("gain", "example", 0.42, 23.7, 90.0, 80.0),
        ],
    )
    (line,) = ablation.reading(section)
    assert line.startswith("**label of gain** (`gain`)")
    assert "longest clean step 0.42 m against the MPC's 0.43 m" in line
    assert "the fixed pelvis's 0.37 m" in line
    assert "waist at 0.40 m 23.7 deg (MPC 25.1 deg)" in line
    assert "-6 N left, +4 N right" in line
    assert ablation.buys(section, section.rows[2]) == (
        "+0.01 m of longest clean step (one step of the grid); a largest shove +6 N left, "
        "-4 N right; the same energy at 0.40 m within the windows' spread (+0.0 J, spread "
        "1.0 J); at 4 x its time a tick"
    )
    # equal within the grid, the bisection and the spread: said so; beyond them: not
    close = _row("gain", "example", 0.43, 23.7, 97.0, 75.0)
    same = dataclasses.replace(section, rows=[*section.rows[:2], close], push_resolution=2.0)
    words = ablation.buys(same, close)
    assert words.startswith("the same longest clean step; the same largest shove within")
    costly = dataclasses.replace(close, energy={"0.30": 40.0, "0.40": 53.0})
    far = dataclasses.replace(section, rows=[*section.rows[:2], costly], push_resolution=2.0)
    assert "+3.0 J less energy per two steps at 0.40 m" in ablation.buys(far, costly)
    # without the MPC's row there is nothing to compare with
    no_mpc = dataclasses.replace(section, rows=section.rows[2:])
    assert ablation.reading(no_mpc) == []


def test_a_students_copy_of_an_example_keeps_its_name(tmp_path, capsys):
    """A student's file that reuses an example's name wins; the example is left out, said once."""
    mine = tmp_path / "my_sine.py"
    mine.write_text(
        "from pelvic_walk import PelvisStrategy\n\n\n"
        "class MySine(PelvisStrategy):\n"
        '    name = "sine"\n\n'
        "    def waist_rate(self, s):\n"
        "        return 0.0\n"
    )
    for name in ("track_ref", "sine"):  # as in a fresh process: the student's file loads first
        if strategy.is_registered(name):
            strategy.unregister(name)
    study = dataclasses.replace(QUICK, strategies=(str(mine),))
    assert study.ablation_methods() == ("track_ref", "sine")
    assert strategy.info("sine").source == f"{mine}:MySine"
    err = capsys.readouterr().err
    assert "leaves out the example feedforward_sine.py" in err and "taken by" in err
