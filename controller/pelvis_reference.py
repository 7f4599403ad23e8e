"""Reference pelvic angle over the MPC horizon, eq. (27)-(33) of Park & Park (2022).

For every predicted sample k = 1..N of the horizon the pelvis is placed at the predicted CoM
(eq. 27), the feet at their planned positions, and the reference yaw of the pelvis is the
mean of one angle per foot (eq. 30-32).

Paper symbols -> code names:
    P_hat_P,i(k) (eq. 27, x and y)      -> ``p_pelvis[k]``   (N, 2) [m]
    P_LF,i(k), P_RF,i(k)                -> ``p_left[k]``, ``p_right[k]`` (N, 2) [m]
    Delta d_LFP,i,x(k), Delta d_RFP,i,x(k) (eq. 28-29) -> ``dx_left``, ``dx_right`` (N,) [m]
    Delta d_LFP,i,y, Delta d_RFP,i,y (eq. 31-32)       -> :func:`lateral_distances` (N, 2) [m]
    k_pel                               -> ``k_pel``
    theta_pel^ref(k) (eq. 30, 33)       -> the returned array (N,) [rad]

Choices where the paper is vague (docs/DESIGN.md):
- **Lateral distance** (``PelvisMpcParams.lateral_distance``): eq. (31)-(32) write
  Delta d_{FP,i,y} with the time index i and no k. Three readings:
  ``current`` (the default, the paper's read literally): the pelvis-to-foot lateral distance
  at tick i, held over the horizon, with the pelvis at the CoM MPC's own state now (the CoM the
  MPC plans from, the same model eq. (27) predicts with); ``predicted``: per horizon sample
  k, from the predicted CoM and the planned feet; ``nominal``: half the step width, constant.
  None of the three reads a measurement, so sensor noise and pushes never enter theta_ref
  (they reach the pelvis through eq. (19) only). ``current`` and ``predicted`` keep each
  distance at least ``lateral_floor`` from zero (sign kept: left foot +, right foot -): when
  the CoM sways over a support foot its distance to that foot shrinks to a few centimetres,
  and atan(k_pel dx / dy) would let that foot's small dx swing the angle. At the paper's step
  width the CoM MPC's state comes within 3.0-3.1 cm of the support foot, so the 3 cm floor
  barely binds (floors of 1 and 5 cm give the same seeded repeats at 0.30 and 0.40 m); it
  guards narrower steps. ``nominal`` makes the reference stationary when the pelvis is
  midway between the feet, so the pelvis barely turns in the DSP.
  Why ``current`` on the CoM MPC's state: it is the reading with the paper's early turn (the
  waist turns toward the coming swing from the start of the DSP: at 0.40 m the rate toward
  the swing at lift-off is +19.5 deg/s and the DSP moves 5.0 % of the step's waist range,
  against +8.1 deg/s and 0.2 % (predicted) and +9.4 deg/s and 0.1 % (nominal); the report's
  section-3 measure on the unseeded 10-step runs), and it reads no measurement. The three
  readings are equally robust: over the study's seeded repeats (``pelvic-walk simulate
  --method mpc --step-length L --steps 20 --seed N --set pelvis.lateral_distance=MODE``,
  seeds 0-9) at 0.15-0.40 m none falls or lands beyond 2 cm, and undisturbed (10 steps, step
  times 1.0-1.4 s, DSP shares 0.1-0.3, 0.15-0.45 m) they fall in the same cells, all at
  0.45 m. ``current`` once read the measured CoM estimate; since eq. (19)'s estimate no
  longer jumps at lift-off and touch-down (``controller/walker.py``) that reading differs
  from the MPC's state by wiggles at the phase changes only and gives the same repeats.
- **Sign**: a positive yaw (about +z) moves the left hip (at +y) backward. The pelvis must turn
  each hip *toward its own foot* (the forward foot's hip moves forward, so the forward leg's
  hip-to-foot distance shrinks), hence ``theta_ref = -mean(atan(k_pel dx / dy))``. The literal
  sign of eq. (31)-(32) would pull the leading hip back.
- Only x and y are used; the pelvis height (z_0 in eq. 27) plays no role in the angle.
"""

