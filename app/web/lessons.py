"""The Learn tab's content: short lessons per layer, the paper's scenarios, the kinematic
analysis of eq. (1)-(5) drawn as the paper's Fig. 1-2.

Text only here (and one SVG drawing); :mod:`app.web.panel` builds the controls around it.
"""

from __future__ import annotations

import math
from typing import Any

# The paper's scenarios, in one place: parameter groups to change (others keep their value)
# and optionally the methods to compare.
PRESETS: dict[str, dict[str, Any]] = {
    "Paper: 0.30 m steps": {"walk": {"step_length": 0.30, "step_time": 1.2}},
    "Paper: 0.40 m steps": {
        "walk": {"step_length": 0.40, "step_time": 1.2},
        "methods": ["fixed", "mpc"],
    },
    # Our fixed pelvis walks cleanly to 0.37 m; at 0.38-0.39 m its swing knee straightens
    # (kappa > 1000) and the IK hits the joint-speed limit (report section 2). Paper: 0.35 m.
    "Where our fixed pelvis fails: 0.39 m (paper: 0.35 m)": {
        "walk": {"step_length": 0.39, "step_time": 1.2},
        "methods": ["fixed", "mpc"],
    },
    "All three methods, 0.30 m": {
        "walk": {"step_length": 0.30, "step_time": 1.2},
        "methods": ["fixed", "redundancy", "mpc"],
    },
    "Defaults": {"walk": {"step_length": 0.2, "step_time": 1.2}, "reset_groups": True},
}

# Short lessons, one per layer, with the paper's equation numbers.
EXPLAIN: dict[str, str] = {
    "Overview": (
        "Each robot runs the same controller with the same parameters; only the **waist yaw** "
        "(the pelvic rotation) differs: **fixed** keeps it at 0, **redundancy** (ref. [21]) "
        "lets the IK use it with no preview, the **pelvic-rotation MPC** plans it over the "
        "horizon. Raise the step length and watch the **reach gauges**: the fixed pelvis "
        "straightens its swing leg (red) first."
    ),
    "CoM MPC (eq. 10-18)": (
        "A linear inverted pendulum at constant height, state [p, v, a] per axis, input = jerk "
        "(eq. 10-12). Over the horizon H it trades **alpha** x ZMP tracking, **beta** x CoM "
        "velocity changes and **gamma** x jerk (eq. 18), keeping the ZMP inside the support "
        "area. The **cyan** points are its predicted CoM (eq. 25-26)."
    ),
    "Pelvis position (eq. 19)": (
        "The pelvis follows the desired CoM and corrects the offset to the CoM measured from "
        "the joint angles with gain K_p (eq. 19). Its orientation stays 0: the torso faces "
        "forward while the waist joint turns the hips."
    ),
    "Feet (eq. 20-21)": (
        "The support foot stays on its foothold; the swing foot follows a cubic from the old "
        "to the new foothold with zero velocity at both ends, plus a smooth lift (eq. 20-21). "
        "The **white/coloured curve** is the path of the swing in progress; the rectangles are "
        "the planned footholds (0.30 x 0.17 m feet)."
    ),
    "Reference pelvic angle (eq. 27-33)": (
        "At each predicted sample the pelvis is put at the predicted CoM (eq. 27) and the angle "
        "is the mean over both feet of atan(k_pel dx / dy) (eq. 28-33), signed so each hip "
        "turns **toward its own foot**. The **yellow hip lines** show it over the horizon."
    ),
    "Pelvic-rotation MPC (eq. 34-38)": (
        "A double integrator theta'' = u tracks the reference with weight **alpha_pel** and "
        "penalises u with **beta_pel**, with |theta| under the angle limit (eq. 34-38). The "
        "**orange hip lines** are its optimised angles: it starts turning *before* the swing."
    ),
    "QP inverse kinematics (eq. 39-40)": (
        "13 joint velocities (waist yaw + two legs) make the feet follow their paths: "
        "min ||J q' - x'_feet||^2 with joint and speed limits (eq. 39-40). The waist rate is "
        "pinned to 0 (fixed), free (redundancy) or the MPC's rate (mpc). The **leg colours** "
        "show the reach: hip-to-ankle distance / leg length, red near 1 (straight knee)."
    ),
    "Arm swing (eq. 41-43)": (
        "The arms cancel the legs' yaw momentum: min omega1 (h_low + h_up)^2 + omega2 "
        "||q_up0 - q_up||^2 + omega3 ||q'_up||^2 on the centroidal momentum matrix "
        "(eq. 41-43). The **arrow** at the CoM is the whole-body yaw momentum."
    ),
    "Energy and kappa (eq. 44-45)": (
        "Energy = sum of the positive joint work per two-step window (eq. 44). kappa(J) is the "
        "condition number of the leg Jacobian (eq. 45): it shoots up as a knee straightens."
    ),
    "Kinematic analysis (eq. 1-5)": (
        "Static step limit of a stretched leg: sqrt(l_leg^2 - z0^2) (eq. 4, 0.31 m); turning "
        "the pelvis moves the forward hip ahead by up to l_pel/2 (eq. 2, 5): 0.42 m, +35 %. "
        "Use the slider below the lesson to turn the pelvis."
    ),
}


