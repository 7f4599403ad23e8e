"""``POST /api/runs``, ``GET /api/runs/{id}``: headless runs, bounded, in a background thread.

A run's result does not depend on what else runs (every session owns its workspace):
``tests/test_runs.py`` checks it beside a live session.
"""

from __future__ import annotations

import threading
import time
import traceback
import uuid
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from fastapi import APIRouter, HTTPException

from app.web.api.edges import finite, router, unprocessable
from app.web.api.models import RunRequest, RunStatus, updates
from controller.params import ControllerParams


class RunBusy(RuntimeError):
    """Too many headless runs queued or running."""


class RunManager:
    """Headless runs (``pelvic_walk.core.run.run``) in one background worker thread.

    Bounded: at most ``max_pending`` runs queued or running (they share the CPU with the live
    tool), and only the ``keep`` most recent records are kept.
    """

    def __init__(self, max_wall_s: float = 600.0, max_pending: int = 4, keep: int = 100):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="headless-run")
        self._lock = threading.Lock()
        self._runs: dict[str, dict[str, Any]] = {}
        self.max_wall_s = max_wall_s
        self.max_pending = max_pending
        self.keep = keep

    def submit(self, params: ControllerParams, seed: int | None) -> str:
        """Queue a run; RunBusy if ``max_pending`` runs are already queued or running."""
        run_id = uuid.uuid4().hex[:12]
        with self._lock:
            pending = sum(r["status"] in ("queued", "running") for r in self._runs.values())
            if pending >= self.max_pending:
                raise RunBusy(
                    f"{pending} headless runs are already queued or running; "
                    "poll GET /api/runs/{id} and try again when one is done"
                )
            self._runs[run_id] = {
                "id": run_id,
                "status": "queued",
                "summary": None,
                "error": None,
                "submitted": time.time(),
            }
            finished = [k for k, r in self._runs.items() if r["status"] in ("done", "error")]
            for old in finished[: max(0, len(self._runs) - self.keep)]:
                del self._runs[old]
        self._pool.submit(self._work, run_id, params, seed)
        return run_id

    def _work(self, run_id: str, params: ControllerParams, seed: int | None) -> None:
        from pelvic_walk.core.run import run, spec_of, summarize

        self._set(run_id, status="running")
        try:
            cfg = spec_of(params, seed).config()  # the CLI's run (a seed: the study's repeat)
            summary = summarize(run(cfg, max_wall_s=self.max_wall_s))
            self._set(run_id, status="done", summary=finite(summary))
        except Exception as exc:  # noqa: BLE001 - reported through GET /api/runs/{id}
            traceback.print_exc()
            self._set(run_id, status="error", error=f"{type(exc).__name__}: {exc}")

    def _set(self, run_id: str, **changes: Any) -> None:
        with self._lock:
            self._runs[run_id].update(changes)

    def get(self, run_id: str) -> dict[str, Any] | None:
        with self._lock:
            rec = self._runs.get(run_id)
            return dict(rec) if rec else None

    def shutdown(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


def runs_router(runs: RunManager) -> APIRouter:
    r = router("/api/runs", "runs")

    @r.post("", response_model=RunStatus, status_code=202)
    def post_run(body: RunRequest) -> dict[str, Any]:  # type: ignore[valid-type]
        """Start a headless closed-loop run; poll ``GET /api/runs/{id}`` for its summary (the
        keys of ``simulate --json``, identical to the CLI's for the same arguments)."""
        try:
            params = ControllerParams().replace(method=body.method, **updates(body))  # type: ignore[attr-defined]
        except (ValueError, TypeError) as exc:
            raise unprocessable(str(exc)) from None
        try:
            run_id = runs.submit(params, body.seed)  # type: ignore[attr-defined]
        except RunBusy as exc:
            raise HTTPException(429, detail=str(exc)) from None
        return runs.get(run_id) or {}

    @r.get("/{run_id}", response_model=RunStatus)
    def get_run(run_id: str) -> dict[str, Any]:
        rec = runs.get(run_id)
        if rec is None:
            raise HTTPException(404, detail=f"no run with id {run_id!r}")
        return rec

    return r
