"""How ``make test`` shares the test files out between its two xdist workers
(``tests/conftest.py``): every real-browser file in one group, every other file its own."""

from __future__ import annotations

from conftest import BROWSER_GROUP, xdist_group_of


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
