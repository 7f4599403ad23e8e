"""Moved to :mod:`app.live` (kept while the web modules move over)."""

from app.live import *  # noqa: F403
from app.live import FALL_RESET_S, SPEED_MAX, SPEED_MIN, LiveFrame, LiveSim  # noqa: F401
from app.live.history import ROW_COLUMNS as HISTORY_COLUMNS  # noqa: F401
