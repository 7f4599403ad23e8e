"""Kinematic analysis of the step length with and without pelvic rotation, eq. (1)-(5).

Section II of Park & Park (2022). Symbols -> names: l_leg (stretched leg, hip to ankle)
-> ``l_leg``; z_0 (ankle-to-hip height) -> ``z0``; l_pel (distance between the hip joints)
-> ``l_pel``; w_step (lateral distance between the feet) -> ``w_step``; theta_pel ->
``theta_pel_deg`` (degrees: user-facing).

    (1) stretched, fixed pelvis:     l* = 2 sqrt(l_leg^2 - z0^2)
    (2) hip advance:                 Delta d_hip = l_pel sin(theta)
    (3) stretched, rotating pelvis:  l* = sqrt((l_max^step + l_pel)^2 - w_step^2),
                                     l_max^step = eq. (1)'s value
    (4) static, fixed pelvis:        l* = sqrt(l_leg^2 - z0^2)
    (5) static, rotating pelvis:     l* = sqrt(l_leg^2 - z0^2) + Delta d*_hc

What reproduces the paper's numbers (0.31 m without, 0.42 m with rotation, +35 %), with
l_leg 0.75, z0 0.68, l_pel 0.21, w_step 0.243, theta 45 deg:
- **0.31 m is eq. (4)**: sqrt(0.75^2 - 0.68^2) = 0.3164 m (the paper truncates). Eq. (1)
  gives 0.633 m and eq. (3) 0.807 m: the stretched-leg pair is not what the paper reports.
- **0.42 m is eq. (5) with Delta d*_hc = 0.105 m = l_pel/2**, i.e. 0.3164 + 0.105 = 0.4214 m.
  The text's Delta d*_hc = 0.5 l_pel sin(theta) gives 0.0742 m at 45 deg and 0.391 m (+23 %)
  instead; no other combination of eq. (1)-(5) lands on 0.42 (eq. 5 with l_pel sin theta:
  0.465; eq. 3 on eq. 4: 0.467; half of eq. 3: 0.403). The value the paper used equals
  ``l_pel sin(theta) cos(theta)`` (= 0.5 l_pel sin 2 theta) at its 45 deg, which is how
  ``rule="paper"`` evaluates Delta d*_hc (maximal, = l_pel/2, at 45 deg).
  ``rule="literal"`` uses the printed 0.5 l_pel sin(theta).
- **+35 %** = 0.42 / 0.31 - 1 on the *rounded* numbers; unrounded, 0.4214 / 0.3164 - 1
  = +33 %. ``increase_percent`` compares the pair the paper compares, the two static values
  (eq. 5 vs eq. 4), unrounded.
"""

from __future__ import annotations

import math

import numpy as np

from controller.pelvis_reference import hip_points

RULES = ("paper", "literal")


def _reach(l_leg: float, z0: float) -> float:
    """sqrt(l_leg^2 - z0^2) [m]: forward reach of a stretched leg (0 if z0 >= l_leg)."""
    return math.sqrt(max(l_leg * l_leg - z0 * z0, 0.0))


def hip_centre_offset(l_pel: float, theta_deg: float, rule: str = "paper") -> float:
    """Delta d*_hc of eq. (5) [m]: forward offset gained by the pelvic rotation.

    ``rule="paper"``: l_pel sin(theta) cos(theta) (reproduces the paper's 0.42 m at 45 deg);
    ``rule="literal"``: 0.5 l_pel sin(theta) as printed under eq. (5).
    """
    t = math.radians(theta_deg)
    if rule == "paper":
        return l_pel * math.sin(t) * math.cos(t)
    if rule == "literal":
        return 0.5 * l_pel * math.sin(t)
    raise ValueError(f"rule must be one of {RULES}, got {rule!r}")


# The paper's inputs to the analysis (Sec. II): l_leg, z0, l_pel, w_step [m], theta_pel [deg]
PAPER_L_LEG, PAPER_Z0, PAPER_L_PEL, PAPER_W_STEP, PAPER_THETA_PEL_DEG = (
    0.75,
    0.68,
    0.21,
    0.243,
    45.0,
)


def kinematic_analysis(
    l_leg: float = PAPER_L_LEG,
    z0: float = PAPER_Z0,
    l_pel: float = PAPER_L_PEL,
    w_step: float = PAPER_W_STEP,
    theta_pel_deg: float = PAPER_THETA_PEL_DEG,
    rule: str = "paper",
) -> dict:
    """Maximum step lengths of eq. (1)-(5) [m] and the paper's increase [%].

    Args:
        l_leg: stretched leg length, hip to ankle [m].
        z0: hip height above the ankle [m].
        l_pel: distance between the two hip joints [m].
        w_step: lateral distance between the feet [m].
        theta_pel_deg: pelvic rotation [deg].
        rule: how Delta d*_hc of eq. (5) is evaluated (see the module docstring).

    Returns:
        dict with keys ``l_leg, z0, l_pel, w_step, theta_pel_deg, step_max_fixed_static``
        (eq. 4), ``step_max_rotation_static`` (eq. 5), ``step_max_fixed_stretched`` (eq. 1),
        ``step_max_rotation_stretched`` (eq. 3 on eq. 1's value) and ``increase_percent``
        (eq. 5 vs eq. 4).
    """
    reach = _reach(l_leg, z0)
    fixed_static = reach  # eq. (4)
    rotation_static = reach + hip_centre_offset(l_pel, theta_pel_deg, rule)  # eq. (5)
    fixed_stretched = 2.0 * reach  # eq. (1)
    rotation_stretched = math.sqrt(max((fixed_stretched + l_pel) ** 2 - w_step**2, 0.0))  # (3)
    increase = 100.0 * (rotation_static / fixed_static - 1.0) if fixed_static > 0 else math.nan
    return {
        "l_leg": l_leg,
        "z0": z0,
        "l_pel": l_pel,
        "w_step": w_step,
        "theta_pel_deg": theta_pel_deg,
        "step_max_fixed_static": fixed_static,
        "step_max_rotation_static": rotation_static,
        "step_max_fixed_stretched": fixed_stretched,
        "step_max_rotation_stretched": rotation_stretched,
        "increase_percent": increase,
    }


def hip_points_for_angle(theta_deg: float, l_pel: float) -> np.ndarray:
    """Hip x offsets from the pelvis centre [m], (2,) = [left, right], for a yaw theta_deg.

    Positive yaw (about +z) moves the left hip (at +y) backward: x_left = -l_pel/2 sin(theta),
    x_right = +l_pel/2 sin(theta) (eq. 2's Delta d_hip = x_right - x_left = l_pel sin theta).
    """
    hips = hip_points(np.zeros((1, 2)), np.array([math.radians(theta_deg)]), 0.5 * l_pel)
    return hips[0, :, 0]


def reachable_step(
    l_leg: float, z0: float, l_pel: float, theta_deg: float, rule: str = "paper"
) -> float:
    """Static maximum step [m] for a slider view: eq. (4) at theta 0, eq. (5) otherwise."""
    return _reach(l_leg, z0) + hip_centre_offset(l_pel, abs(theta_deg), rule)
