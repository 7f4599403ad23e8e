"""A peer's walk loop on our robot, for ``pelvic-walk bench``: placo's pattern generator + IK.

Run by the bench as a script in an interpreter that has placo (``--peer-python``): it imports
numpy and placo only, never this project, because placo pins its own Pinocchio (placo 0.10.2
requires pin 3.8.0, this project runs pin 4.1). It reads one JSON object (argv[1]: the URDF
the bench wrote from our MJCF at run time, our walking timing and sizes, the tick counts) and
prints one JSON object of per-tick timings.

The loop is placo's own walk loop (the structure of placo-examples' ``walk/walk.py``): per
tick the walk tasks follow the planned trajectory, the whole-body kinematics QP is solved,
the support foot is kept on the floor, and every ``replan_timesteps`` planning steps the
footsteps and the CoM trajectory (a LIPM QP) are re-planned from the current support.
Kinematics only: no physics, as a peer of our controller tick (not of our closed loop).

The horizon is fixed, as in that example: the repetitive footstep planner returns the same
number of steps at every re-plan (the example: 10 steps of 0.38 s), so the walk goes on for
as many ticks as asked and every re-plan solves a problem of the same size. placo 0.10's
pattern generator puts a LIPM on every support it is given (its ``planned_timesteps``
parameter is not applied there), so the planner's step count is the horizon: here the steps
that cover ``planned_timesteps`` planning steps (48 x 0.096 s = 4.6 s with our timing: 4
steps of 1.2 s). A plan of the whole walk would make each re-plan grow with the run's length.
"""

from __future__ import annotations

import json
import math
import sys
import time
from importlib.metadata import version

import numpy as np
import placo  # type: ignore[import-not-found]  # in its own venv (module docstring)


def walk_loop(cfg: dict) -> dict:
    """Per-tick timings [ms] of placo's walk loop on the robot of ``cfg['urdf']``."""
    dt = cfg["dt"]
    robot = placo.HumanoidRobot(cfg["urdf"])
    p = placo.HumanoidParameters()
    # our walking timing: a step = DSP + SSP (placo: the DSP as a ratio of the SSP)
    ssp = cfg["step_time"] * (1.0 - cfg["dsp_ratio"])
    p.single_support_duration = ssp
    p.single_support_timesteps = cfg["ssp_timesteps"]
    p.double_support_ratio = cfg["step_time"] * cfg["dsp_ratio"] / ssp
    p.startend_double_support_ratio = 1.5
    p.planned_timesteps = cfg["planned_timesteps"]
    p.walk_com_height = cfg["com_height"]
    p.walk_foot_height = cfg["foot_height"]
    p.walk_trunk_pitch = 0.0
    p.walk_foot_rise_ratio = 0.2
    p.foot_length, p.foot_width = cfg["foot_size"]
    p.feet_spacing = cfg["step_width"]
    p.zmp_margin = cfg["zmp_margin"]
    p.foot_zmp_target_x = p.foot_zmp_target_y = 0.0
    p.walk_max_dtheta = 1.0
    p.walk_max_dy = 0.04
    p.walk_max_dx_forward = cfg["step_length"]
    p.walk_max_dx_backward = 0.03

    solver = placo.KinematicsSolver(robot)
    solver.enable_velocity_limits(True)
    solver.dt = dt
    tasks = placo.WalkTasks()
    tasks.initialize_tasks(solver, robot)
    joints = solver.add_joints_task()
    joints.set_joints(cfg["held_joints"])  # arms and waist at the walk-ready pose
    joints.configure("joints", "soft", 1.0)
    tasks.reach_initial_pose(np.eye(4), p.feet_spacing, p.walk_com_height, p.walk_trunk_pitch)

    # the fixed horizon (module docstring): the steps that cover planned_timesteps
    steps_ahead = max(2, math.ceil(p.planned_timesteps * p.dt() / cfg["step_time"] - 1e-9))
    planner = placo.FootstepsPlannerRepetitive(p)
    planner.configure(cfg["step_length"], 0.0, 0.0, steps_ahead)
    footsteps = planner.plan(
        placo.HumanoidRobot_Side.left,
        placo.flatten_on_floor(robot.get_T_world_left()),
        placo.flatten_on_floor(robot.get_T_world_right()),
    )
    supports = placo.FootstepsPlanner.make_supports(
        footsteps, 0.0, True, p.has_double_support(), True
    )
    walk = placo.WalkPatternGenerator(robot, p)
    trajectory = walk.plan(supports, robot.com_world(), 0.0)

    replan_every = cfg["replan_timesteps"] * p.dt()
    t, last_replan = 0.0, 0.0
    ticks, cpu, replans = [], [], []
    clock, cpu_clock = time.perf_counter, time.thread_time  # wall, and CPU of this thread
    for i in range(cfg["warmup_ticks"] + cfg["ticks"]):
        t0, c0 = clock(), cpu_clock()
        tasks.update_tasks_from_trajectory(trajectory, t)
        robot.update_kinematics()
        solver.solve(True)
        if not trajectory.support_is_both(t):
            robot.update_support_side(str(trajectory.support_side(t)))
            robot.ensure_on_floor()
        replanned = False
        if t - last_replan > replan_every and walk.can_replan_supports(trajectory, t):
            supports = walk.replan_supports(planner, trajectory, t, last_replan)
            trajectory = walk.replan(supports, trajectory, t)
            last_replan = t
            replanned = True
        elapsed, elapsed_cpu = clock() - t0, cpu_clock() - c0
        if i >= cfg["warmup_ticks"]:
            ticks.append(elapsed)
            cpu.append(elapsed_cpu)
            replans.append(replanned)
        t += dt
    ms, ms_cpu = np.array(ticks) * 1e3, np.array(cpu) * 1e3
    re = np.array(replans)
    return {
        "name": f"placo {version('placo')} walk loop (pattern generator + kinematics QP, "
        "no physics) on our robot",
        "tick_ms_median": float(np.median(ms)),
        "tick_ms_mean": float(np.mean(ms)),
        "tick_ms_p99": float(np.percentile(ms, 99)),
        "tick_ms_max": float(np.max(ms)),
        "replan_tick_share": float(re.mean()),
        "replan_tick_ms_median": float(np.median(ms[re])) if re.any() else None,
        # in CPU time: a re-planning tick lasts a few ms, long enough for the machine's other
        # jobs to preempt it, which the wall-time median counts and this one does not
        "replan_tick_ms_cpu_median": float(np.median(ms_cpu[re])) if re.any() else None,
        "tick_ms_cpu_median": float(np.median(ms_cpu)),
        "replans": int(re.sum()),
        "steps_ahead": steps_ahead,
        "horizon_s": steps_ahead * cfg["step_time"],
        "ticks": len(ms),
        "com_height_end": float(robot.com_world()[2]),
        "x_travelled": float(robot.get_T_world_trunk()[0, 3]),
    }


if __name__ == "__main__":
    print(json.dumps(walk_loop(json.loads(sys.argv[1]))))
