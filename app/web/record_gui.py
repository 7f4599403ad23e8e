"""The Record folder of one view's panel: the last seconds of the session as a zip that plays
back without the server (:mod:`app.web.recording`), downloaded by the browser that asked (a
file saved as any download is, not a link to click).

The recording is made in viser's callback thread from what the session keeps (its frames and
plot rows): the live loop runs on. The slider is bounded by the history a session keeps; if
less is kept when the button is pressed (just after a restart), what is kept is recorded and
the folder says so.
"""

from __future__ import annotations

import html
import time
from typing import TYPE_CHECKING, Any

import viser

from app.live.session import KEEP_S
from app.web import recording

if TYPE_CHECKING:
    from app.web.host import PanelHost

MIN_S = 1.0  # [s] the shortest recording the slider offers
DEFAULT_S = 10.0
BUTTON = "Record and download (.zip)"


class RecordFolder:
    """A length slider, a button and a line that reports the last recording."""

    def __init__(self, gui: Any, panel: PanelHost):
        self.panel = panel
        with gui.add_folder("Record", expand_by_default=False):
            gui.add_markdown(
                "Save the **last seconds** as a zip that plays back **without the server**: "
                "unzip it and open `index.html` in a browser (the 3-D scene, the plots of the "
                "same window as a PNG and their numbers as CSV). Also `GET /api/recording` "
                "and `pelvic-walk simulate ... --record PATH`."
            )
            self.seconds = gui.add_slider(
                "Last [s]",
                MIN_S,
                KEEP_S,
                1.0,
                DEFAULT_S,
                hint=f"A session keeps the last {KEEP_S:g} s (less just after a restart); "
                "while paused, the seconds up to the instant shown.",
            )
            self.button = gui.add_button(BUTTON, icon=viser.Icon.DOWNLOAD)
            self.button.on_click(lambda e: self.record(e.client))
            self.result = gui.add_markdown("")

    def record(self, client: Any) -> bytes | None:
        """Make the recording and send it to ``client`` as a file download; returns the zip,
        or None with the reason shown in the folder."""
        session = self.panel.session
        asked = float(self.seconds.value)
        kept = recording.kept_seconds(session)
        seconds = min(asked, kept)
        if seconds < MIN_S / 2:
            self.result.content = "Nothing to record yet: wait for the robots to start."
            return None
        self.button.disabled = True
        self.button.label = "Recording..."
        self.result.content = (
            f"Drawing {seconds:.0f} s of the scene into a file: this takes a while; the "
            "download starts by itself when it is made."
        )
        t0 = time.perf_counter()
        try:
            rec = recording.from_session(session, seconds)
            data = recording.render(rec, "zip", dict(self.panel.view.scene.layers))
        except (ValueError, recording.RecorderBusy) as exc:
            self.result.content = f"**Not recorded:** {html.escape(str(exc))}"
            return None
        finally:
            self.button.label = BUTTON
            self.button.disabled = False
        made = time.perf_counter() - t0
        if client is not None:  # saved by the browser at once, not offered as a link
            client.send_file_download(f"{rec.name}.zip", data, save_immediately=True)
        short = f" (only {kept:.1f} s were kept)" if asked > kept + recording.SLACK_S else ""
        self.result.content = (
            f"Recorded **{rec.duration:.1f} s** of {len(rec.methods)} robot"
            f"{'s' if len(rec.methods) != 1 else ''}{short}: {len(data) / 1e6:.1f} MB, made "
            f"in {made:.1f} s, downloaded as `{rec.name}.zip` (your browser's downloads)."
        )
        return data
