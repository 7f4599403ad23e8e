"""The live simulation of the web tool: one owner of the loop, intent in, frames out
(docs/ARCHITECTURE.md, "Principles").

- ``intent``: what users ask for (:class:`Intent`), replaced atomically by callbacks;
- ``loop``: :class:`LiveLoop` ticks the robots, paces them, publishes frames (no display code);
- the immutable :class:`LiveFrame` / :class:`RobotFrame` the displays draw are the core's
  (``pelvic_walk.core.frames``: plain data a headless run captures too);
- ``history``: plot rows and kept frames, bounded (pause, scrub, record);
- ``session``: :class:`SessionView`, a session's display side, with the waits the API needs;
- ``pool``: :class:`WorkerPool`, the one live mode: the robots run in workers (processes, or
  threads of this process: ``engines``), one part per robot, their frames merged.
"""

from app.live.intent import SPEED_MAX, SPEED_MIN, Intent, check_methods
from app.live.loop import LIVE_STEPS, live_params
from app.live.session import FALL_HOLD_S, Playback, SessionView
from pelvic_walk.core.frames import Horizon, LiveFrame, RobotFrame

__all__ = [
    "FALL_HOLD_S",
    "LIVE_STEPS",
    "SPEED_MAX",
    "SPEED_MIN",
    "Horizon",
    "Intent",
    "LiveFrame",
    "Playback",
    "RobotFrame",
    "SessionView",
    "check_methods",
    "live_params",
]
