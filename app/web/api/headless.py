"""``POST /api/runs``, ``GET /api/runs/{id}``: headless runs, bounded, in a background thread.

The queue is shared fairly: each client (its private session, else its address, read as every
seat is: :mod:`app.web.addresses`) has at most ``per_client`` runs queued or running, and all
clients together ``max_pending``; the instructor's bearer token is beyond both. A client over
its share gets 429 with ``Retry-After`` and one line saying what to do (the same line whoever
is refused), and no other client is held up by it.

A run's result does not depend on what else runs (every session owns its workspace):
``tests/test_runs.py`` checks it beside a live session.
"""

from __future__ import annotations

import threading
import time
import traceback
import uuid
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from fastapi import APIRouter, Depends, HTTPException

from app.web.api.edges import finite, router, unprocessable
from app.web.api.models import RunRequest, RunStatus, updates
from app.web.api.sessions import Caller
from controller.params import ControllerParams
from pelvic_walk.core import robots as robots_

RETRY_AFTER_S = 10  # [s] a refused client's Retry-After (a short run takes a few seconds)


class RunBusy(RuntimeError):
    """Too many headless runs queued or running (for this client, or for all)."""


def busy_line(held: int, limit: int, whose: str) -> str:
    """The one line every refused client reads."""
    return (
        f"{whose} {held} headless run{'s' if held != 1 else ''} queued or running, as many as "
        f"{'one client may have' if whose == 'you have' else 'the server queues'} ({limit}): "
        "poll GET /api/runs/{id} until one is done, then submit again (Retry-After says "
        "when to look)"
    )


class RunManager:
    """Headless runs (``pelvic_walk.core.run.run``) in one background worker thread.

    Bounded: at most ``per_client`` runs queued or running for one client and ``max_pending``
    for all (they share the CPU with the live tool); a client ``None`` (the instructor) is
    beyond both. Only the ``keep`` most recent records are kept.
    """

    def __init__(
        self,
        max_wall_s: float = 600.0,
        max_pending: int = 16,
        keep: int = 100,
        per_client: int = 2,
    ):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="headless-run")
        self._lock = threading.Lock()
        self._runs: dict[str, dict[str, Any]] = {}
        self.max_wall_s = max_wall_s
        self.max_pending = max_pending
        self.per_client = per_client
        self.keep = keep

    def submit(self, params: ControllerParams, seed: int | None, client: str | None = None) -> str:
        """Queue a run for ``client`` (None: the instructor, beyond every limit); RunBusy if
        that client has ``per_client`` runs queued or running, or all have ``max_pending``."""
        run_id = uuid.uuid4().hex[:12]
        with self._lock:
            live = [r for r in self._runs.values() if r["status"] in ("queued", "running")]
            if client is not None:
                mine = sum(r.get("_client") == client for r in live)
                if mine >= self.per_client:
                    raise RunBusy(busy_line(mine, self.per_client, "you have"))
                others = sum(r.get("_client") is not None for r in live)
                if others >= self.max_pending:
                    raise RunBusy(busy_line(others, self.max_pending, "clients have"))
            self._runs[run_id] = {
                "_client": client,  # never shown (GET /api/runs/{id} answers RunStatus)
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
            return {k: v for k, v in rec.items() if not k.startswith("_")} if rec else None

    def shutdown(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


def run_params(body: Any) -> ControllerParams:
    """A run request's parameters: the defaults with its groups (the paper's and strategies'
    own), then its ``robot``'s strategy and settings, else its ``method`` (ValueError)."""
    params = ControllerParams().replace(method=body.method, **updates(body))
    if body.robot is not None:
        params = robots_.params_of(params, robots_.parse(body.robot))
    return params


def runs_router(
    runs: RunManager, client_of: Callable[[Caller], str | None], caller_dep: Any
) -> APIRouter:
    """``client_of``: the queue's key of a caller (None: the instructor, beyond the limits)."""
    r = router("/api/runs", "runs")
    Who = Depends(caller_dep)

    @r.post(
        "",
        response_model=RunStatus,
        status_code=202,
        responses={429: {"description": "this client's share of the queue is full"}},
    )
    def post_run(body: RunRequest, caller: Caller = Who) -> dict[str, Any]:  # type: ignore[valid-type]
        """Start a headless closed-loop run; poll ``GET /api/runs/{id}`` for its summary (the
        keys of ``simulate --json``, identical to the CLI's for the same arguments). A live
        robot's walk: the session's groups (GET /api/params) and its ``robot`` form. A client
        (its private session, else its address) has at most a few runs queued or running;
        the instructor's bearer token is beyond that limit."""
        try:
            params = run_params(body)
        except (ValueError, TypeError) as exc:
            raise unprocessable(str(exc)) from None
        try:
            run_id = runs.submit(params, body.seed, client_of(caller))  # type: ignore[attr-defined]
        except RunBusy as exc:
            raise HTTPException(
                429, detail=str(exc), headers={"Retry-After": str(RETRY_AFTER_S)}
            ) from None
        return runs.get(run_id) or {}

    @r.get("/{run_id}", response_model=RunStatus)
    def get_run(run_id: str) -> dict[str, Any]:
        rec = runs.get(run_id)
        if rec is None:
            raise HTTPException(404, detail=f"no run with id {run_id!r}")
        return rec

    return r


def run_client(registry: Any) -> Callable[[Caller], str | None]:
    """A caller's key in the run queue: None for the instructor (beyond the limits), its
    private session when it holds one (students behind one address each have their own),
    else its address (one source with the scene's: :mod:`app.web.addresses`). A credential
    the server did not give counts as nothing: inventing tokens makes no new client."""

    def client_of(caller: Caller) -> str | None:
        if caller.instructor:
            return None
        own = registry.owned(caller.credentials) if caller.credentials else None
        if own is not None:
            return f"session {own}"
        return f"address {caller.address or '?'}"

    return client_of
