"""The one run function: a whole plan headless (``simulate``, ``POST /api/runs``, the study).

:class:`~app.sim.session.Session` steps one robot one control period at a time; :func:`run`
loops it to the end of the plan (or shortly after a fall). The live tool paces the same
``Session`` to real time and publishes frames instead.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from app.sim.session import RunConfig, Session
from app.sim.summary import SUMMARY_KEYS

__all__ = ["SUMMARY_KEYS", "RunConfig", "Session", "run"]


def run(
    cfg: RunConfig,
    max_wall_s: float | None = None,
    on_tick: Callable[[Session], None] | None = None,
) -> Session:
    """Run a whole plan headless (stops ``cfg.settle_time`` after a fall, or at ``max_wall_s``
    of wall time); returns the session with its series and summary. ``on_tick`` (e.g. a
    recording's capture) is called with the session after every control tick."""
    session = Session(cfg)
    start = time.perf_counter()
    settle_ticks = int(cfg.settle_time / cfg.params.control_dt)
    while not session.walker.finished:
        session.tick()
        if on_tick is not None:
            on_tick(session)
        if session.fell:
            settle_ticks -= 1
            if settle_ticks <= 0:
                break
        if max_wall_s is not None and time.perf_counter() - start > max_wall_s:
            break
    return session
