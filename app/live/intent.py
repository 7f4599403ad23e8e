"""What the users of a live session want: an immutable :class:`Intent`, replaced as a whole.

Web handlers and GUI callbacks never touch the simulation: they replace the intent (under a
lock, :class:`IntentBox`) and the loop picks it up on its next tick. Requests that must happen
once (a reset, a single step, a push) are counters or numbered entries, so the loop can tell
which ones it has already carried out, and a writer can wait until its own request is done.
"""

from __future__ import annotations

import dataclasses
import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from controller import strategy
from controller.params import ControllerParams
from pelvic_walk.core import robots as robots_
from pelvic_walk.core.robots import Robot

DEFAULT_METHODS: tuple[str, ...] = strategy.BUILTINS  # the paper's three, compared
SPEED_MIN, SPEED_MAX = 0.1, 4.0  # playback speed range (x real time)
STEP_UNTIL = ("tick", "liftoff", "landing")  # what a single step advances to
PUSH_FORCE_MAX = 300.0  # [N] largest horizontal push (about 0.6 body weights)
PUSH_DURATION_MAX = 1.0  # [s]
PUSHES_KEPT = 16  # push requests an intent remembers (the loop carries them out in order)


@dataclass(frozen=True)
class Push:
    """A horizontal push on one robot's torso."""

    number: int  # increases with every push request of the session
    method: str  # the robot
    force: tuple[float, float]  # [N] x, y
    duration: float  # [s]


@dataclass(frozen=True)
class Intent:
    """Everything the users of one live session asked for."""

    params: ControllerParams  # shared by every robot (its ``method`` field is not used)
    # the robots shown: a strategy, its own settings over ``params``, a label (their key)
    robots: tuple[Robot, ...] = robots_.of_methods(DEFAULT_METHODS)
    paused: bool = False
    speed: float = 1.0  # x real time
    step_requests: int = 0  # single steps asked for so far (monotonic)
    step_until: str = "tick"  # what the latest single step advances to (STEP_UNTIL)
    reset_requests: int = 0  # resets asked for so far (monotonic), the automatic ones included
    # of which the session made itself (after a fall was shown, or at the end of the plans):
    # they keep the plots and the kept frames, so a fall can be scrubbed back to
    auto_restarts: int = 0
    pushes: tuple[Push, ...] = ()  # the latest push requests, oldest first
    # The session's time base, shared by every loop running part of it (they may sit in
    # different worker processes): session clock ``anchor[1]`` [s] at monotonic wall time
    # ``anchor[0]`` [s]; while running the clock is anchor[1] + (now - anchor[0]) * speed.
    anchor: tuple[float, float] = (0.0, 0.0)
    start_clock: float = 0.0  # [s] robots (re)built by a reset start walking at this clock
    version: int = 0  # bumped on every change

    @property
    def methods(self) -> tuple[str, ...]:
        """The robots' keys (labels), in their order: what frames, plots and pushes name."""
        return tuple(r.key for r in self.robots)

    def robot(self, key: str) -> Robot:
        """The robot ``key``; ValueError naming the robots shown otherwise."""
        for r in self.robots:
            if r.key == key:
                return r
        raise ValueError(f"no robot {key!r} is shown (robots: {', '.join(self.methods)})")

    def params_of(self, key: str) -> ControllerParams:
        """Robot ``key``'s parameters: the shared ones with its own settings on top."""
        return robots_.params_of(self.params, self.robot(key))


def check_methods(methods: Sequence[str]) -> tuple[str, ...]:
    """Validated, de-duplicated robots (registered strategies) in the registry's order (the
    paper's three first); ValueError otherwise."""
    methods = tuple(methods)
    bad = [m for m in methods if not strategy.is_registered(m)]
    if bad:
        raise ValueError(f"unknown method {bad[0]!r}: choose from {', '.join(strategy.names())}")
    if not methods:
        raise ValueError("choose at least one method")
    return strategy.ordered(methods)


def check_speed(speed: float) -> float:
    speed = float(speed)
    if not math.isfinite(speed) or not SPEED_MIN <= speed <= SPEED_MAX:
        raise ValueError(f"speed must be between {SPEED_MIN} and {SPEED_MAX}, got {speed}")
    return speed


def check_push(
    method: str, force: Sequence[float], duration: float, methods: Sequence[str]
) -> tuple[tuple[float, float], float]:
    """Validated (force, duration) of a push on a robot shown now; ValueError otherwise."""
    if method not in methods:
        raise ValueError(f"no robot {method!r} is shown (robots: {', '.join(methods)})")
    fx, fy = (float(f) for f in force)
    if not (math.isfinite(fx) and math.isfinite(fy)):
        raise ValueError("force must be finite")
    size = math.hypot(fx, fy)
    if size > PUSH_FORCE_MAX:
        raise ValueError(f"a push of {size:.0f} N is above the maximum {PUSH_FORCE_MAX:.0f} N")
    duration = float(duration)
    if not (math.isfinite(duration) and 0.0 < duration <= PUSH_DURATION_MAX):
        raise ValueError(f"duration must be in (0, {PUSH_DURATION_MAX}] s, got {duration}")
    return (fx, fy), duration


class IntentBox:
    """The current intent of one session, replaced atomically (any thread)."""

    def __init__(self, intent: Intent, on_change: Callable[[], None] | None = None):
        self._lock = threading.Lock()
        self._intent = intent
        self._on_change = on_change

    def get(self) -> Intent:
        with self._lock:
            return self._intent

    def modify(self, changes_of: Callable[[Intent], dict]) -> Intent:
        """Read, change and write the intent atomically (concurrent writers lose nothing).

        ``changes_of`` maps the current intent to the fields to replace; it may raise
        ValueError, and then nothing changes. Returns the new intent.
        """
        with self._lock:
            cur = self._intent
            new = dataclasses.replace(cur, version=cur.version + 1, **changes_of(cur))
            self._intent = new
        if self._on_change is not None:
            self._on_change()
        return new
