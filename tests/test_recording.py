"""Recordings (app/web/recording.py): from a live session through ``GET /api/recording`` and
the Record folder, from a headless run through ``simulate --record``; bad input gets a 422
(or exit 2) and the live loop runs on. The real-browser playback is test_browser_recording.py.
"""

from __future__ import annotations

import csv
import io
import math
import zipfile
from types import SimpleNamespace

import pytest

from app.cli import main
from app.live.history import ROW_COLUMNS
from app.live.session import SessionView
from app.web import recording
from app.web.recording import check_seconds, decimate, kept_seconds

FILES = {"index.html", "scene.html", "timeseries.csv", "plots.png", "robots.json", "README.txt"}


LIVE_SESSION = {"methods": ["mpc"], "speed": 4.0}  # one robot at 4x: seconds are kept quickly
APP_OPTIONS = {"viser_port": 18767}


@pytest.fixture(scope="module", autouse=True)
def _recorders_stopped():
    """The recorders' threads end with the module."""
    yield
    recording.shutdown()


def _keep_at_least(live: SessionView, seconds: float) -> None:
    """Wait until ``seconds`` of frames and of plot rows are kept (the robots plot nothing
    while they stand by to start)."""

    def rows_kept() -> float:
        clock = live.history.window().column("mpc", "clock")
        return float(clock[-1] - clock[0]) if len(clock) else 0.0

    frame = live.frame()
    while kept_seconds(live) < seconds or rows_kept() < seconds:
        frame = live.wait_frame(frame.seq, timeout=30)
        assert frame is not None, "the live simulation stopped publishing"


def _frame_gap(live: SessionView) -> float:
    """[s] the largest gap in simulated time between two kept frames: a window starts at its
    first kept frame, up to that much after the window's start (frames come at the display rate
    in wall time, so a loop slowed by the machine's other jobs keeps them further apart)."""
    kept = [f.clock for f in live.frames.between(-math.inf, math.inf)]
    return max((b - a for a, b in zip(kept[:-1], kept[1:], strict=True)), default=0.0)


def _still_running(live: SessionView) -> None:
    frame = live.frame()
    for _ in range(3):
        frame = live.wait_frame(frame.seq, timeout=30)
        assert frame is not None
    assert live.running and live.error is None and not live.intent.paused


def test_check_seconds_says_what_is_wrong():
    check_seconds(5.0, 5.0)
    check_seconds(5.05, 5.0)  # within the slack of one display frame or two
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="positive"):
            check_seconds(bad, 5.0)
    with pytest.raises(ValueError, match=r"only 5\.0 s .* kept"):
        check_seconds(6.0, 5.0)


def test_decimate_keeps_the_rate_and_the_newest():
    frames = [SimpleNamespace(clock=0.01 * i) for i in range(101)]  # 100 Hz, 1 s
    kept = decimate(frames, hz=20.0)
    gaps = [b.clock - a.clock for a, b in zip(kept[:-1], kept[1:], strict=True)]
    assert min(gaps) >= 0.05 - 1e-9 and kept[0] is frames[0] and kept[-1] is frames[-1]
    assert len(kept) == 21


BAD = {
    "zero": ("seconds=0", "positive"),
    "negative": ("seconds=-2", "positive"),
    "NaN": ("seconds=nan", "positive"),
    "not a number": ("seconds=ten", "seconds"),
    "beyond the kept history": ("seconds=1000", "kept"),
    "unknown format": ("seconds=1&format=gif", "format must be one of zip, html, csv, png"),
}


@pytest.mark.parametrize("query", BAD.values(), ids=BAD.keys())
def test_bad_requests_get_422_with_a_message(client, live, query):
    params, words = query
    for prefix in ("/api", "/api/sessions/shared"):
        r = client.get(f"{prefix}/recording?{params}")
        assert r.status_code == 422, r.text
        assert words in r.json()["detail"]
    _still_running(live)


