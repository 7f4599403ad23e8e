"""Reference pelvic angle over the MPC horizon, eq. (27)-(33) of Park & Park (2022).

For every predicted sample k = 1..N of the horizon the pelvis is placed at the predicted CoM
(eq. 27), the feet at their planned positions, and the reference yaw of the pelvis is the
mean of one angle per foot (eq. 30-32).

Paper symbols -> code names:
    P_hat_P,i(k) (eq. 27, x and y)      -> ``p_pelvis[k]``   (N, 2) [m]
    P_LF,i(k), P_RF,i(k)                -> ``p_left[k]``, ``p_right[k]`` (N, 2) [m]
    Delta d_LFP,i,x(k), Delta d_RFP,i,x(k) (eq. 28-29) -> ``dx_left``, ``dx_right`` (N,) [m]
    Delta d_LFP,i,y, Delta d_RFP,i,y (eq. 31-32)       -> ``+half_width``, ``-half_width`` [m]
    k_pel                               -> ``k_pel``
    theta_pel^ref(k) (eq. 30, 33)       -> the returned array (N,) [rad]

Choices where the paper is vague (SPEC sections 1 and 6):
- **Lateral distance**: eq. (31)-(32) give the y distance no index k; we use the *nominal*
  pelvis-to-foot lateral distance, ``+half_width`` for the left foot and ``-half_width`` for
  the right (half the step width). Using the predicted lateral distance would divide by the
  few centimetres left when the CoM sways over the support foot and let that foot dominate.
- **Sign**: a positive yaw (about +z) moves the left hip (at +y) backward. The pelvis must turn
  each hip *toward its own foot* (the forward foot's hip moves forward, so the forward leg's
  hip-to-foot distance shrinks), hence ``theta_ref = -mean(atan(k_pel dx / dy))``. The literal
  sign of eq. (31)-(32) would pull the leading hip back.
- Only x and y are used; the pelvis height (z_0 in eq. 27) plays no role in the angle.
"""

from __future__ import annotations

import numpy as np

HIP_HALF_WIDTH = 0.105  # [m] lateral distance from the pelvis centre to each hip joint


def reference_pelvic_angles(
    p_pelvis: np.ndarray,
    p_left: np.ndarray,
    p_right: np.ndarray,
    k_pel: float,
    half_width: float,
) -> np.ndarray:
    """Reference pelvic yaw for each predicted sample, eq. (28)-(33).

    Args:
        p_pelvis: (N, 2) predicted pelvis (= CoM) x, y positions [m], eq. (27).
        p_left: (N, 2) planned left-foot x, y positions at the same instants [m].
        p_right: (N, 2) planned right-foot x, y positions [m].
        k_pel: gain of eq. (31)-(32) (share of the step made by the pelvic rotation).
        half_width: nominal pelvis-to-foot lateral distance, half the step width [m] (> 0).

    Returns:
        (N,) reference pelvic angles theta_ref(k) [rad], positive about +z.
    """
    if half_width <= 0.0:
        raise ValueError(f"half_width must be positive, got {half_width}")
    p_pelvis = np.atleast_2d(np.asarray(p_pelvis, dtype=float))
    p_left = np.atleast_2d(np.asarray(p_left, dtype=float))
    p_right = np.atleast_2d(np.asarray(p_right, dtype=float))
    dx_left = p_left[:, 0] - p_pelvis[:, 0]  # eq. (28) [m]
    dx_right = p_right[:, 0] - p_pelvis[:, 0]  # eq. (29) [m]
    theta_left = np.arctan(k_pel * dx_left / half_width)  # eq. (31), dy = +half_width
    theta_right = np.arctan(k_pel * dx_right / -half_width)  # eq. (32), dy = -half_width
    return -0.5 * (theta_left + theta_right)  # eq. (30) with the sign rule of SPEC section 1


def hip_points(
    p_pelvis: np.ndarray, theta: np.ndarray, hip_half_width: float = HIP_HALF_WIDTH
) -> np.ndarray:
    """Left and right hip-joint positions of a pelvis yawed by ``theta`` (for drawing).

    Args:
        p_pelvis: (N, 2) pelvis centre x, y [m].
        theta: (N,) pelvic yaw [rad].
        hip_half_width: lateral distance from the pelvis centre to each hip [m].

    Returns:
        (N, 2, 2) array: ``[k, 0]`` is the left hip (x, y), ``[k, 1]`` the right hip.
    """
    p_pelvis = np.atleast_2d(np.asarray(p_pelvis, dtype=float))
    theta = np.broadcast_to(np.asarray(theta, dtype=float), (p_pelvis.shape[0],))
    # Rotating (0, +h) by theta gives (-h sin theta, h cos theta): positive yaw -> left hip back.
    offset = hip_half_width * np.stack([-np.sin(theta), np.cos(theta)], axis=-1)  # (N, 2)
    return np.stack([p_pelvis + offset, p_pelvis - offset], axis=1)
