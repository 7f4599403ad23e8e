"""Test scheduling under pytest-xdist (``make test`` runs ``-n 2 --dist loadgroup``).

Each test file is one group (its module fixtures, e.g. a served tool, start once), except the
real-browser files, which form one group: a headless Chromium renders the scene in software and
takes a core, so two at once beside two servers starve each other and their clicks time out.
"""

from __future__ import annotations

import pytest


@pytest.hookimpl(tryfirst=True)  # before xdist reads the marks into the node ids
def pytest_collection_modifyitems(config, items):
    for item in items:
        if any(item.iter_markers("xdist_group")):
            continue
        group = "browser" if item.get_closest_marker("browser") else item.module.__name__
        item.add_marker(pytest.mark.xdist_group(group))
