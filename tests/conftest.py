"""Test scheduling, markers and the rerun rule, in one place.

- **Groups** under pytest-xdist (``make test`` runs ``-n 2 --dist loadgroup``): each test file is
  one group (its module fixtures, e.g. a served tool, start once), except the real-browser
  files, which form one group: a headless Chromium renders the scene in software and takes a
  core, so two at once beside two servers starve each other.
- **Markers**: ``browser`` (drives a real Chromium), ``slow`` (long closed-loop runs, a study, a
  wheel build, schemathesis, mypy, a load test). ``make check`` runs the rest, the quick inner
  loop: ``-m "not browser and not slow"``.
- **Reruns show, and only real-browser tests get one**: under ``CI=true`` (``.ci/run`` sets it)
  a real-browser test that fails is run once more (pytest-rerunfailures), as Playwright's own
  runner does on CI; the summary lists every rerun with the traceback of its first failure
  ("rerun test summary info"), so a flake never hides. Other tests are never rerun.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

import pytest

# Whole files that are slow (the rest mark single tests with @pytest.mark.slow).
SLOW_FILES = {"test_install", "test_schemathesis", "test_lint", "test_loadtest", "test_rerun_rule"}
BROWSER_GROUP = "real-browser tests"
BROWSER_RERUNS = 1 if os.environ.get("CI", "").lower() in ("true", "1", "yes") else 0


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.module.__name__ in SLOW_FILES:
            item.add_marker(pytest.mark.slow)
        if item.get_closest_marker("browser") is not None and BROWSER_RERUNS:
            item.add_marker(pytest.mark.flaky(reruns=BROWSER_RERUNS))


NOTEBOOK_FILE = "test_notebooks.py"  # its notebooks run one per group: the workers share them


def xdist_group_of(nodeid: str) -> str:
    """The group a test runs in under xdist: its file, or one group for every real-browser
    file (``tests/test_browser*.py``: the files whose tests drive Chromium); each course
    notebook of ``tests/test_notebooks.py`` is a group of its own."""
    path = nodeid.split("::", 1)[0]
    if Path(path).name == NOTEBOOK_FILE and "[" in nodeid:  # each notebook on its own
        return nodeid
    return BROWSER_GROUP if Path(path).name.startswith("test_browser") else path


# The groups that take longest, with their seconds in one full `make test` on the 2-core machine
# (only their order matters). A worker that asks for work gets the longest group still waiting:
# xdist's own order (most tests first) started the browser group, the longest chain of the
# run, fifth, and the one-test schemathesis file last, while the other worker sat idle. A group
# not listed costs nothing here and keeps xdist's order, after these.
GROUP_COST_S = {
    BROWSER_GROUP: 735,
    "tests/test_experiments.py": 210,
    "tests/test_schemathesis.py": 62,
    "tests/test_ray_live.py": 56,
    "tests/test_loadtest.py": 44,
    "tests/test_lint.py": 44,
    "tests/test_pool.py": 42,
    "tests/test_api.py": 32,
    "tests/test_ray_pool.py": 30,
    "tests/test_strategies.py": 27,
    "tests/test_sweep.py": 26,
    "tests/test_notebooks.py": 24,
    "tests/test_python_api.py": 21,
    "tests/test_clean_log.py": 21,
    "tests/test_compiled.py": 20,
    "tests/test_install.py": 20,
    "tests/test_robots_live.py": 19,
    "tests/test_cli.py": 17,
    "tests/test_live.py": 15,
    "tests/test_walker.py": 14,
    "tests/test_seats.py": 13,
    "tests/test_rerun_rule.py": 12,
}


def next_group(waiting: Iterable[str]) -> str:
    """The group to hand out next: the costliest waiting (:data:`GROUP_COST_S`), the first in
    ``waiting``'s order among equals."""
    return max(waiting, key=lambda group: GROUP_COST_S.get(group, 0))