from __future__ import annotations

import math

import numpy as np

from controller.compiled import kernel
from controller.params import LATERAL_MODES

_CURRENT, _PREDICTED = LATERAL_MODES.index("current"), LATERAL_MODES.index("predicted")
HIP_HALF_WIDTH = 0.105  # [m] lateral distance from the pelvis centre to each hip joint


def lateral_distances(
    mode: str,
    p_pelvis: np.ndarray,
    p_left: np.ndarray,
    p_right: np.ndarray,
    p_pelvis_now: np.ndarray,
    p_left_now: np.ndarray,
    p_right_now: np.ndarray,
    half_width: float,
    floor: float,
) -> np.ndarray:
    """Delta d_{LFP,y}, Delta d_{RFP,y} of eq. (31)-(32) for each horizon sample, (N, 2) [m].

    Args:
        mode: ``"current"``, ``"predicted"`` or ``"nominal"`` (module docstring).
        p_pelvis, p_left, p_right: (N, 2) predicted pelvis (= CoM) and planned feet [m].
        p_pelvis_now, p_left_now, p_right_now: (2,) the CoM MPC's state and the feet now [m].
        half_width: half the step width [m] (the nominal distance).
        floor: [m] smallest |distance| (``current`` and ``predicted``).
    """
    p_pelvis = _rows(p_pelvis)
    out = np.empty((p_pelvis.shape[0], 2))
    _lateral(
        _mode_code(mode), p_pelvis, _rows(p_left), _rows(p_right),
        np.asarray(p_pelvis_now, dtype=float), np.asarray(p_left_now, dtype=float),
        np.asarray(p_right_now, dtype=float), float(half_width), float(floor), out,
    )  # fmt: skip
    return out


_MODE_CODES = {mode: i for i, mode in enumerate(LATERAL_MODES)}
_SIGNS = "the left foot's lateral distance must be > 0 and the right's < 0"


def _mode_code(mode: str) -> int:
    """The index of ``mode`` in ``LATERAL_MODES`` (what the kernels read)."""
    code = _MODE_CODES.get(mode)
    if code is None:
        raise ValueError(f"lateral distance mode must be one of {LATERAL_MODES}, got {mode!r}")
    return code


@kernel
def _lateral(
    mode, p_pelvis, p_left, p_right, p_pelvis_now, p_left_now, p_right_now, width, floor, out
):
    """:func:`lateral_distances` into ``out`` (N, 2), ``mode`` its index in ``LATERAL_MODES``."""
    if mode == _CURRENT:
        out[:] = _current_lateral(p_pelvis_now, p_left_now, p_right_now, floor, out.shape[0])
    elif mode == _PREDICTED:
        out[:] = _predicted_lateral(p_pelvis, p_left, p_right, floor)
    else:  # nominal: half the step width
        out[:, 0] = width
        out[:, 1] = -width


@kernel
def _floored(left, right, floor):
    """The left foot's lateral distance (at +y of the pelvis) at least ``floor``, the right's
    (at -y) at most -floor (NaN passes, as np.maximum)."""
    return (floor if left < floor else left), (-floor if right > -floor else right)


@kernel
def _current_lateral(p_pelvis_now, p_left_now, p_right_now, floor, n):
    """(n, 2) the ``current`` lateral distances, held over the horizon: the left and right
    feet's y from the pelvis's now, floored."""
    left, right = _floored(p_left_now[1] - p_pelvis_now[1], p_right_now[1] - p_pelvis_now[1], floor)
    out = np.empty((n, 2))
    out[:, 0] = left
    out[:, 1] = right
    return out


@kernel
def _predicted_lateral(p_pelvis, p_left, p_right, floor):
    """(N, 2) the ``predicted`` lateral distances: per sample, the feet's y from the
    pelvis's, floored."""
    n = p_pelvis.shape[0]
    out = np.empty((n, 2))
    for k in range(n):
        out[k, 0], out[k, 1] = _floored(
            p_left[k, 1] - p_pelvis[k, 1], p_right[k, 1] - p_pelvis[k, 1], floor
        )
    return out


