"""The push study: how hard a sideways shove each method survives (``pelvic-walk push-study``).

One run walks a short plan headless (the same :class:`~app.sim.session.Session` as
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
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass

import mujoco
import numpy as np

from app.sim.session import RunConfig, Session
from controller import strategy
from controller.footsteps import LEFT
from controller.params import ControllerParams

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
    for ``duration`` s from the middle of step ``step``'s single support."""
    strategy.info(method)  # ValueError naming the choices
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {', '.join(DIRECTIONS)}, got {direction!r}")
    if not (math.isfinite(force) and force >= 0.0):
        raise ValueError(f"force must be a finite number >= 0, got {force}")
    if not (math.isfinite(duration) and duration > 0.0):
        raise ValueError(f"duration must be > 0 s, got {duration}")
    if not 0 <= step < n_steps:
        raise ValueError(f"the pushed step must be in 0..{n_steps - 1}, got {step}")
    base = params or ControllerParams()
    p = base.replace(method=method, walk={"step_length": step_length, "n_steps": n_steps})
    session = Session(RunConfig(params=p))
    plan = session.plan
    lift, land = float(plan.liftoff_times()[step]), float(plan.landing_times()[step])
    t_push = lift + phase * (land - lift)  # phase of the single support (0.5: its middle)
    support = "right" if int(plan.swing_side[step]) == LEFT else "left"
    dx, dy = DIRECTIONS[direction]
    world = session.world
    along = np.array([dx, dy])

    def com_speed() -> float:  # the whole body's CoM velocity along the push [m/s]
        mujoco.mj_subtreeVel(world.model, world.data)  # MuJoCo's step leaves it stale
        return float(world.data.subtree_linvel[world.root_id][:2] @ along)

    pushed, v_before, v_after = False, 0.0, None
    dt = session.params.control_dt
    while not session.walker.finished and not session.fell:
        # The push acts from the next control period on: start it on the tick that ends
        # closest to mid-SSP.
        if not pushed and session.t + 0.5 * dt >= t_push:
            v_before = com_speed()
            session.push(force * along, duration)
            pushed = True
        session.tick()
        if pushed and v_after is None and not world.pushing:
            v_after = com_speed()
    summary_steps = int(sum(1 for k in session.landings if k < plan.n_walking_steps))
    return PushOutcome(
        method=method,
        step_length=step_length,
        force=force,
        direction=direction,
        duration=duration,
        push_time=t_push,
        support=support,
        com_speed_change=(v_after if v_after is not None else math.nan) - v_before,
        recovered=not session.fell,
        fall_time=session.fall_time,
        fall_reason=session.fall_reason,
        steps_completed=summary_steps,
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

    def describe(self) -> str:
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


def _survival_job(args: tuple) -> Survival:
    return largest_survived(*args)


def study(
    methods: Sequence[str],
    step_length: float,
    direction: str = "left",
    duration: float = 0.1,
    f_high: float = F_HIGH,
    resolution: float = F_RESOLUTION,
    jobs: int = 1,
) -> list[Survival]:
    """:func:`largest_survived` for each method (one process per method with ``jobs`` > 1)."""
    args = [(m, step_length, direction, duration, f_high, resolution) for m in methods]
    if jobs <= 1 or len(args) == 1:
        return [_survival_job(a) for a in args]
    with ProcessPoolExecutor(max_workers=min(jobs, len(args))) as pool:
        return list(pool.map(_survival_job, args))


def table(rows: Sequence[Survival], force: float | None = None) -> str:
    """A markdown table of the study (and of a single ``force`` if given)."""
    lines = [
        "| method | step [m] | push | survives [N] | falls at [N] | why it falls |",
        "|---|---|---|---|---|---|",
    ]
    for s in rows:
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


def main(args) -> int:
    """``pelvic-walk push-study``: one push per method (``--force``) or the bisection."""
    import json
    import sys
    import time

    from controller.params import spec

    meta = spec(ControllerParams().walk)["step_length"]
    problems = []
    if not meta["min"] <= args.step_length <= meta["max"]:
        problems.append(f"--step-length must be in {meta['min']}..{meta['max']} m")
    if not 0.0 < args.duration <= 1.0:
        problems.append("--duration must be in (0, 1] s")
    if args.force is not None and args.force < 0.0:
        problems.append("--force must be >= 0 N")
    if problems:
        print(f"pelvic-walk push-study: error: {problems[0]}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    singles: list[PushOutcome] = []
    rows: list[Survival] = []
    if args.force is not None:
        for m in args.methods:
            o = run_push(m, args.step_length, args.force, args.direction, args.duration)
            singles.append(o)
            result = (
                "recovered" if o.recovered else f"FELL at {o.fall_time:.2f} s ({o.fall_reason})"
            )
            print(
                f"{m}: {o.force:.0f} N {o.direction} for {o.duration:.2f} s at t = "
                f"{o.push_time:.2f} s (mid-SSP, on the {o.support} foot), step "
                f"{o.step_length:.2f} m: {result}"
            )
    else:
        rows = study(args.methods, args.step_length, args.direction, args.duration, jobs=args.jobs)
        print(table(rows))
    print(f"({time.perf_counter() - start:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps(as_json(rows, singles), indent=2))
    return 0
