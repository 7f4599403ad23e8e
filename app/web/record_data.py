"""What a recording holds: the scene's frames and the plot rows of one window of simulated
time (:class:`Recording`). :mod:`app.web.recording` makes and writes recordings;
:mod:`app.web.record_page` and :mod:`app.web.record_plots` draw their page and plots.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from controller.params import ControllerParams
from pelvic_walk.core.frames import LiveFrame


@dataclass(frozen=True)
class Recording:
    """Frames of the scene and plot rows of one window of simulated time."""

    frames: tuple[LiveFrame, ...]  # oldest first, at most RECORD_HZ per simulated second
    rows: dict[str, np.ndarray]  # method -> (n, len(ROW_COLUMNS)) plot rows of the window
    source: str  # what was recorded, for the page ("live session", "simulate ...")
    created: float = field(default_factory=time.time)

    @property
    def methods(self) -> tuple[str, ...]:
        return tuple(r.method for r in self.frames[-1].robots)

    @property
    def start(self) -> float:
        return self.frames[0].clock

    @property
    def duration(self) -> float:
        return self.frames[-1].clock - self.frames[0].clock

    @property
    def params(self) -> ControllerParams:
        return self.frames[-1].robots[0].params

    @property
    def name(self) -> str:
        """A file name stem: ``pelvic-walk-recording-YYYYmmdd-HHMMSS``."""
        stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(self.created))
        return f"pelvic-walk-recording-{stamp}"
