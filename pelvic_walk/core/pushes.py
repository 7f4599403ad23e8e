"""The push study: how hard a sideways shove each method survives (``pelvic-walk push-study``).

One run walks a short plan headless (the same :class:`~pelvic_walk.core.session.Session` as
``simulate`` and the live tool) and applies a horizontal force to the torso for a short time
at the middle of one step's single support, through the world's push (MuJoCo
``xfrc_applied``). The run *recovers* when the robot has not fallen by the end of the plan.

What the controller can do about a push is limited, and that is the lesson: the CoM MPC keeps
its plan (its ZMP inside the support foot) and eq. (19) moves the pelvis to bring the measured
CoM back onto the planned one, but nothing moves the footsteps (no step adjustment), so the
push must be absorbed inside the planned footholds. :func:`largest_survived` bisects the
force between a push that is survived and one that is not; falls are not strictly monotonic in
the force, so the figure is the edge the bisection found, stated with its resolution.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from controller import strategy
from controller.footsteps import LEFT
from controller.params import ControllerParams
from pelvic_walk.core.run import run
from pelvic_walk.core.session import RunConfig, Session

DIRECTIONS = {"left": (0.0, 1.0), "right": (0.0, -1.0), "forward": (1.0, 0.0), "back": (-1.0, 0.0)}
PUSH_STEP = 2  # the pushed step: the third, past the start-up step, in steady walking
N_STEPS = 5  # a short plan: two steps after the pushed one show whether the robot recovered
F_HIGH = 400.0  # [N] upper end of the bisection (the live tool's maximum is 300 N)
F_RESOLUTION = 10.0  # [N] the bisection stops when survived and failed are this close


@dataclass(frozen=True)
class PushOutcome:
    """One pushed run."""

    method: str
    step_length: float  # [m]
    force: float  # [N] size of the push
    direction: str  # left / right / forward / back
    duration: float  # [s]
    push_time: float  # [s] when the push started (mid-SSP of the pushed step)
    support: str  # the foot the robot stood on when pushed
    com_speed_change: float  # [m/s] CoM velocity along the push, over the push
    recovered: bool  # no fall until the end of the plan
    fall_time: float | None  # [s]
    fall_reason: str | None
    steps_completed: int
    error: str | None = None  # the pelvis strategy stopped the walk (its file and line)


def run_push(
    method: str,
    step_length: float,
    force: float,
    direction: str = "left",
    duration: float = 0.1,
    step: int = PUSH_STEP,
    n_steps: int = N_STEPS,
    params: ControllerParams | None = None,
    phase: float = 0.5,
) -> PushOutcome:
    """Walk ``n_steps`` of ``step_length`` and push the torso ``force`` N toward ``direction``
    for ``duration`` s from ``phase`` of step ``step``'s single support (0.5: its middle)."""
    strategy.info(method)  # ValueError naming the choices
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {direction!r}")
    if not (math.isfinite(force) and force >= 0.0):
        raise ValueError(f"force must be a finite number >= 0, got {force}")
    if not (math.isfinite(duration) and duration > 0.0):
        raise ValueError(f"duration must be > 0 s, got {duration}")
    if not 0 <= step < n_steps:
        raise ValueError(f"the pushed step must be in 0..{n_steps - 1}, got {step}")
    if not (math.isfinite(phase) and 0.0 <= phase <= 1.0):
        raise ValueError(f"phase must be within 0..1 of the single support, got {phase}")
    base = params or ControllerParams()
    p = base.replace(method=method, walk={"step_length": step_length, "n_steps": n_steps})
    along = np.array(DIRECTIONS[direction])
    dt = p.control_dt
    speeds: dict[str, float] = {}
    when: dict[str, float] = {}  # the push's time, from the run's own plan

    def push_time(session: Session) -> float:
        if not when:
            plan = session.plan
            lift, land = float(plan.liftoff_times()[step]), float(plan.landing_times()[step])
            when["t"] = lift + phase * (land - lift)  # phase of the single support (0.5: middle)
        return when["t"]

    def com_speed(session: Session) -> float:  # the whole body's CoM velocity along the push
        world = session.world
        mujoco.mj_subtreeVel(world.model, world.data)  # MuJoCo's step leaves it stale
        return float(world.data.subtree_linvel[world.root_id][:2] @ along)

    def shove(session: Session) -> None:
        # The push acts from the next control period on: start it on the tick that ends
        # closest to mid-SSP.
        if "before" not in speeds and session.t + 0.5 * dt >= push_time(session):
            speeds["before"] = com_speed(session)
            session.push(force * along, duration)

    def after(session: Session) -> None:
        if "before" in speeds and "after" not in speeds and not session.world.pushing:
            speeds["after"] = com_speed(session)

    # a fall ends the trial at once (the outcome is the fall)
    session = run(RunConfig(params=p), before_tick=shove, on_tick=after, stop=lambda s: s.fell)
    plan = session.plan
    support = "right" if int(plan.swing_side[step]) == LEFT else "left"
    summary_steps = int(sum(1 for k in session.landings if k < plan.n_walking_steps))
    return PushOutcome(
        method=method,
        step_length=step_length,
        force=force,
        direction=direction,
        duration=duration,
        push_time=push_time(session),
        support=support,
        com_speed_change=speeds.get("after", math.nan) - speeds.get("before", 0.0),
        recovered=not session.fell and session.error is None,
        fall_time=session.fall_time,
        fall_reason=session.fall_reason,
        steps_completed=summary_steps,
        error=session.error,
    )


