"""Recordings that play back without the server: the 3-D scene, the plots and the numbers.

A :class:`~app.web.record_data.Recording` is a list of published :class:`~app.live.LiveFrame`
objects and the plot rows of the same window (``app.live.history.ROW_COLUMNS``). It is made
from what a live session already keeps in the web process (:func:`from_session`: its
FrameStore and plot history; the simulation is never paused or stepped for it) or captured
during a headless run (:func:`of_capture`: the core's frame sink, ``pelvic-walk simulate ...
--record PATH``).

It is written as (:func:`package`):

- ``scene.html``: the scene as the live page draws it (:class:`~app.web.scene.SceneView`),
  recorded by viser's scene serializer with one sleep per frame and embedded, with viser's
  client taken from the installed package at record time, in one self-contained page (no
  server, no internet: the client build inlines its scripts, styles and assets);
- ``timeseries.csv``: the plot rows of every robot (one tidy table);
- ``plots.png``: the live plots of the same window (matplotlib; viser recordings drop GUI
  plots), drawn by :mod:`app.web.record_plots`;
- ``robots.json``: every robot's label, strategy and parameters (its own settings included);
- ``index.html``: a page that shows them together, and ``README.txt``
  (:mod:`app.web.record_page`).

Scenes are drawn into one viser server of this process that nobody connects to (bound to
127.0.0.1 on a free port), one recording at a time.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import html
import io
import json
import math
import threading
import zipfile
from collections.abc import Sequence
from pathlib import Path

from app.live.history import ROW_COLUMNS
from app.live.session import KEEP_S, SessionView
from app.web.record_data import Recording
from app.web.record_page import README, index_html, title
from pelvic_walk.core.capture import RECORD_HZ, Capture
from pelvic_walk.core.frames import LiveFrame

FORMATS = ("zip", "html", "csv", "png")  # what GET /api/recording can return
MEDIA_TYPES = {"zip": "application/zip", "html": "text/html", "csv": "text/csv", "png": "image/png"}
BUSY_WAIT_S = 20.0  # [s] a recording waits this long for the one being made, then gives up
SLACK_S = 0.1  # [s] a request this much longer than what is kept is still granted


class RecorderBusy(RuntimeError):
    """Another recording is being drawn for too long (the caller may try again)."""


def decimate(frames: Sequence[LiveFrame], hz: float = RECORD_HZ) -> tuple[LiveFrame, ...]:
    """Frames at least 1/hz of simulated time apart, the newest always kept."""
    kept: list[LiveFrame] = []
    for f in frames:
        if not kept or f.clock - kept[-1].clock >= 1.0 / hz - 1e-9:
            kept.append(f)
    if frames and kept[-1] is not frames[-1]:
        kept.append(frames[-1])
    return tuple(kept)


def check_seconds(seconds: float, kept: float) -> None:
    """ValueError with a readable message unless 0 < seconds <= what is kept [s]."""
    if not math.isfinite(seconds) or seconds <= 0:
        raise ValueError(f"seconds must be a positive number, got {seconds}")
    if seconds > kept + SLACK_S:
        raise ValueError(
            f"only {kept:.1f} s of this session are kept now (at most {KEEP_S:g} s; less "
            f"after a restart): ask for at most that, got {seconds:g} s"
        )


def _kept_window(session: SessionView) -> tuple[float, float] | None:
    """(oldest kept, shown) session clock: what a recording may cover now, or None."""
    shown = session.shown_frame()
    span = session.frames.span()
    if shown is None or span is None:
        return None
    return span[0], min(shown.clock, span[1])


def kept_seconds(session: SessionView) -> float:
    """[s] the longest recording the session can make now (up to the instant shown)."""
    window = _kept_window(session)
    return window[1] - window[0] if window else 0.0


def from_session(session: SessionView, seconds: float) -> Recording:
    """The last ``seconds`` up to the instant shown (the present, or the sought one while
    paused), from the session's kept frames and plot rows; ValueError if that much is not
    kept. Only reads what the displays read: the live loop runs on undisturbed."""
    window = _kept_window(session)
    if window is None:
        raise ValueError("nothing is kept yet: wait for the robots to start")
    end = window[1]
    check_seconds(seconds, end - window[0])
    frames = session.frames.between(end - seconds, end)
    if not frames:
        raise ValueError("nothing is kept in that window")
    methods = tuple(r.method for r in frames[-1].robots)
    frames = [f for f in frames if tuple(r.method for r in f.robots) == methods]
    start = frames[0].clock
    plots = session.history.window(end - start, until=end)
    rows = {m: plots.rows[m] for m in methods if m in plots.rows}
    return Recording(decimate(frames), rows, "live session")


def of_capture(capture: Capture, source: str) -> Recording:
    """The recording of a headless run's :class:`~pelvic_walk.core.capture.Capture`."""
    if not capture.frames:
        raise ValueError("the run produced no frame")
    return Recording(tuple(capture.frames), {capture.method: capture.rows}, source)


# -- the scene ------------------------------------------------------------------------------
_lock = threading.Lock()
_server = None
_model = None


