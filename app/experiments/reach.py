"""Why a walk reaches farther than eq. (4): the legs' geometry at lift-off and touch-down.

Eq. (4) of the paper (Sec. II) is a static reach: the pelvis centre above the supporting
foot, the hip ``z0`` above the ankle, the swing knee fully stretched, so the swing ankle lands
``sqrt(l_leg^2 - z0^2)`` ahead of its hip, and the hips side by side (no rotation). A walk
breaks each assumption by some amount. :func:`reach_job` walks one method at one length and
measures, at every mid-walk touch-down (and lift-off), what eq. (4) assumed:

- the step split in three: the stance hip ahead of its own ankle, the swing hip ahead of the
  stance hip (the pelvis's yaw), the swing ankle ahead of its hip (the leg's forward reach);
- each leg's hip-to-ankle distance (a share of the stretched leg ``LEG_LENGTH``), the hip's
  height above its ankle (eq. 4's ``z0``), its sideways offset, the knee angle;
- the pelvis's roll and height, and where the CoM lies between the ankles.

Medians over the walking steps after the first two; one run of the engine (a job of plain
data), as the push bisections are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

STEPS = 10  # the sweep's walk
SKIP = 2  # the start-up steps left out

# quantity -> words, the order the report shows them
QUANTITIES = {
    "step": "step length, ankle to ankle, forward [m]",
    "stance_hip_ahead": "stance hip ahead of its own ankle [m]",
    "hips_apart": "swing hip ahead of the stance hip (the pelvis's yaw) [m]",
    "swing_reach": "swing ankle ahead of its hip [m]",
    "swing_leg_share": "swing hip-to-ankle distance / stretched leg",
    "swing_hip_height": "swing hip above its ankle [m] (eq. 4's z0)",
    "swing_lateral": "swing ankle's sideways offset from its hip [m]",
    "swing_knee_deg": "swing knee angle [deg]",
    "stance_leg_share": "stance hip-to-ankle distance / stretched leg",
    "stance_hip_height": "stance hip above its ankle [m]",
    "stance_knee_deg": "stance knee angle [deg]",
    "pelvis_roll_deg": "pelvis roll, swing side down > 0 [deg]",
    "pelvis_yaw_deg": "pelvis yaw toward the swing [deg]",
    "com_share": "CoM between the ankles (0 stance, 1 swing)",
}


@dataclass(frozen=True)
class ReachCase:
    """One method at one length: medians at touch-down and at lift-off."""

    method: str
    step_length: float  # [m] planned
    steps: int  # walking steps measured
    landing: dict[str, float] = field(default_factory=dict)
    liftoff: dict[str, float] = field(default_factory=dict)
    fell: bool = False


@dataclass(frozen=True)
class ReachSection:
    leg_length: float  # [m] stretched, hip to ankle
    z0: float  # [m] eq. (4)'s hip height
    eq4: float  # [m] eq. (4) on our robot
    cases: dict[str, ReachCase]  # "<method>@<length>"


def _geometry(world: Any, swing: int, ids: dict[str, int]) -> dict[str, float]:
    """The legs' geometry now; ``swing`` LEFT (0) or RIGHT (1)."""
    d = world.data
    side = ("L", "R")
    st = 1 - swing
    hip = {s: d.xanchor[ids[f"{side[s]}_hip_pitch"]].copy() for s in (0, 1)}
    ank = {s: d.xanchor[ids[f"{side[s]}_ankle_pitch"]].copy() for s in (0, 1)}
    knee = {s: float(d.qpos[ids[f"q_{side[s]}_knee"]]) for s in (0, 1)}
    from models.dyros_jet import LEG_LENGTH

    R = d.xmat[world.root_id].reshape(3, 3)
    roll = math.atan2(R[2, 1], R[2, 2])
    yaw = math.atan2(R[1, 0], R[0, 0])
    down = 1.0 if swing == 0 else -1.0  # left swing: roll > 0 lifts the left side
    toward = -1.0 if swing == 0 else 1.0  # a left swing advances with negative yaw
    com = d.subtree_com[world.root_id]
    span = ank[swing][0] - ank[st][0]
    return {
        "step": float(span),
        "stance_hip_ahead": float(hip[st][0] - ank[st][0]),
        "hips_apart": float(hip[swing][0] - hip[st][0]),
        "swing_reach": float(ank[swing][0] - hip[swing][0]),
        "swing_leg_share": float(np.linalg.norm(hip[swing] - ank[swing]) / LEG_LENGTH),
        "swing_hip_height": float(hip[swing][2] - ank[swing][2]),
        "swing_lateral": float(abs(hip[swing][1] - ank[swing][1])),
        "swing_knee_deg": math.degrees(knee[swing]),
        "stance_leg_share": float(np.linalg.norm(hip[st] - ank[st]) / LEG_LENGTH),
        "stance_hip_height": float(hip[st][2] - ank[st][2]),
        "stance_knee_deg": math.degrees(knee[st]),
        "pelvis_roll_deg": -down * math.degrees(roll),
        "pelvis_yaw_deg": toward * math.degrees(yaw),
        "com_share": float((com[0] - ank[st][0]) / span) if abs(span) > 1e-6 else math.nan,
    }