@dataclass(frozen=True)
class Survival:
    """The largest push one method survived (bisection between survived and failed)."""

    method: str
    step_length: float  # [m]
    direction: str
    duration: float  # [s]
    survived: float | None  # [N] largest force survived (None: falls even unpushed)
    failed: float | None  # [N] smallest force that made it fall (None: survived f_high)
    fall_reason: str | None  # why it fell at ``failed``
    runs: int
    support: str | None = None  # the foot the robot stood on when pushed
    error: str | None = None  # the pelvis strategy stopped a trial (its file and line): no figure

    def describe(self) -> str:
        if self.error is not None:
            return f"{self.method}: stopped by its strategy: {self.error}"
        if self.survived is None:
            return f"{self.method}: falls without a push at {self.step_length:.2f} m"
        if self.failed is None:
            return f"{self.method}: survives {self.survived:.0f} N (the highest tried)"
        return (
            f"{self.method}: survives {self.survived:.0f} N, falls at {self.failed:.0f} N "
            f"({self.fall_reason})"
        )


def largest_survived(
    method: str,
    step_length: float,
    direction: str = "left",
    duration: float = 0.1,
    f_high: float = F_HIGH,
    resolution: float = F_RESOLUTION,
    step: int = PUSH_STEP,
    n_steps: int = N_STEPS,
    params: ControllerParams | None = None,
    phase: float = 0.5,
) -> Survival:
    """Bisect the push size between 0 N and ``f_high`` until survived and failed are at most
    ``resolution`` apart.

    The ends are run only when the bisection needs them (a walk that survives every midpoint
    is tried at ``f_high``, one that falls at every midpoint unpushed), so a bracket costs
    ``log2(f_high / resolution)`` walks: 7 for 256 N at 2 N.
    """

    def trial(f: float) -> PushOutcome:
        return run_push(method, step_length, f, direction, duration, step, n_steps, params, phase)

    lo, hi = 0.0, f_high
    why: str | None = None
    failed_seen = survived_seen = False
    runs = 0
    support = None
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        out = trial(mid)
        runs, support = runs + 1, out.support
        if out.error is not None:  # a student's fault, not a fall: no bracket to report
            return Survival(
                method, step_length, direction, duration, None, None, None, runs, support, out.error
            )
        if out.recovered:
            lo, survived_seen = mid, True
        else:
            hi, why, failed_seen = mid, out.fall_reason, True
    if not survived_seen:  # every midpoint fell: does it walk unpushed?
        out = trial(0.0)
        runs, support = runs + 1, out.support
        if not out.recovered:
            return Survival(
                method, step_length, direction, duration, None, 0.0, out.fall_reason, runs, support
            )
    if not failed_seen:  # every midpoint survived: the top of the range
        out = trial(f_high)
        runs, support = runs + 1, out.support
        if out.recovered:
            return Survival(
                method, step_length, direction, duration, f_high, None, None, runs, support
            )
        why = out.fall_reason
    return Survival(method, step_length, direction, duration, lo, hi, why, runs, support)


def study(
    methods: Sequence[str],
    step_length: float,
    direction: str = "left",
    duration: float = 0.1,
    f_high: float = F_HIGH,
    resolution: float = F_RESOLUTION,
    jobs: int = 1,
    ray: str | None = None,
) -> list[Survival]:
    """:func:`largest_survived` for each method, a job each on the run engine
    (:mod:`pelvic_walk.core.engine`: in this process, a ``spawn`` process pool of ``jobs``, or
    Ray with ``ray`` not None). ImportError / ConnectionError (one line) when Ray cannot run."""
    from pelvic_walk.core.engine import OneJob, make_backend, run_tasks

    tasks = [
        OneJob(largest_survived, m, step_length, direction, duration, f_high, resolution, label=m)
        for m in methods
    ]
    backend = make_backend(ray, jobs, len(tasks))
    try:
        run_tasks(tasks, backend, desc=f"push study ({backend.name})")
    finally:
        backend.close()
    return [t.result for t in tasks]


def table(rows: Sequence[Survival], force: float | None = None) -> str:
    """A markdown table of the study (and of a single ``force`` if given)."""
    lines = [
        "| method | step [m] | push | survives [N] | falls at [N] | why it falls |",
        "|---|---|---|---|---|---|",
    ]
    for s in rows:
        if s.error is not None:
            lines.append(
                f"| {s.method} | {s.step_length:.2f} | {s.direction}, {s.duration:.2f} s "
                "| - | - | stopped by its strategy |"
            )
            continue
        survived = "falls unpushed" if s.survived is None else f"{s.survived:.0f}"
        if s.failed is None:
            survived = f">= {s.survived:.0f}"
        lines.append(
            f"| {s.method} | {s.step_length:.2f} | {s.direction}, {s.duration:.2f} s "
            f"| {survived} | {'-' if s.failed is None else f'{s.failed:.0f}'} "
            f"| {s.fall_reason or '-'} |"
        )
    return "\n".join(lines)


def as_json(rows: Sequence[Survival], singles: Sequence[PushOutcome] = ()) -> dict:
    return {"survival": [asdict(s) for s in rows], "pushes": [asdict(o) for o in singles]}
