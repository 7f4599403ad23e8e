"""The one run path: a whole plan headless, for every face.

:class:`~pelvic_walk.core.session.Session` steps one robot one control period at a time;
:func:`run` loops it to the end of the plan (or shortly after a fall), calling the faces'
hooks; :func:`spec_of` names a run as the study's :class:`RunSpec`. The live tool paces the
same ``Session`` to real time and publishes frames instead.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

from controller.params import GROUPS, ControllerParams
from controller.strategy import StrategyError
from pelvic_walk.core.run_spec import OWN_FIELDS, RunSpec
from pelvic_walk.core.session import RunConfig, Session
from pelvic_walk.core.summary import SUMMARY_KEYS, summarize

__all__ = ["SUMMARY_KEYS", "Hook", "RunConfig", "Session", "run", "spec_of", "summarize"]


def spec_of(params: ControllerParams, seed: int | None = None) -> RunSpec:
    """The study's :class:`RunSpec` of these parameters: its own fields (method, length, steps,
    arms, seed) and every other parameter that differs from its default as an override, the
    strategy's own parameters (``gain.k``) among them. Other strategies' own values, which
    ``params`` may carry (a live robot's shared settings), change nothing in this walk and
    are left out.

    ``spec_of(p, n).config()`` is the run the study makes of that cell with seed ``n`` (its
    repeat n: the same start perturbation, the same pushes from the same stream), so
    ``simulate --seed n`` and the study build a run with one function and cannot drift.
    """
    default = ControllerParams()
    overrides = []
    for group in GROUPS:
        ours, theirs = getattr(params, group), getattr(default, group)
        for f in dataclasses.fields(ours):
            name, value = f"{group}.{f.name}", getattr(ours, f.name)
            if name not in OWN_FIELDS and value != getattr(theirs, f.name):
                overrides.append((name, value))
    prefix = f"{params.method}."
    overrides += [(name, value) for name, value in params.own if name.startswith(prefix)]
    spec = RunSpec(
        params.method,
        params.walk.step_length,
        params.walk.n_steps,
        params.arms.enabled,
        seed,
        tuple(overrides),
    )  # (a user's strategy: the spec takes its file from the registry)
    walked = dataclasses.replace(
        params, own=tuple((n, v) for n, v in params.own if n.startswith(prefix))
    )
    if spec.params() != walked:  # a parameter outside the groups (none today)
        raise ValueError("these parameters have no study run spec")
    return spec


Hook = Callable[[Session], None]


def run(
    cfg: RunConfig,
    max_wall_s: float | None = None,
    on_tick: Hook | None = None,
    before_tick: Hook | None = None,
    stop: Callable[[Session], bool] | None = None,
) -> Session:
    """Run a whole plan headless: **the one run path** of every face (``simulate``,
    ``pelvic_walk.simulate``, ``POST /api/runs``, a sweep, the push study, the study).

    Stops at the end of the plan, ``cfg.settle_time`` after a fall, at once when the pelvis
    strategy fails (its :class:`StrategyError` is kept in ``session.error``, never raised: a
    student's fault stops this walk only), when ``stop(session)`` says so after a tick, or at
    ``max_wall_s`` of wall time. Returns the session with its series and summary.

    Hooks, called with the session: ``before_tick`` before every control tick (e.g. the push
    study's shove at mid-step), ``on_tick`` after it (a frame sink such as
    :class:`~pelvic_walk.core.capture.Capture`, a measurement).
    """
    session = Session(cfg)
    start = time.perf_counter()
    settle_ticks = int(cfg.settle_time / cfg.params.control_dt)
    while not session.walker.finished:
        if before_tick is not None:
            before_tick(session)
        try:
            session.tick()
        except StrategyError:  # recorded in session.error; the summary says it
            break
        if on_tick is not None:
            on_tick(session)
        if stop is not None and stop(session):
            break
        if session.fell:
            settle_ticks -= 1
            if settle_ticks <= 0:
                break
        if max_wall_s is not None and time.perf_counter() - start > max_wall_s:
            break
    return session
