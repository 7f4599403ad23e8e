"""The rerun rule of tests/conftest.py: under CI=true a failed real-browser test is run once
more and listed with its first failure; any other test is never rerun; without CI nothing is."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["pytester"]
PROBES = """
import pytest
from pathlib import Path

@pytest.mark.browser
def test_flaky_browser(tmp_path_factory):
    flag = tmp_path_factory.getbasetemp().parent / "failed-once"
    if not flag.exists():
        flag.write_text("x")
        raise AssertionError("first failure of a flaky browser test")

def test_plain_failure():
    raise AssertionError("a unit test that fails")
"""


@pytest.fixture
def probes(pytester):
    pytester.makeconftest((Path(__file__).with_name("conftest.py")).read_text())
    pytester.makeini(
        "[pytest]\nmarkers =\n    browser: x\n    slow: y\naddopts = -raR --rerun-show-tracebacks\n"
    )
    pytester.makepyfile(test_probes=PROBES)
    return pytester


def test_ci_reruns_a_browser_test_once_and_shows_its_first_failure(probes, monkeypatch):
    monkeypatch.setenv("CI", "true")
    result = probes.runpytest_subprocess("-p", "no:cacheprovider")
    outcomes = result.parseoutcomes()
    assert (outcomes["passed"], outcomes["failed"], outcomes["rerun"]) == (1, 1, 1), outcomes
    out = result.stdout.str()
    assert "rerun test summary info" in out
    assert "RERUN test_probes.py::test_flaky_browser" in out
    assert "first failure of a flaky browser test" in out  # its first failure, shown


def test_without_ci_nothing_is_rerun(probes, monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    result = probes.runpytest_subprocess("-p", "no:cacheprovider")
    outcomes = result.parseoutcomes()
    assert outcomes["failed"] == 2 and "rerun" not in outcomes, outcomes
