"""What a live session keeps of its past, on the display side: plot rows and kept frames.

- :class:`PlotHistory`: the metric rows the loop records every ``HISTORY_DECIMATION`` ticks
  (50 Hz) and sends along with its frames, one rolling window per robot, for the live plots.
- :class:`FrameStore`: the last ``keep_s`` seconds of published frames (display rate), for
  pausing and scrubbing back (scene, horizon inspector, plot cursor) and for recordings.

Both are bounded: memory never grows with the session's run time.
"""

from __future__ import annotations

import bisect
import threading
from collections import deque
from dataclasses import dataclass

import numpy as np

from pelvic_walk.core.frames import HISTORY_DECIMATION, ROW_COLUMNS, LiveFrame

__all__ = ["HISTORY_DECIMATION", "ROW_COLUMNS", "FrameStore", "PlotHistory", "PlotWindow"]

COL = {name: i for i, name in enumerate(ROW_COLUMNS)}


@dataclass(frozen=True)
class PlotWindow:
    """A snapshot of the plot rows: one (n, len(ROW_COLUMNS)) array per robot."""

    rows: dict[str, np.ndarray]

    def column(self, method: str, name: str) -> np.ndarray:
        arr = self.rows.get(method)
        return arr[:, COL[name]] if arr is not None else np.zeros(0)


class PlotHistory:
    """Rolling window of plot rows per robot (any thread; the receiver appends)."""

    def __init__(self, seconds: float = 60.0, rate_hz: float = 50.0):
        self.capacity = max(10, int(seconds * rate_hz))
        self.seconds = seconds
        self._lock = threading.Lock()
        self._rows: dict[str, deque[np.ndarray]] = {}

    def clear(self) -> None:
        with self._lock:
            self._rows = {}

    def extend(self, rows: dict[str, np.ndarray]) -> None:
        """Append new rows ((k, len(ROW_COLUMNS)) per robot)."""
        with self._lock:
            for method, arr in rows.items():
                ring = self._rows.setdefault(method, deque(maxlen=self.capacity))
                ring.extend(arr)

    def window(self, seconds: float | None = None, until: float | None = None) -> PlotWindow:
        """Rows of the last ``seconds`` up to session clock ``until`` (default: the newest)."""
        with self._lock:
            rows = {m: np.array(r) for m, r in self._rows.items() if r}
        out = {}
        for m, arr in rows.items():
            clock = arr[:, 0]
            end = clock[-1] if until is None else until
            keep = clock <= end + 1e-9
            if seconds is not None:
                keep &= clock >= end - seconds
            out[m] = arr[keep]
        return PlotWindow(out)


class FrameStore:
    """The last ``keep_s`` seconds of frames, by session clock (any thread)."""

    def __init__(self, keep_s: float = 40.0):
        self.keep_s = keep_s
        self._lock = threading.Lock()
        self._clocks: list[float] = []
        self._frames: list[LiveFrame] = []

    def clear(self) -> None:
        with self._lock:
            self._clocks, self._frames = [], []

    def add(self, frame: LiveFrame) -> None:
        with self._lock:
            if self._clocks and frame.clock < self._clocks[-1]:
                self._clocks, self._frames = [], []  # a new session clock
            if self._clocks and frame.clock == self._clocks[-1]:
                self._frames[-1] = frame  # the same instant (e.g. an intent applied paused)
            else:
                self._clocks.append(frame.clock)
                self._frames.append(frame)
            cut = bisect.bisect_left(self._clocks, frame.clock - self.keep_s)
            if cut > 0:
                del self._clocks[:cut], self._frames[:cut]

    def span(self) -> tuple[float, float] | None:
        """(oldest, newest) session clock kept, or None."""
        with self._lock:
            return (self._clocks[0], self._clocks[-1]) if self._clocks else None

    def nearest(self, clock: float) -> LiveFrame | None:
        """The kept frame nearest to ``clock``."""
        with self._lock:
            if not self._clocks:
                return None
            i = bisect.bisect_left(self._clocks, clock)
            if i == len(self._clocks) or (
                i > 0 and clock - self._clocks[i - 1] <= self._clocks[i] - clock
            ):
                i -= 1
            return self._frames[i]

    def between(self, start: float, end: float) -> list[LiveFrame]:
        """Kept frames with start <= clock <= end, oldest first."""
        with self._lock:
            a = bisect.bisect_left(self._clocks, start)
            b = bisect.bisect_right(self._clocks, end)
            return self._frames[a:b]

    def __len__(self) -> int:
        with self._lock:
            return len(self._frames)

    def nbytes(self) -> int:
        """Approximate memory of the kept frames' arrays [bytes] (plans and params shared)."""
        with self._lock:
            frames = list(self._frames)
        return sum(frame_nbytes(f) for f in frames)


def frame_nbytes(frame: LiveFrame) -> int:
    """Bytes of a frame's own arrays (what keeping it costs)."""
    total = 0
    for r in frame.robots:
        for value in vars(r).values():
            if isinstance(value, np.ndarray):
                total += value.nbytes
        if r.horizon is not None:
            total += sum(v.nbytes for v in vars(r.horizon).values() if isinstance(v, np.ndarray))
    return total + sum(a.nbytes for a in frame.rows.values())