def test_csv_and_png_of_the_last_seconds(client, live):
    _keep_at_least(live, 2.5)
    r = client.get("/api/recording?seconds=2&format=csv")
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("text/csv")
    assert "attachment" in r.headers["content-disposition"]
    rows = list(csv.reader(io.StringIO(r.text)))
    assert rows[0] == ["method", "rec_t", *ROW_COLUMNS]
    body = rows[1:]
    assert {row[0] for row in body} == {"mpc"}
    rec_t = [float(row[1]) for row in body]
    clock = [float(row[2]) for row in body]
    t = [float(row[3]) for row in body]  # the robot's own time
    assert ROW_COLUMNS[:2] == ("clock", "t")
    # the window starts at the first kept frame in it (frames come at the display rate, a
    # few per simulated second at 4x), the plot rows at 50 Hz from there to its end. The
    # plans here are short: when one ends the robots restart together, and a robot standing by
    # to start plots nothing (its time then goes back), wherever the window happens to lie.
    start = clock[0] - rec_t[0]
    assert rec_t[0] <= 0.02 + 1e-6 or t[0] <= rec_t[0] + 1e-6  # or it started in the window
    for i in range(1, len(body)):
        assert clock[i] - clock[i - 1] == pytest.approx(0.02, abs=1e-6) or t[i] < t[i - 1], i
    restarted_at_end = any(  # the last frame in the window shows it restarted, standing
        r.t < t[-1] for f in live.frames.between(clock[-1], start + 2.0) for r in f.robots
    )
    assert 2.0 - _frame_gap(live) - 0.05 <= rec_t[-1] or restarted_at_end
    assert rec_t[-1] <= 2.05
    r = client.get("/api/recording?seconds=1&format=png")
    assert r.status_code == 200 and r.content.startswith(b"\x89PNG\r\n\x1a\n")
    _still_running(live)


def test_zip_and_html(client, live):
    _keep_at_least(live, 1.5)
    r = client.get("/api/recording?seconds=1.5")  # zip is the default
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "application/zip"
    with zipfile.ZipFile(io.BytesIO(r.content)) as z:
        names = z.namelist()
        folder = names[0].split("/")[0]
        assert {n.split("/", 1)[1] for n in names} == FILES and folder.startswith("pelvic-walk")
        index = z.read(f"{folder}/index.html").decode()
        scene = z.read(f"{folder}/scene.html").decode()
    for name in ("scene.html", "plots.png", "timeseries.csv"):
        assert name in index
    assert "__VISER_EMBED_DATA__" in scene and "pelvic-walk recording" in scene
    r = client.get("/api/sessions/shared/recording?seconds=0.5&format=html")
    assert r.status_code == 200 and "__VISER_EMBED_DATA__" in r.text
    rec = recording.from_session(live, 1.0)
    # from the first kept frame in the last second to the last (_frame_gap)
    assert rec.methods == ("mpc",) and 1.0 - _frame_gap(live) - 1e-9 <= rec.duration <= 1.0 + 1e-9
    assert len(rec.frames) >= 2
    _still_running(live)


def test_the_record_folder_downloads_the_zip(live):
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        _keep_at_least(live, 2.0)
        view = SimpleNamespace(scene=SimpleNamespace(layers={"labels": False}))
        from app.web.record_gui import RecordFolder

        folder = RecordFolder(server.gui, SimpleNamespace(session=live, view=view))
        folder.seconds.value = 1000.0  # beyond what is kept (40 s max; the slider clamps)
        sent = []
        data = folder.record(
            SimpleNamespace(send_file_download=lambda *a, **kw: sent.append((a, kw)))
        )
        assert data is not None and data.startswith(b"PK")
        (name, payload), kw = sent[0]
        assert name.endswith(".zip") and payload == data
        assert kw == {"save_immediately": True}  # a file download, not a link in a toast
        assert "Recorded" in folder.result.content and "were kept" in folder.result.content
        assert not folder.button.disabled
    finally:
        server.stop()
    _still_running(live)


def test_simulate_record_writes_the_whole_run(tmp_path, capsys):
    """To a folder here (the browser test records a zip)."""
    out = tmp_path / "walk"
    args = ["simulate", "--method", "fixed", "--step-length", "0.2", "--steps", "1"]
    assert main([*args, "--step-time", "0.8", "--record", str(out)]) == 0
    assert "recording:" in capsys.readouterr().out
    assert {p.name for p in out.iterdir()} == FILES
    rows = list(csv.reader(io.StringIO((out / "timeseries.csv").read_text())))
    assert rows[0] == ["method", "rec_t", *ROW_COLUMNS]
    clock = [float(r[2]) for r in rows[1:]]
    assert {r[0] for r in rows[1:]} == {"fixed"}
    assert len(clock) == pytest.approx(clock[-1] * 50, abs=2)  # 50 Hz from the first tick
    assert max(int(float(r[ROW_COLUMNS.index("step_index") + 2])) for r in rows[1:]) >= 1


@pytest.mark.parametrize(
    "where, says",
    [("missing/walk.zip", "does not exist"), ("afile", "is a file, not a folder")],
)
def test_simulate_record_bad_path_exits_2(tmp_path, capsys, where, says):
    (tmp_path / "afile").write_text("x")
    args = ["simulate", "--method", "fixed", "--step-length", "0.2", "--steps", "1"]
    assert main([*args, "--record", str(tmp_path / where)]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1 and "--record" in err
