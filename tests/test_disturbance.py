"""The seeded disturbance of the study's repeats: it lasts the whole run, so two seeds give
different energy means, and one seed gives the same run twice."""

from __future__ import annotations

from app.experiments.definitions import DISTURBANCE, DISTURBANCE_PERIOD, RunSpec
from controller.params import ControllerParams
from pelvic_walk.core.run import RunConfig, Session, run, summarize

PARAMS = ControllerParams().replace(method="mpc", walk={"step_length": 0.2, "n_steps": 3})


def _cfg(seed: int | None) -> RunConfig:
    return RunConfig(
        params=PARAMS,
        seed=seed,
        perturbation=0.0,  # the pushes alone
        disturbance=DISTURBANCE,
        disturbance_period=DISTURBANCE_PERIOD,
    )


def _energy(seed: int) -> list[float]:
    s = summarize(run(_cfg(seed)))
    assert s["success"] and s["energy_two_step_windows"]
    return s["energy_two_step_windows"]


def test_two_seeds_give_different_energy_means_and_one_seed_the_same():
    a, b = _energy(0), _energy(1)
    assert abs(sum(a) / len(a) - sum(b) / len(b)) > 1e-6 * a[0]  # the repeats are not copies
    assert _energy(0) == a  # a seed is one run


def test_the_pushes_need_a_seed():
    assert Session(_cfg(None))._disturb_rng is None
    assert Session(_cfg(2))._disturb_rng is not None
    assert RunSpec("mpc", 0.3, 4, seed=3).disturbance == DISTURBANCE
    assert RunSpec("mpc", 0.3, 4).disturbance == 0.0
