"""How ``make test`` shares the test files out between its two xdist workers
(``tests/conftest.py``): every real-browser file in one group, each course notebook one, every
other file its own."""

from __future__ import annotations

from conftest import BROWSER_GROUP, next_group, xdist_group_of


def test_every_real_browser_file_shares_one_group():
    ids = [
        "tests/test_browser.py::test_x",
        "tests/test_browser_lessons.py::test_a_lesson[lesson3]",
        "tests/test_browser_class_instructor.py::test_y",
    ]
    assert {xdist_group_of(i) for i in ids} == {BROWSER_GROUP}


def test_other_files_are_a_group_each_whatever_their_parameters():
    a = xdist_group_of("tests/test_api.py::test_pages")
    b = xdist_group_of("tests/test_api.py::test_push[left-1.5]")
    c = xdist_group_of("tests/test_pool.py::test_x")
    assert a == b == "tests/test_api.py" and c == "tests/test_pool.py"
    assert BROWSER_GROUP not in (a, c)


def test_each_course_notebook_is_a_group_of_its_own():
    one = xdist_group_of("tests/test_notebooks.py::test_notebook_runs_top_to_bottom[01_a.ipynb]")
    two = xdist_group_of("tests/test_notebooks.py::test_notebook_runs_top_to_bottom[02_b.ipynb]")
    rest = xdist_group_of("tests/test_notebooks.py::test_checks_of_runs_read_the_runs")
    assert len({one, two, rest}) == 3 and rest == "tests/test_notebooks.py"


def test_the_longest_groups_are_handed_out_first():
    """The browser group, the longest chain of the run, starts at once; the rest of the
    listed groups by their cost; unlisted groups keep xdist's order, after them."""
    waiting = ["tests/test_views.py", "tests/test_claims.py", "tests/test_schemathesis.py"]
    assert next_group([*waiting, BROWSER_GROUP, "tests/test_experiments.py"]) == BROWSER_GROUP
    assert next_group([*waiting, "tests/test_experiments.py"]) == "tests/test_experiments.py"
    assert next_group(waiting) == "tests/test_schemathesis.py"
    assert next_group(waiting[:2]) == "tests/test_views.py"
