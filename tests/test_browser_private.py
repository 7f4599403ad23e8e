"""Private sessions in real browsers, one scenario per test: each browser's robots follow its
own slider; a browser beyond capacity is told so and watches the shared demo; a browser that
closes ends its session; a killed worker is reported on the page and in /api/health and its
sessions restart.

One server in private mode whose sessions show one robot (mpc), one worker holding 3 robots:
the shared demo and two private sessions fill it, so a third browser is refused. Every test
closes its browsers and waits for their sessions to end, so each starts from the shared demo
alone; the worker's death comes last.
"""

from __future__ import annotations

import contextlib
import os
import signal

import httpx
import pytest
from browser_util import (
    WAIT_S,
    api,
    chromium,
    click_slider,
    needs_chromium,
    open_scene,
    serving,
    slider_value,
    wait_until,
)

pytestmark = needs_chromium
VIEWPORT = {"width": 1300, "height": 720}  # small: three pages render in software at once
# A private session answers only to its browser and the instructor: the test reads every
# session as the instructor (the browsers here connect to the scene alone, without a page)
TOKEN = "private-browsers-4Wd-token"
TEACHER = {"Authorization": f"Bearer {TOKEN}"}


@pytest.fixture(scope="module")
def tool():
    args = ("--sessions", "private", "--workers", "1", "--robots-per-worker", "3")
    with serving(*args, "--methods", "mpc", "--instructor-token", TOKEN) as (base, viser_url, _):
        yield base, viser_url


def get(base: str, path: str, sid: str | None = None):
    """``GET`` an API route as the instructor."""
    r = httpx.get(f"{api(base, sid)}/{path}", headers=TEACHER, timeout=30)
    r.raise_for_status()
    return r.json()


def wait_robots(base: str, what: str, ok, sid: str | None = None, timeout=WAIT_S) -> list:
    """Wait until every robot of session ``sid``'s state satisfies ``ok``; the robots."""
    return wait_until(
        lambda: (rs := get(base, "state", sid)["robots"]) and all(ok(r) for r in rs) and rs,
        what,
        timeout,
    )


@pytest.fixture(scope="module")
def browser():
    with chromium() as b:
        yield b


def _private(base: str) -> list[dict]:
    return [s for s in get(base, "sessions")["sessions"] if s["kind"] == "private"]


def _diagnosis(base: str) -> str:
    """What the server says about its sessions and viewers, for a failure's message."""
    return f"sessions: {get(base, 'sessions')}; health: {get(base, 'health')}"


@contextlib.contextmanager
def _pages(tool, browser):
    """Open pages with ``open(url=viser URL)``; at the end close them all and wait until
    their private sessions have ended."""
    base, viser_url = tool
    wait_until(lambda: not _private(base), f"no private session left over: {_diagnosis(base)}")
    pages: list = []

    def open_page(url: str = viser_url, framed: bool = False):
        page, scene = open_scene(browser, url, VIEWPORT, framed=framed)
        pages.append(page)
        return page, scene

    try:
        yield open_page
    finally:
        for page in pages:
            with contextlib.suppress(Exception):
                page.context.close()
        wait_until(lambda: not _private(base), "the closed browsers' sessions to end")


def _open_private(base: str, open_page, n: int):
    """Open a browser that gets the ``n``-th private session (the previous one stands alone:
    a late reconnect would leave one more for a moment and this one would be refused)."""
    wait_until(lambda: len(_private(base)) == n - 1, f"{n - 1} private sessions")
    page, scene = open_page()
    wait_until(lambda: len(_private(base)) == n, f"the {n}. private session: {_diagnosis(base)}")
    return page, scene


def test_each_browser_walks_at_its_own_step_length(tool, browser):
    base, _viser_url = tool
    with _pages(tool, browser) as open_page:
        for n, value in enumerate((0.25, 0.35), start=1):
            page, scene = _open_private(base, open_page, n)
            click_slider(page, scene, "Step length [m]", value)
            assert slider_value(scene, "Step length [m]") == pytest.approx(value)
            wait_until(
                lambda v=value: any(
                    get(base, "params", s["id"])["walk"]["step_length"] == pytest.approx(v)
                    for s in _private(base)
                ),
                f"a session at {value} m: {_diagnosis(base)}",
            )
        sessions = _private(base)
        lengths = {s["id"]: get(base, "params", s["id"])["walk"]["step_length"] for s in sessions}
        assert sorted(lengths.values()) == pytest.approx([0.25, 0.35]), _diagnosis(base)
        # each one's robots take its own length from their next step; the shared demo not
        for sid, want in lengths.items():
            wait_robots(
                base,
                f"session {sid}'s robots at {want} m",
                lambda r, w=want: r["step_length"] == pytest.approx(w) and r["step_index"] >= 1,
                sid=sid,
                timeout=120,
            )
        assert get(base, "params")["walk"]["step_length"] == pytest.approx(0.2)


def test_a_browser_beyond_capacity_is_told_and_watches_the_shared_demo(tool, browser):
    base, _viser_url = tool
    with _pages(tool, browser) as open_page:
        for n in (1, 2):
            _open_private(base, open_page, n)
        _page, third = open_page()
        third.get_by_text("as many as the workers hold").wait_for()
        assert slider_value(third, "Step length [m]") == pytest.approx(0.2)  # the shared demo's
        assert len(_private(base)) == 2


def test_a_closed_browser_ends_its_session_and_frees_its_slots(tool, browser):
    base, _viser_url = tool
    with _pages(tool, browser) as open_page:
        page, _scene = _open_private(base, open_page, 1)
        free = get(base, "sessions")["robot_slots_free"]
        page.context.close()  # mid-walk
        wait_until(lambda: not _private(base), "the closed browser's session to end")
        assert get(base, "sessions")["robot_slots_free"] == free + 1
        assert get(base, "health")["status"] == "ok"


def test_a_killed_worker_is_reported_and_its_sessions_restart(tool, browser):
    base, _viser_url = tool
    with _pages(tool, browser) as open_page:
        # the tool's page frames the scene: that viewer takes a private session too
        page, _scene = open_page(base + "/", framed=True)
        wait_until(lambda: len(_private(base)) == 1, f"a private session: {_diagnosis(base)}")
        kept = _private(base)[0]["id"]
        worker = get(base, "health")["workers"][0]
        os.kill(worker["pid"], signal.SIGKILL)
        health = wait_until(
            lambda: (h := get(base, "health"))["worker_deaths"] and h["status"] == "ok" and h,
            "the death to be reported and a new worker to run",
        )
        assert f"pid {worker['pid']}" in health["worker_deaths"][0]
        page.locator("#status", has_text="stopped at").wait_for()
        assert kept in [s["id"] for s in _private(base)]  # the open browser's session
        wait_until(  # runs on, restarted on the new worker
            lambda: get(base, "state", kept)["robots"][0]["t"] > 1.0,
            "the session's robot to walk again on the new worker",
        )