def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup`` by :func:`xdist_group_of`, the longest groups first
    (:func:`next_group`). xdist's own loadgroup reads ``xdist_group`` marks into node ids,
    which pytest 9 no longer lets it rewrite: the marks were silently ignored and two browser
    files ran at once. The scheduler sees node ids only, hence groups by file name."""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class ByTestGroup(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return xdist_group_of(nodeid)

        def _assign_work_unit(self, node) -> None:
            # xdist hands out the first group of its (ordered) queue: put the costliest there
            if self.workqueue:
                self.workqueue.move_to_end(next_group(self.workqueue), last=False)
            super()._assign_work_unit(node)

    return ByTestGroup(config, log)


@pytest.fixture(scope="session", autouse=True)
def _own_state_dir(tmp_path_factory):
    """Tests never write into the user's state: XDG_STATE_HOME (where `experiments` records
    the reports `/report` shows, pelvic_walk/core/report_dir.py) points at a folder of this
    test session, for this process and the servers and studies it starts."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("XDG_STATE_HOME", str(tmp_path_factory.mktemp("xdg-state")))
        yield


# -- the API around a live session (one per test module) --------------------------------------
# A module tunes them with module-level dicts: LIVE_SESSION (initial_intent's keyword
# arguments, e.g. ``{"methods": ["mpc"], "speed": 4.0}``; the plans are short, N_STEPS steps)
# and APP_OPTIONS (create_app's, e.g. ``{"runs": RunManager(max_wall_s=2.0)}``).
N_STEPS = 4  # steps of a live plan in these tests: short, so plan ends and restarts are seen


@pytest.fixture(scope="module")
def live_pool():
    """The worker pool of a test module, on its in-process engine (the workers are threads of
    this process: nothing to spawn, and the tests may read the robots); room for six robots."""
    from app.live.engines import InProcessEngine
    from app.live.pool import WorkerPool

    pool = WorkerPool(1, robots_per_worker=6, engine=InProcessEngine()).start()
    yield pool
    pool.stop()


@pytest.fixture(scope="module")
def live(live_pool, request):
    """A running session of :func:`live_pool` (two robots, fixed and mpc, by default) that has
    published a frame; closed at the end, and it must not have failed."""
    from app.live.session import initial_intent
    from controller.params import ControllerParams

    kw = {"methods": ["fixed", "mpc"], **getattr(request.module, "LIVE_SESSION", {})}
    params = ControllerParams().replace(walk={"n_steps": N_STEPS})
    session = live_pool.open(initial_intent(params, **kw), sid="shared")
    assert session.wait_frame(timeout=60) is not None, "the live session published nothing"
    yield session
    live_pool.close(session)
    assert session.error is None, session.error


@pytest.fixture(scope="module")
def client(live, request):
    """FastAPI's TestClient on the app around :func:`live` (with the module's APP_OPTIONS)."""
    from fastapi.testclient import TestClient

    from app.web.api import create_app

    app = create_app(live, **getattr(request.module, "APP_OPTIONS", {}))
    with TestClient(app) as c:
        yield c
    app.state.runs.shutdown()


@contextlib.contextmanager
def _served_in_thread(app) -> Iterator[str]:
    """uvicorn serving ``app`` on a free loopback port in a thread; yields its base URL."""
    import threading

    import uvicorn

    from app.bench.local_server import free_port

    port = free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    thread = threading.Thread(target=server.run, name="uvicorn", daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started and thread.is_alive() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert server.started, "uvicorn did not start"
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(15)
        app.state.runs.shutdown()


@pytest.fixture(scope="module")
def serve_app():
    """``with serve_app(app) as base_url``: a real HTTP server for requests a TestClient cannot
    make (raw paths, another process such as schemathesis)."""
    return _served_in_thread


@contextlib.contextmanager
def only_builtin_strategies() -> Iterator[None]:
    """The strategy registry as a fresh process has it (the paper's three), and back as it was
    after: a test that counts colours, markers or names must not see the strategies other
    tests of this process loaded (the examples take the palette's colours first)."""
    from controller import params, strategy

    saved = (
        dict(strategy._REGISTRY),
        dict(strategy._LOADED),
        dict(params.OWN_PARAMS),
        dict(params.ALIASES),
    )
    for name in [n for n in strategy.names() if not strategy.info(n).builtin]:
        strategy.unregister(name)
    try:
        yield
    finally:
        for live, kept in zip(
            (strategy._REGISTRY, strategy._LOADED, params.OWN_PARAMS, params.ALIASES),
            saved,
            strict=True,
        ):
            live.clear()
            live.update(kept)  # type: ignore[attr-defined]
