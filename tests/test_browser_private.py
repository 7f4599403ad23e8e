"""Private sessions in real browsers: each browser's robots follow its own slider; a browser
beyond capacity is told so and watches the shared demo; a browser that closes ends its
session; a killed worker is reported on the page and in /api/health and its sessions restart.

One server in private mode whose sessions show one robot (mpc), one worker holding 3 robots:
the shared demo and two private sessions fill it, so the third browser is refused.
"""

from __future__ import annotations

import os
import signal

import httpx
import pytest
from browser_util import (
    CHROME_ARGS,
    CHROMIUM,
    click_slider,
    close_notice,
    needs_chromium,
    serving,
    slider,
    wait_for,
)

pytestmark = needs_chromium
VIEWPORT = {"width": 1300, "height": 720}  # small: three pages render in software at once


def _private(base: str) -> list[dict]:
    return [
        s
        for s in httpx.get(f"{base}/api/sessions", timeout=10).json()["sessions"]
        if s["kind"] == "private"
    ]


def _step_length(base: str, sid: str) -> float:
    return httpx.get(f"{base}/api/sessions/{sid}/params", timeout=10).json()["walk"]["step_length"]


def _diagnosis(base: str) -> str:
    """What the server says about its sessions and viewers, for a failure's message."""
    sessions = httpx.get(f"{base}/api/sessions", timeout=10).json()
    health = httpx.get(f"{base}/api/health", timeout=10).json()
    return f"sessions: {sessions}; health: {health}"


def test_private_sessions_admission_close_and_a_worker_death():
    from playwright.sync_api import sync_playwright

    with (
        serving(
            "--sessions",
            "private",
            "--workers",
            "1",
            "--robots-per-worker",
            "3",
            "--methods",
            "mpc",
        ) as (base, viser_url, _proc),
        sync_playwright() as p,
    ):
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROME_ARGS)
        try:
            pages = []
            for n, value in enumerate((0.25, 0.35)):  # two browsers, each its own session
                # the previous browser's session stands alone (a late reconnect would leave one
                # more for a moment and the next browser would be refused)
                assert wait_for(lambda n=n: len(_private(base)) == n, timeout=60), _diagnosis(base)
                page = browser.new_context(viewport=VIEWPORT).new_page()
                page.goto(viser_url)
                thumb, _track = slider(page, "Step length [m]")
                close_notice(page)
                click_slider(page, page, "Step length [m]", value)
                assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(value)
                assert wait_for(
                    lambda v=value: any(
                        _step_length(base, s["id"]) == pytest.approx(v) for s in _private(base)
                    ),
                    timeout=60,
                ), _diagnosis(base)
                pages.append(page)
            sessions = _private(base)
            assert sorted(_step_length(base, s["id"]) for s in sessions) == pytest.approx(
                [0.25, 0.35]
            ), _diagnosis(base)
            # each one's robots take its own length from their next step; the shared demo not
            for s in sessions:
                want = _step_length(base, s["id"])
                state = wait_for(
                    lambda sid=s["id"], w=want: (
                        (st := httpx.get(f"{base}/api/sessions/{sid}/state", timeout=10).json())
                        and all(
                            r["step_length"] == pytest.approx(w) and r["step_index"] >= 1
                            for r in st["robots"]
                        )
                        and st
                    ),
                    timeout=120,
                )
                assert state, s
            assert httpx.get(f"{base}/api/params", timeout=30).json()["walk"]["step_length"] == 0.2

            # the third browser: beyond capacity, told so, watching the shared demo
            third = browser.new_context(viewport=VIEWPORT).new_page()
            third.goto(viser_url)
            notice = third.get_by_text("as many as the workers hold")
            notice.wait_for(timeout=60_000)
            thumb, _track = slider(third, "Step length [m]")
            assert float(thumb.get_attribute("aria-valuenow")) == pytest.approx(0.2)
            assert len(_private(base)) == 2
            third.context.close()

            # a browser that closes mid-walk ends its session and frees its robots' slots
            free = httpx.get(f"{base}/api/sessions", timeout=30).json()["robot_slots_free"]
            pages[0].context.close()
            assert wait_for(lambda: len(_private(base)) == 1, timeout=30)
            assert (
                httpx.get(f"{base}/api/sessions", timeout=30).json()["robot_slots_free"] == free + 1
            )
            kept = _private(base)[0]["id"]
            assert httpx.get(f"{base}/api/health", timeout=30).json()["status"] == "ok"

            # a worker killed: reported on the page and in /api/health, sessions restart (the
            # page frames the scene: that viewer takes the free slot, a private session too)
            page = browser.new_context(viewport=VIEWPORT).new_page()
            page.goto(base + "/")
            worker = httpx.get(f"{base}/api/health", timeout=30).json()["workers"][0]
            os.kill(worker["pid"], signal.SIGKILL)
            health = wait_for(
                lambda: (
                    (h := httpx.get(f"{base}/api/health", timeout=30).json())["worker_deaths"]
                    and h["status"] == "ok"
                    and h
                ),
                timeout=90,
            )
            assert health and f"pid {worker['pid']}" in health["worker_deaths"][0]
            page.locator("#status", has_text="stopped at").wait_for(timeout=30_000)
            assert kept in [s["id"] for s in _private(base)]  # the open browser's session
            assert wait_for(
                lambda: (
                    httpx.get(  # runs on, restarted on the new worker
                        f"{base}/api/sessions/{kept}/state", timeout=30
                    ).json()["robots"][0]["t"]
                    > 1.0
                ),
                timeout=60,
            )
        finally:
            browser.close()
