"""The four layers' explanations of a walker's last tick (:mod:`controller.explain`).

Called right after :meth:`controller.walker.Walker.tick`, by whoever asks (a display's frame,
a recording, the API, a notebook): each layer's solver still holds that tick's QP, solution
and DAQP's duals, so nothing is kept or copied during the tick itself. :func:`active_counts`
is the one per-tick reading (a recorded run's series): the number of non-zero duals per layer.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from controller.arm_swing import explain_arm
from controller.explain import QpExplain, TickExplain, not_run
from controller.ik import explain_ik
from controller.pelvis_mpc import PelvisMpc
from controller.qp import QpSolver

if TYPE_CHECKING:
    from controller.walker import TickOutput, Walker


def _pelvis_mpc(walker: Walker) -> PelvisMpc | None:
    """The pelvic MPC of the walker's strategy (the paper's method), or None."""
    mpc = getattr(walker.strategy.strategy, "mpc", None)
    return mpc if isinstance(mpc, PelvisMpc) else None


def _pelvis_not_run(walker: Walker) -> QpExplain:
    method = walker.params.method
    if method == "fixed":
        note = (
            "the fixed pelvis solves no pelvic QP: it pins the waist rate at 0 "
            "(the IK's 'waist rate pinned by the strategy')"
        )
    elif method == "redundancy":
        note = "redundancy solves no pelvic QP: the waist is free in the IK"
    else:
        note = f"method {method} solves no pelvic QP of ours (its own code sets the waist)"
    return not_run("pelvis_mpc", note)


def explain_tick(walker: Walker, out: TickOutput) -> TickExplain:
    """The explanations of ``walker``'s last tick, whose output is ``out`` (call it before
    the next tick)."""
    p, dt = walker.params, walker.dt
    layers = [walker.com_mpc.explain(out.com_plan)]
    mpc = _pelvis_mpc(walker)
    if mpc is not None and out.pelvis_plan is not None and mpc.solver.last_qp is not None:
        layers.append(mpc.explain(out.pelvis_plan))
    else:
        layers.append(_pelvis_not_run(walker))
    ik_qp = walker.ik_solver.last_qp
    if ik_qp is None:
        layers.append(not_run("ik", "no tick yet"))
    else:
        q_min, q_max = walker.kin.q_min[walker.lower], walker.kin.q_max[walker.lower]
        layers.append(explain_ik(ik_qp, walker.ik_solver, out.kin.J_low, q_min, q_max, p.ik, dt))
    arm_qp = walker.arm_solver.last_qp
    if not p.arms.enabled or arm_qp is None:
        layers.append(not_run("arm_swing", "arm swing is off: the arms return to their pose"))
    else:
        arms = walker.arms
        layers.append(
            explain_arm(
                arm_qp,
                walker.arm_solver,
                out.kin.cmm_yaw_up,
                out.h_low,
                walker.kin.q_min[arms],
                walker.kin.q_max[arms],
                p.ik.joint_speed_limit,
                p.arms,
                dt,
            )
        )
    # the time after the tick, as the time series' ``t`` and the frames' have it
    return TickExplain(round(float(out.t) + dt, 9), p.method, tuple(layers))


def _count(solver: QpSolver | None) -> float:
    return math.nan if solver is None else solver.active_count()


def active_counts(walker: Walker) -> tuple[float, float, float, float]:
    """Active constraints of the last tick per layer (CoM MPC, pelvic MPC, IK, arm swing);
    NaN for a layer that solved no QP. Cheap (DAQP: its non-zero duals): read every tick of a
    recorded run."""
    mpc = _pelvis_mpc(walker)
    return (
        _count(walker.com_mpc.solver),
        _count(mpc.solver) if mpc is not None and walker.strategy.plan is not None else math.nan,
        _count(walker.ik_solver),
        _count(walker.arm_solver) if walker.params.arms.enabled else math.nan,
    )
