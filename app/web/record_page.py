"""The pages of a recording a person reads first: ``index.html`` (the scene framed, the plots,
where the numbers are) and ``README.txt``. The scene's colours come from the live page's
legend (:func:`app.web.overlays.legend_html`), so both say the same."""

from __future__ import annotations

import html
import time
from typing import TYPE_CHECKING

from app.web.overlays import legend_html
from pelvic_walk.core.methods import METHOD_INFO

if TYPE_CHECKING:
    from app.web.record_data import Recording

README = """pelvic-walk recording
=====================

Open index.html (double-click): the 3-D scene, the plots and a link to the numbers.
scene.html      the 3-D scene alone (plays in a loop; the bar at the bottom pauses and scrubs)
plots.png       waist yaw, waist rate, yaw momentum, kappa(J) and energy per two steps
timeseries.csv  the numbers behind the plots (one row per robot every 20 ms)
robots.json     every robot's label, strategy and parameters (the settings that differ)

Nothing needs a server or the internet: any recent browser opens the files.
"""


def robot_title(label: str, strategy: str) -> str:
    """How a recording names a robot: its strategy's title, or its label beside it when the
    label is its own ("short (pelvic MPC)")."""
    info = METHOD_INFO.get(strategy)
    name = info.title if info is not None else strategy
    return name if label == strategy else f"{label} ({name})"


def title(rec: Recording) -> str:
    names = " vs ".join(robot_title(m, s) for m, s in rec.strategies.items())
    return f"pelvic-walk recording: {names}, {rec.duration:.1f} s"


def settings_html(rec: Recording) -> str:
    """The robots' settings that differ, one item each (empty when they share them all);
    every parameter of every robot is in robots.json."""
    items = [
        f"<li><b>{html.escape(robot_title(r['label'], r['strategy']))}</b>: "
        + html.escape(", ".join(f"{k} = {v}" for k, v in r["settings"].items()))
        + "</li>"
        for r in rec.robots()
        if r["settings"]
    ]
    if not items:
        return ""
    return "<p>The robots' settings that differ:</p><ul>" + "".join(items) + "</ul>"


def describe(rec: Recording) -> str:
    """What was recorded, in one sentence (the source, the window, the walk)."""
    w = rec.params.walk
    arms = "on" if rec.params.arms.enabled else "off"
    return (
        f"{rec.source}; session clock {rec.start:.2f} to {rec.start + rec.duration:.2f} s; "
        f"step length {w.step_length:.2f} m, step time {w.step_time:.2f} s, arm swing {arms}; "
        f"recorded {time.strftime('%Y-%m-%d %H:%M', time.localtime(rec.created))}"
    )


def index_html(rec: Recording) -> str:
    """The page that opens first: the scene (framed), the plots and where the numbers are."""
    heading = html.escape(title(rec))
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{heading}</title>
<style>body{{font-family:sans-serif;margin:1em auto;max-width:1100px;padding:0 1em}}
iframe{{width:100%;height:62vh;border:1px solid #ccc}} img{{width:100%}}
code{{background:#f3f3f3;padding:0 .2em}}</style></head><body>
<h1>{heading}</h1>
<p>{html.escape(describe(rec))}.</p>
{settings_html(rec)}
<h2>3-D scene</h2>
<iframe src="scene.html" title="3-D scene"></iframe>
{legend_html()}
<p><a href="scene.html">Open the scene on its own</a>. It plays in a loop: the bar at the
bottom pauses (or press space), scrubs and sets the speed; drag to turn the view, scroll to
zoom. The floor moves with the robots, so they stay in view.</p>
<h2>Plots of the same window</h2>
<img src="plots.png" alt="waist yaw, waist rate, yaw momentum, kappa and energy per two steps">
<p>Grey bands: double support. The numbers behind them: <a href="timeseries.csv">
timeseries.csv</a> (one row per robot every 20 ms; <code>rec_t</code> is the time in the
scene's playback bar, <code>clock</code> the session clock, <code>t</code> the robot's own
time; waist in deg and deg/s, yaw momentum in kg m^2/s, energy in J). Every robot's
parameters: <a href="robots.json">robots.json</a>.</p>
<p style="color:#666">Made by pelvic-walk (Park &amp; Park, IEEE Access 2022). Everything
here works offline: no server, no internet.</p>
</body></html>
"""
