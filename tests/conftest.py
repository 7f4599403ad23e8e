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

import os

import pytest

# Whole files that are slow (the rest mark single tests with @pytest.mark.slow).
SLOW_FILES = {"test_install", "test_schemathesis", "test_lint", "test_loadtest"}
BROWSER_RERUNS = 1 if os.environ.get("CI", "").lower() in ("true", "1", "yes") else 0


@pytest.hookimpl(tryfirst=True)  # before xdist reads the marks into the node ids
def pytest_collection_modifyitems(config, items):
    for item in items:
        browser = item.get_closest_marker("browser") is not None
        if item.module.__name__ in SLOW_FILES:
            item.add_marker(pytest.mark.slow)
        if browser and BROWSER_RERUNS:
            item.add_marker(pytest.mark.flaky(reruns=BROWSER_RERUNS))
        if not any(item.iter_markers("xdist_group")):
            group = "browser" if browser else item.module.__name__
            item.add_marker(pytest.mark.xdist_group(group))


@pytest.fixture(scope="session", autouse=True)
def _own_state_dir(tmp_path_factory):
    """Tests never write into the user's state: XDG_STATE_HOME (where `experiments` records
    the reports `/report` shows, app/report_dir.py) points at a folder of this test session,
    for this process and the servers and studies it starts."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("XDG_STATE_HOME", str(tmp_path_factory.mktemp("xdg-state")))
        yield
