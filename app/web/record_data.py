"""What a recording holds: the scene's frames and the plot rows of one window of simulated
time (:class:`Recording`). :mod:`app.web.recording` makes and writes recordings;
:mod:`app.web.record_page` and :mod:`app.web.record_plots` draw their page and plots.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controller.params import GROUPS, ControllerParams
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
        """The robots' labels (their keys), in their order."""
        return tuple(r.method for r in self.frames[-1].robots)

    @property
    def strategies(self) -> dict[str, str]:
        """Robot label -> the strategy it runs (two robots may run one)."""
        return {r.method: r.strategy for r in self.frames[-1].robots}

    def robots(self) -> list[dict[str, Any]]:
        """Every robot: ``label``, ``strategy``, ``settings`` (its parameters that not every
        robot shares, by dotted name) and ``params`` (all of its parameters in force, by
        dotted name, its strategy's own included)."""
        tables = {r.method: flat_params(r.params) for r in self.frames[-1].robots}
        keys = sorted({k for t in tables.values() for k in t})
        differ = [k for k in keys if len({repr(t.get(k)) for t in tables.values()}) > 1]
        return [
            {
                "label": label,
                "strategy": self.strategies[label],
                "settings": {k: t[k] for k in differ if k in t},
                "params": t,
            }
            for label, t in tables.items()
        ]

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


def flat_params(params: ControllerParams) -> dict[str, Any]:
    """Every parameter by dotted name (``walk.step_length``; a strategy's own set away from
    its default, ``gain.k``), the strategy left out (it is the robot's)."""
    out = {f"{g}.{k}": v for g in GROUPS for k, v in vars(getattr(params, g)).items()}
    out.update(dict(params.own))
    return out
