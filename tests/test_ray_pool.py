"""The worker pool's own tests (``tests/test_pool.py``) on the Ray engine: the same pool, its
workers Ray actors on a local Ray instance of 2 CPUs (``serve --ray``'s engine), so what the
pool does (robots split over workers in step, admission, a dead worker replaced and its
sessions restarted, a pause) holds on both engines.

Marked ``ray`` (``pytest -m ray``: the Ray set alone) and ``slow``; skipped without Ray.
"""

from __future__ import annotations

import pytest
from test_pool import (
    test_a_dead_worker_is_reported_replaced_and_its_sessions_restart,
    test_a_pause_keeps_every_frame_kept_while_running,
    test_a_session_split_across_workers_keeps_step,
    test_admission_and_closing_free_the_slots,
)

from app.live.pool import WorkerPool

pytestmark = [pytest.mark.ray, pytest.mark.slow]

__all__ = [
    "test_a_dead_worker_is_reported_replaced_and_its_sessions_restart",
    "test_a_pause_keeps_every_frame_kept_while_running",
    "test_a_session_split_across_workers_keeps_step",
    "test_admission_and_closing_free_the_slots",
]


@pytest.fixture(scope="module")
def pool():
    """The pool of tests/test_pool.py (2 workers x 2 robots), its workers Ray actors."""
    ray = pytest.importorskip(
        "ray", reason="Ray is an optional extra: pip install '.[cluster]'", exc_type=ImportError
    )
    from app.live.ray_engine import RayEngine

    engine = RayEngine(robots_per_worker=2, cpus=2)
    p = WorkerPool(2, robots_per_worker=2, engine=engine).start()
    yield p
    p.stop()  # (its engine's local Ray instance too)
    assert not ray.is_initialized()
