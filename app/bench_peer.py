"""A peer's walk loop on our robot, for ``pelvic-walk bench``: placo's pattern generator + IK.

Run by the bench as a script in an interpreter that has placo (``--peer-python``): it imports
numpy and placo only, never this project, because placo pins its own Pinocchio (placo 0.10.2
requires pin 3.8.0, this project runs pin 4.1). It reads one JSON object (argv[1]: the URDF
the bench wrote from our MJCF at run time, our walking timing and sizes, the tick counts) and
prints one JSON object of per-tick timings.

The loop is placo's own walk loop (the structure of placo-examples' ``walk/walk.py``): per
tick the walk tasks follow the planned trajectory, the whole-body kinematics QP is solved,
the support foot is kept on the floor, and every ``replan_timesteps`` planning steps the
footsteps and the CoM trajectory (a LIPM QP over ``planned_timesteps``) are re-planned.
Kinematics only: no physics, as a peer of our controller tick (not of our closed loop).
"""

from __future__ import annotations

import json
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

    planner = placo.FootstepsPlannerRepetitive(p)
    planner.configure(cfg["step_length"], 0.0, 0.0, cfg["n_steps"])
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
    ticks, replans = [], []
    clock = time.perf_counter
    for i in range(cfg["warmup_ticks"] + cfg["ticks"]):
        t0 = clock()
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
        elapsed = clock() - t0
        if i >= cfg["warmup_ticks"]:
            ticks.append(elapsed)
            replans.append(replanned)
        t += dt
    ms = np.array(ticks) * 1e3
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
        "ticks": len(ms),
        "com_height_end": float(robot.com_world()[2]),
        "x_travelled": float(robot.get_T_world_trunk()[0, 3]),
    }


if __name__ == "__main__":
    print(json.dumps(walk_loop(json.loads(sys.argv[1]))))