def _recorder():
    """The viser server scenes are drawn into (created on first use; quiet)."""
    global _server, _model
    if _server is None:
        import mujoco
        import viser

        from models.dyros_jet import SCENE_XML

        with contextlib.redirect_stdout(io.StringIO()):  # viser prints a banner
            _server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
        _model = mujoco.MjModel.from_xml_path(str(SCENE_XML))  # only read for its shapes
    return _server, _model


def shutdown() -> None:
    """Stop the recorder's viser server (quietly), if one was started."""
    global _server
    with _lock:
        if _server is not None:
            with contextlib.redirect_stdout(io.StringIO()):
                _server.stop()
            _server = None


def scene_html(rec: Recording, layers: dict[str, bool] | None = None) -> str:
    """The recorded scene as one self-contained HTML page (viser's client and the data).

    Raises:
        RecorderBusy: another recording took the recorder longer than BUSY_WAIT_S.
    """
    from app.web.camera import camera_pose
    from app.web.scene import SceneView, stagger_x

    if not _lock.acquire(timeout=BUSY_WAIT_S):
        raise RecorderBusy("another recording is being made: try again in a moment")
    try:
        server, model = _recorder()
        server.scene.reset()
        view = SceneView(server, model)
        for key, on in (layers or {}).items():
            if key in view.layers:
                view.set_layer(key, on)
        # fitted for the widest stagger of the recording (a robot lying where it fell)
        stagger = max(stagger_x(f.robots) for f in rec.frames if f.robots)
        pos, look, up, fov = camera_pose("follow", len(rec.methods), 16 / 9, False, stagger)
        server.initial_camera.position = tuple(pos)
        server.initial_camera.look_at = tuple(look)
        server.initial_camera.up = up
        server.initial_camera.fov = fov
        serializer = server.get_scene_serializer()
        try:
            previous = None
            for frame in rec.frames:
                if previous is not None:
                    serializer.insert_sleep(max(frame.clock - previous, 0.0))
                previous = frame.clock
                # drawn as if paused: every frame refreshes the overlays and labels and the
                # world follows the robots exactly (no smoothing over wall time)
                view.draw(dataclasses.replace(frame, paused=True))
            serializer.insert_sleep(1.0 / RECORD_HZ)
            page = serializer.as_html()
        except BaseException:
            serializer.serialize()  # unregister it: it would record every later message
            raise
        server.scene.reset()
    finally:
        _lock.release()
    title_tag = f"<title>{html.escape(title(rec))}</title>"
    return page.replace("<title>Viser</title>", title_tag, 1)


# -- numbers and plots ----------------------------------------------------------------------
def timeseries_csv(rec: Recording) -> str:
    """The plot rows of every robot: ``method`` (its label), ``rec_t`` (seconds into the
    recording, as the scene's playback bar) and ROW_COLUMNS."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(("method", "rec_t", *ROW_COLUMNS))
    for method, rows in rec.rows.items():
        for row in rows:
            w.writerow((method, f"{row[0] - rec.start:.4f}", *(_num(v) for v in row)))
    return out.getvalue()


def _num(v: float) -> str:
    return "" if not math.isfinite(v) else f"{v:.6g}"


def package(rec: Recording, layers: dict[str, bool] | None = None) -> dict[str, bytes]:
    """Every file of a recording, by name."""
    from app.web.record_plots import plots_png

    return {
        "index.html": index_html(rec).encode(),
        "scene.html": scene_html(rec, layers).encode(),
        "plots.png": plots_png(rec),
        "timeseries.csv": timeseries_csv(rec).encode(),
        "robots.json": robots_json(rec).encode(),
        "README.txt": README.encode(),
    }


def robots_json(rec: Recording) -> str:
    """Every robot of the recording: its label (the ``method`` of timeseries.csv), strategy,
    the settings that differ and all of its parameters in force."""
    return json.dumps(
        {
            "source": rec.source,
            "start": rec.start,
            "duration": rec.duration,
            "robots": rec.robots(),
        },
        indent=1,
        default=str,
    )


def render(rec: Recording, fmt: str, layers: dict[str, bool] | None = None) -> bytes:
    """One format of :data:`FORMATS`: the zip of everything, or one of its files."""
    from app.web.record_plots import plots_png

    if fmt == "zip":
        return zip_bytes(rec.name, package(rec, layers))
    if fmt == "html":
        return scene_html(rec, layers).encode()
    if fmt == "csv":
        return timeseries_csv(rec).encode()
    if fmt == "png":
        return plots_png(rec)
    raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")


def zip_bytes(folder: str, files: dict[str, bytes]) -> bytes:
    """A zip holding one folder with ``files`` (extracting it gives that folder)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in files.items():  # (the scene's data is zstd already: -20 % here)
            z.writestr(f"{folder}/{name}", data)
    return buf.getvalue()


def write(rec: Recording, path: Path) -> Path:
    """Write a recording: ``path`` ending in ``.zip`` gets the zip, else a folder of files."""
    files = package(rec)
    if path.suffix.lower() == ".zip":
        path.write_bytes(zip_bytes(path.stem, files))
    else:
        path.mkdir(parents=True, exist_ok=True)
        for name, data in files.items():
            (path / name).write_bytes(data)
    return path