@kernel
def _reference_angles(p_pelvis, p_left, p_right, k_pel, lateral):
    """(N,) eq. (28)-(33) sample by sample: dx per foot, atan(k_pel dx / dy) per foot, minus
    their mean (sign rule of the module docstring); ``lateral`` has N rows or one, held."""
    n = p_pelvis.shape[0]
    out = np.empty(n)
    for k in range(n):
        i = k if lateral.shape[0] > 1 else 0
        dx_left = p_left[k, 0] - p_pelvis[k, 0]  # eq. (28)
        dx_right = p_right[k, 0] - p_pelvis[k, 0]  # eq. (29)
        left = math.atan(k_pel * dx_left / lateral[i, 0])  # eq. (31)
        right = math.atan(k_pel * dx_right / lateral[i, 1])  # eq. (32)
        out[k] = -0.5 * (left + right)  # eq. (30), (33)
    return out


def reference_pelvic_angles(
    p_pelvis: np.ndarray,
    p_left: np.ndarray,
    p_right: np.ndarray,
    k_pel: float,
    lateral: np.ndarray,
) -> np.ndarray:
    """Reference pelvic yaw for each predicted sample, eq. (28)-(33).

    Args:
        p_pelvis: (N, 2) predicted pelvis (= CoM) x, y positions [m], eq. (27).
        p_left: (N, 2) planned left-foot x, y positions at the same instants [m].
        p_right: (N, 2) planned right-foot x, y positions [m].
        k_pel: gain of eq. (31)-(32) (share of the step made by the pelvic rotation).
        lateral: (N, 2) pelvis-to-foot lateral distances [left (> 0), right (< 0)] [m]
            (:func:`lateral_distances`).

    Returns:
        (N,) reference pelvic angles theta_ref(k) [rad], positive about +z.
    """
    lateral = np.asarray(lateral, dtype=float)
    if lateral[0, 0] <= 0.0 or lateral[0, 1] >= 0.0:  # held over the horizon, or per sample
        raise ValueError(_SIGNS)
    return _reference_angles(_rows(p_pelvis), _rows(p_left), _rows(p_right), float(k_pel), lateral)


@kernel
def _reference_step(mode, com, left, right, com_now, left_now, right_now, width, k, lateral, ref):
    """:func:`_lateral` (``k``: (floor, k_pel)) into ``lateral`` (N, 2) and eq. (28)-(33)
    into ``ref`` (N,); returns whether the first row's distances have the right signs."""
    _lateral(mode, com, left, right, com_now, left_now, right_now, width, k[0], lateral)
    if lateral[0, 0] <= 0.0 or lateral[0, 1] >= 0.0:
        return False
    ref[:] = _reference_angles(com, left, right, k[1], lateral)
    return True


def reference_with_lateral(
    mode: str,
    p_pelvis: np.ndarray,
    p_left: np.ndarray,
    p_right: np.ndarray,
    p_pelvis_now: np.ndarray,
    p_left_now: np.ndarray,
    p_right_now: np.ndarray,
    half_width: float,
    floor_and_gain: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """(theta_ref (N,), lateral (N, 2)): :func:`lateral_distances` then
    :func:`reference_pelvic_angles` in one compiled call (the walker's tick), for float
    arrays of rows (N, 2) and points (2,), or of 3-D points (their x, y read: the plan's sole
    rows as they are); ``floor_and_gain``: (lateral floor, k_pel)."""
    n = p_pelvis.shape[0]
    lateral, ref = np.empty((n, 2)), np.empty(n)
    ok = _reference_step(
        _mode_code(mode), p_pelvis, p_left, p_right, p_pelvis_now, p_left_now, p_right_now,
        float(half_width), floor_and_gain, lateral, ref,
    )  # fmt: skip
    if not ok:
        raise ValueError(_SIGNS)
    return ref, lateral


def _rows(a: np.ndarray) -> np.ndarray:
    """``a`` as a float array of rows (N, 2) (one row if it is a single point)."""
    a = np.asarray(a, dtype=float)
    return a if a.ndim == 2 else a.reshape(1, -1)


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
