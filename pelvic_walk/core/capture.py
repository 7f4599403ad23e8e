"""A headless run's frames and plot rows, as a live session keeps them: the frame sink that
``simulate --record``, ``pelvic_walk``'s ``Run.horizon`` and its 3-D player read.

Pass :meth:`Capture.capture` as :func:`~pelvic_walk.core.run.run`'s ``on_tick``: it keeps a
:class:`~pelvic_walk.core.frames.LiveFrame` every ``1 / hz`` of simulated time and a plot row
every :data:`~pelvic_walk.core.frames.HISTORY_DECIMATION` ticks. Plain data only: turning them
into a recording's page is a face's job (``app.web.recording``).
"""

from __future__ import annotations

import numpy as np

from pelvic_walk.core.frames import (
    HISTORY_DECIMATION,
    ROW_COLUMNS,
    LiveFrame,
    TwoStepEnergy,
    plot_row,
    robot_frame,
)
from pelvic_walk.core.session import Session

RECORD_HZ = 20.0  # frames kept per second of simulated time (a recording plays these)


class Capture:
    """Frames at ``hz`` and plot rows at 50 Hz of one robot's headless run."""

    def __init__(self, method: str, hz: float = RECORD_HZ):
        self.method = method
        self.period = 1.0 / hz
        self.frames: list[LiveFrame] = []
        self._rows: list[np.ndarray] = []
        self._ticks = 0
        self._energy = TwoStepEnergy()

    @property
    def rows(self) -> np.ndarray:
        """(n, len(ROW_COLUMNS)) the plot rows so far."""
        return np.array(self._rows).reshape(-1, len(ROW_COLUMNS))

    def capture(self, session: Session) -> None:
        """After every control tick of ``session``."""
        self._ticks += 1
        t = float(session.t)
        if self._ticks % HISTORY_DECIMATION == 0:
            row = plot_row(session, t, self._energy(session))
            if row is not None:
                self._rows.append(row)
        if not self.frames or t - self.frames[-1].clock >= self.period - 1e-9:
            robot = robot_frame(
                session,
                0,
                t,
                self.method,
                int(session.fell),
                0,
                None,
                False,
                None,
                fell_clock=session.fall_time,
            )
            self.frames.append(
                LiveFrame(
                    seq=len(self.frames),
                    clock=t,
                    paused=False,
                    speed=1.0,
                    realtime_factor=None,
                    compute_realtime_factor=None,
                    intent_version=0,
                    steps_done=0,
                    pushes_done=0,
                    robots=(robot,),
                )
            )