def reach_job(method: str, step_length: float, steps: int = STEPS) -> dict[str, Any]:
    """Walk ``steps`` of ``step_length`` headless; the legs' geometry at each walking step's
    touch-down and lift-off (medians over the steps after the first :data:`SKIP`)."""
    import mujoco

    from controller.params import ControllerParams
    from pelvic_walk.core.session import RunConfig, Session

    p = ControllerParams().replace(
        method=method, walk={"step_length": step_length, "n_steps": steps}
    )
    session = Session(RunConfig(params=p))
    world, plan = session.world, session.plan
    m = world.model
    ids = {}
    for s in ("L", "R"):
        for j in ("hip_pitch", "ankle_pitch", "knee"):
            jid = m.joint(f"{s}_{j}").id
            ids[f"{s}_{j}"] = jid
            ids[f"q_{s}_{j}"] = int(m.jnt_qposadr[jid])
    n = plan.n_walking_steps
    events = []
    for k in range(SKIP, n - 1):
        swing = int(plan.swing_side[k])
        events.append((float(plan.liftoff_times()[k]), "liftoff", swing))
        events.append((float(plan.landing_times()[k]), "landing", swing))
    events.sort()
    out: dict[str, list[dict[str, float]]] = {"landing": [], "liftoff": []}
    i = 0
    while not session.walker.finished and not session.fell and i < len(events):
        session.tick()
        while i < len(events) and session.t >= events[i][0]:
            mujoco.mj_kinematics(m, world.data)
            mujoco.mj_comPos(m, world.data)
            out[events[i][1]].append(_geometry(world, events[i][2], ids))
            i += 1

    def medians(rows: list[dict[str, float]]) -> dict[str, float]:
        return {k: float(np.nanmedian([r[k] for r in rows])) for k in QUANTITIES} if rows else {}

    return {
        "method": method,
        "step_length": step_length,
        "steps": len(out["landing"]),
        "landing": medians(out["landing"]),
        "liftoff": medians(out["liftoff"]),
        "fell": bool(session.fell),
    }


def reach_cases(study: Any, ms: dict[str, Any]) -> list[tuple[str, float]]:
    """(method, length) to measure: the fixed pelvis and the MPC at the fixed pelvis's longest
    clean step, and the MPC at its own."""
    from controller.strategy import FIXED, MPC

    if FIXED not in ms or MPC not in ms:
        return []
    f, m = ms[FIXED].longest_clean, ms[MPC].longest_clean
    out = [(FIXED, f), (MPC, f)] if f is not None else []
    if m is not None and (f is None or abs(m - f) > 1e-9):
        out.append((MPC, m))
    return out


def reach_section(outcomes: dict[str, dict[str, Any] | None]) -> ReachSection | None:
    """The section from the jobs' outcomes ("<method>@<length>" -> :func:`reach_job`'s)."""
    from controller.analysis import kinematic_analysis
    from models.dyros_jet import HIP_HEIGHT_Z0, LEG_LENGTH

    cases = {k: ReachCase(**v) for k, v in outcomes.items() if v}
    if not cases:
        return None
    eq4 = kinematic_analysis(l_leg=LEG_LENGTH, z0=HIP_HEIGHT_Z0)["step_max_fixed_static"]
    return ReachSection(LEG_LENGTH, HIP_HEIGHT_Z0, eq4, cases)