def analysis_svg(theta_deg: float) -> str:
    """Top view of the pelvis turned by ``theta_deg`` and the static step limit (eq. 1-5)."""
    from controller.analysis import hip_points_for_angle, kinematic_analysis, reachable_step

    ka = kinematic_analysis()
    l_leg, z0, l_pel = ka["l_leg"], ka["z0"], ka["l_pel"]
    step0 = reachable_step(l_leg, z0, l_pel, 0.0)
    step = reachable_step(l_leg, z0, l_pel, theta_deg)
    hx = hip_points_for_angle(theta_deg, l_pel)  # (2,) x of left, right hip [m]
    hy = 0.5 * l_pel * math.cos(math.radians(theta_deg))
    scale, ox, oy = 300.0, 70.0, 95.0  # px per m, origin (pelvis centre) in px

    def px(x: float, y: float) -> tuple[float, float]:
        return ox + scale * x, oy - scale * y

    (lx, ly), (rx, ry) = px(hx[0], hy), px(hx[1], -hy)
    foot0, foot1 = px(step0, -0.12), px(step, -0.12)
    rear = px(0.0, -0.12)
    return f"""
<svg viewBox="0 0 320 198" width="100%" xmlns="http://www.w3.org/2000/svg"
     style="font: 11px sans-serif; background: #f6f7f9; border-radius: 6px">
  <text x="8" y="16">top view, walking to the right; pelvis turned {theta_deg:.0f} deg</text>
  <line x1="{lx:.1f}" y1="{ly:.1f}" x2="{rx:.1f}" y2="{ry:.1f}" stroke="#444" stroke-width="6"
        stroke-linecap="round"/>
  <circle cx="{lx:.1f}" cy="{ly:.1f}" r="6" fill="#4682ff"/>
  <circle cx="{rx:.1f}" cy="{ry:.1f}" r="6" fill="#ff5050"/>
  <line x1="{rear[0]:.1f}" y1="{rear[1] + 8:.1f}" x2="{foot0[0]:.1f}" y2="{foot0[1] + 8:.1f}"
        stroke="#999" stroke-width="3"/>
  <line x1="{rear[0]:.1f}" y1="{rear[1] + 22:.1f}" x2="{foot1[0]:.1f}" y2="{foot1[1] + 22:.1f}"
        stroke="#28b464" stroke-width="3"/>
  <text x="8" y="{rear[1] + 12:.1f}">eq. 4</text>
  <text x="8" y="{rear[1] + 26:.1f}">eq. 5</text>
  <text x="{foot0[0] + 4:.1f}" y="{foot0[1] + 12:.1f}">{step0:.3f} m</text>
  <text x="{foot1[0] + 4:.1f}" y="{foot1[1] + 26:.1f}">{step:.3f} m
    (+{100 * (step / step0 - 1):.0f} %)</text>
  <text x="8" y="176">hip advance {1000 * (hx[1] - hx[0]):.0f} mm (eq. 2)</text>
  <text x="8" y="191">l_leg {l_leg} m, z0 {z0} m, l_pel {l_pel} m</text>
</svg>"""


# Longest steps measured on this model (README; `pelvic-walk sweep --measure limit`): beyond
# them a method does not walk cleanly at the default timing.
CLEAN_LIMIT_M = {"fixed": 0.37, "redundancy": 0.43, "mpc": 0.43}


def warnings_for(params: Any) -> list[str]:
    """Settings known to break walking, explained in one line each (empty when none)."""
    w = params.walk
    out = []
    if params.com.horizon < w.step_time:
        out.append(
            f"The MPC horizon ({params.com.horizon:.1f} s) is shorter than one step "
            f"({w.step_time:.2f} s): the CoM MPC cannot see the next support foot before the "
            "step starts, so the CoM arrives late and the robots tend to fall."
        )
    if w.dsp_ratio * w.step_time < 0.1:
        out.append(
            f"A double support of {1000 * w.dsp_ratio * w.step_time:.0f} ms leaves the CoM "
            "very little time to move to the new support foot."
        )
    if params.pelvis.k_pel == 0.0:
        out.append("k_pel = 0: the reference pelvic angle is 0, the MPC plans no rotation.")
    beyond = [m for m, lim in CLEAN_LIMIT_M.items() if w.step_length > lim + 1e-9]
    if beyond:
        out.append(
            f"{w.step_length:.2f} m is beyond the longest clean step measured here for "
            f"{', '.join(beyond)} (fixed {CLEAN_LIMIT_M['fixed']:.2f} m, rotating "
            f"{CLEAN_LIMIT_M['mpc']:.2f} m at 1.2 s steps): watch the status badges."
        )
    return out
