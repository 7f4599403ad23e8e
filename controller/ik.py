"""QP inverse kinematics of the lower body, eq. (39)-(40) of Park & Park (2022).

Decision variable: the 13 lower-body joint velocities q_dot = [waist yaw, left leg (6),
right leg (6)] (eq. 6), the order of ``LOWER_JOINTS``. The QP is

    min  1/2 ||J_low q_dot - v_des||^2 + damping/2 ||q_dot||^2 (+ redundancy term)     (39)
    s.t. max((q_min - q)/dt, -v_max) <= q_dot <= min((q_max - q)/dt, v_max)
         waist row: pinned at a rate or free (below)

and the caller sets q_des = q + dt q_dot (eq. 40).

Paper symbols -> code names:
    J_low (eq. 9, 12 x 13, pelvis frame) -> ``J_low``; X_dot_f,d -> ``v_des`` (12,) =
    [left foot twist (6); right foot twist (6)], each [linear (3); angular (3)] in the pelvis
    frame (Pinocchio's LOCAL_WORLD_ALIGNED ordering, expressed in the pelvis frame);
    q_low,cur -> ``q_low``; q_low,min/max -> ``q_min``/``q_max``; Delta t -> ``dt``;
    q_dot_low,min/max -> +-``params.joint_speed_limit``; theta_dot_{i+1} -> ``waist_rate``.

The waist row is data, ``waist_rate``: what the tick's pelvis strategy asked for
(``controller.strategy``; docs/DESIGN.md, "The three methods"):
- a rate [rad/s]: the waist row l = u = that rate, **clipped into the waist's joint-limit /
  speed bounds** so the QP always stays feasible. Method ``mpc`` pins the pelvic MPC's
  theta_dot_{i+1} (the MPC already keeps the angle within +-45 deg, inside the joint range;
  the clip only matters if the two limits disagree), method ``fixed`` pins 0.
- ``None``: the waist is free (method ``redundancy``, ref. [21]); the motion comes from the
  redundancy (the damping term spreads joint motion onto the waist when that reduces the
  legs' velocities, i.e. during the swing) and a regularisation pulls the waist toward 0
  using the current state only (no prediction):

      redundancy_weight/2 * (q_waist + dt q_dot_waist)^2        [rad^2]

  i.e. the squared waist angle one control period ahead. Equivalently
  ``(w dt^2)/2 (q_dot_waist + q_waist/dt)^2``: a rate task toward the one-tick dead-beat rate,
  weighted w dt^2. Against the damping it produces, in double support (feet still, so only
  the 1-D null space of J_low moves), a first-order decay of the waist angle with time
  constant about ``damping |n|^2 / (w dt)`` where n is the null-space vector scaled to a unit
  waist component (|n|^2 ~ 2-4): ~1 s with the defaults (damping 1e-4, w 0.05, dt 5 ms), the
  slow decay toward 0 of the paper's Fig. 8. Dividing by dt^2 instead (a rate residual
  comparable to the foot task) would snap the waist back within a few ticks.
"""

from __future__ import annotations

import math

import numpy as np

from controller.compiled import daqp_call_new_hessian, kernel
from controller.explain import ActiveConstraint, QpExplain, explain_qp, joint_bound
from controller.params import IkParams
from controller.qp import QP, QpSolver, frozen
from models.dyros_jet import LOWER_JOINTS

WAIST = 0  # index of the waist yaw in q_low (13,)
N_LOW = 13
# The bound rows' matrix, one shared read-only object: the QP solver never re-factors it
# (controller.qp tracks frozen matrices by identity).
BOUND_ROWS = frozen(np.eye(N_LOW))


@kernel
def velocity_bounds(q, q_min, q_max, dt, speed_limit):
    """Joint-angle limits as velocity bounds intersected with |q_dot| <= speed_limit.

    A joint already beyond a limit gets a bound that moves it back (at most ``speed_limit``),
    so ``lo <= hi`` always holds. ``q``, ``q_min``, ``q_max``: arrays of one shape [rad].

    Returns:
        (lo, hi), each shaped like ``q`` [rad/s].
    """
    lo = np.minimum(np.maximum((q_min - q) / dt, -speed_limit), speed_limit)
    hi = np.minimum(np.maximum((q_max - q) / dt, -speed_limit), speed_limit)
    return lo, np.maximum(hi, lo)


@kernel
def _ik_qp(P, J, v, q, q_min, q_max, dt, speed_limit, damping, waist_rate, weight):
    """Eq. (39) on J'J (``P`` on entry, in place): P = J'J + damping I, c = -J'v, the bounds
    lo <= q_dot <= hi, and the waist row (:func:`build_ik`)."""
    for i in range(P.shape[0]):
        P[i, i] += damping  # + damping I
    c = -(J.T @ v)  # (13,)
    lo, hi = velocity_bounds(q, q_min, q_max, dt, speed_limit)
    if waist_rate is None:  # free: w/2 (q_w + dt qd_w)^2 = w dt^2/2 qd_w^2 + w dt q_w qd_w + ..
        P[WAIST, WAIST] += weight * dt * dt
        c[WAIST] += weight * dt * q[WAIST]
    else:  # pinned at the rate, clipped into the waist's bounds
        w = waist_rate
        if lo[WAIST] > w:
            w = lo[WAIST]
        if hi[WAIST] < w:
            w = hi[WAIST]
        lo[WAIST] = hi[WAIST] = w
    return P, c, lo, hi


def build_ik(
    J_low: np.ndarray,
    v_des: np.ndarray,
    q_low: np.ndarray,
    q_min: np.ndarray,
    q_max: np.ndarray,
    params: IkParams,
    dt: float,
    waist_rate: float | None,
) -> QP:
    """The QP of eq. (39) for one tick.

    Args:
        J_low: (12, 13) lower-body Jacobian in the pelvis frame (eq. 9).
        v_des: (12,) desired foot twists [left; right], each [v (3) m/s; omega (3) rad/s].
        q_low: (13,) current (commanded) lower-body joint angles [rad].
        q_min, q_max: (13,) joint limits [rad].
        params: ``damping``, ``joint_speed_limit``, ``redundancy_weight``.
        dt: control period [s].
        waist_rate: [rad/s] the waist's rate the strategy asked for, pinned (clipped into
            its bounds): the pelvic MPC's theta_dot_{i+1}, or 0 for a fixed pelvis; None
            leaves the waist free with the redundancy regularisation (module docstring).

    Returns:
        QP with variable q_dot (13,), A = identity (13 bound rows).
    """
    J = np.asarray(J_low, dtype=float)
    # J'J by numpy: its matmul sees the transposed pair and computes a symmetric product
    # (BLAS syrk), exactly symmetric, where a general product could differ by rounding
    P, c, lo, hi = _ik_qp(
        J.T @ J,
        J,
        np.asarray(v_des, dtype=float),
        np.asarray(q_low, dtype=float),
        np.asarray(q_min, dtype=float),
        np.asarray(q_max, dtype=float),
        dt,
        params.joint_speed_limit,
        params.damping,
        None if waist_rate is None else float(waist_rate),
        params.redundancy_weight,
    )
    return QP(P, c, BOUND_ROWS, lo, hi)


@kernel
def foot_targets(p_left, v_left, p_right, v_right, pelvis, v_pelvis):
    """The feet's targets relative to the pelvis: positions (3,) and feed-forward twists (6,)
    [linear; angular] (the feet do not turn), left and right, from their world positions and
    velocities (3,) and the pelvis's."""
    v_ff_l = np.zeros(6)
    v_ff_l[:3] = v_left - v_pelvis
    v_ff_r = np.zeros(6)
    v_ff_r[:3] = v_right - v_pelvis
    return p_left - pelvis, p_right - pelvis, v_ff_l, v_ff_r


@kernel
def _step(
    T_left, T_right, feet, pelvis, v_pelvis, JtJ, J, q, limits, k, waist_rate, H, qp_vectors, x, *ws
):
    """Eq. (39) for flat feet, built and solved in one compiled step (:func:`solve_ik_step`):
    the feet's targets from row 1 of the plan's (p_left, v_left, p_right, v_right)
    ``feet``, relative to the pelvis (``pelvis``, ``v_pelvis``), their twists
    (:func:`_foot_twists`), the QP (:func:`_ik_qp` on J'J = ``JtJ``) written into DAQP's
    ``H`` and ``qp_vectors`` (c, lo, hi), solved by DAQP into ``x``; returns (status, flag).
    ``limits``: (q_min, q_max); ``k``: (foot gain, dt, speed limit, damping, weight)."""
    p_left, v_left, p_right, v_right = feet
    p_des_l, p_des_r, v_ff_l, v_ff_r = foot_targets(
        p_left[1], v_left[1], p_right[1], v_right[1], pelvis, v_pelvis
    )
    v_des = _foot_twists(T_left, _FLAT, p_des_l, v_ff_l, T_right, _FLAT, p_des_r, v_ff_r, k[0])
    P, c, lo, hi = _ik_qp(
        JtJ, J, v_des, q, limits[0], limits[1], k[1], k[2], k[3], waist_rate, k[4]
    )
    return daqp_call_new_hessian(P, c, lo, hi, H, qp_vectors, x, *ws)


def solve_ik_step(
    solver: QpSolver,
    J_low: np.ndarray,
    T_left: np.ndarray,
    T_right: np.ndarray,
    feet: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    pelvis: np.ndarray,
    v_pelvis: np.ndarray,
    q_low: np.ndarray,
    limits: np.ndarray,
    constants: np.ndarray,
    waist_rate: float | None,
) -> tuple[np.ndarray, bool] | None:
    """The walker's IK of a tick: :func:`foot_targets`, :func:`flat_foot_velocity_command`,
    :func:`build_ik` and :func:`solve_ik` in one compiled step (the same arithmetic), or None
    when the solver runs no compiled step (then the caller makes those four calls).

    Args:
        J_low: (12, 13); T_left, T_right: (4, 4) the soles' poses in the pelvis frame.
        feet: the plan's (p_left, v_left, p_right, v_right) rows, row 1 the next tick's.
        pelvis, v_pelvis: (3,) the desired pelvis's position and velocity (world) [m, m/s].
        q_low: (13,); limits: (2, 13) q_min, q_max [rad].
        constants: (5,) foot gain, dt [s], joint speed limit [rad/s], damping, redundancy
            weight (:func:`ik_constants`).
        waist_rate: as :func:`build_ik`.
    """
    args = solver.step_args(None, BOUND_ROWS)
    if args is None:
        return None
    vectors = np.empty((3, N_LOW))
    x = np.zeros(N_LOW)
    H = solver.hessian
    # J'J by numpy (as build_ik): a symmetric product (BLAS syrk), exactly symmetric
    status, flag = _step(
        T_left, T_right, feet, pelvis, v_pelvis, J_low.T @ J_low, J_low, q_low, limits, constants,
        waist_rate, H, vectors, x, *args,
    )  # fmt: skip
    c, lo, hi = vectors
    res = solver.settle(QP(H, c, BOUND_ROWS, lo, hi), x, status, flag, args[1])
    return res.x, res.ok


def ik_constants(params: IkParams, dt: float) -> np.ndarray:
    """(5,) the constants of :func:`solve_ik_step`: foot gain, dt, speed limit, damping,
    redundancy weight."""
    return np.array(
        [params.foot_gain, dt, params.joint_speed_limit, params.damping, params.redundancy_weight]
    )


def solve_ik(qp: QP, solver: QpSolver) -> tuple[np.ndarray, bool]:
    """Solve the IK QP; returns (q_dot (13,), ok). On failure q_dot is the solver's fallback
    (its previous solution, or zeros)."""
    res = solver.solve(qp)
    return res.x, res.ok


def explain_ik(
    qp: QP,
    solver: QpSolver,
    J_low: np.ndarray,
    q_min: np.ndarray,
    q_max: np.ndarray,
    params: IkParams,
    dt: float,
) -> QpExplain:
    """What the IK's last solve (``qp``, by ``solver``) did: the cost of eq. (39) split into
    the left foot's task, the right foot's, the damping and (free waist) the waist's
    regularisation; each joint at an angle or speed bound, and the waist's pinned rate.

    The desired foot twists are recovered from the QP's linear term (c = -J'v on the rows
    the waist's regularisation leaves alone), so the tick keeps nothing for this."""
    res = solver.last_result
    assert res is not None and solver.last_qp is qp, "explain right after the solve"
    J = np.asarray(J_low, dtype=float)
    x = res.x if res.ok else np.zeros(N_LOW)  # the walker holds the last command on failure
    w, d = params.redundancy_weight, params.damping
    extra = qp.P[WAIST, WAIST] - (J[:, WAIST] @ J[:, WAIST]) - d
    free = w > 0.0 and abs(extra - w * dt * dt) <= 1e-9 * (1.0 + abs(extra))
    cols = slice(1, None) if free else slice(None)  # the rows c = -J'v holds exactly
    v, *_ = np.linalg.lstsq(J[:, cols].T, -qp.q[cols], rcond=None)
    q_waist = (qp.q[WAIST] + J[:, WAIST] @ v) / (w * dt) if free else 0.0
    r = J @ x - v
    terms = {
        "left foot task": 0.5 * float(r[:6] @ r[:6]),
        "right foot task": 0.5 * float(r[6:] @ r[6:]),
        "damping": 0.5 * d * float(x @ x),
    }
    if free:
        terms["waist regularisation (redundancy)"] = 0.5 * w * (q_waist + dt * x[WAIST]) ** 2
    pinned = not free and qp.l[WAIST] == qp.u[WAIST]
    speed = params.joint_speed_limit

    def name(row: int, lam: float, bound: float) -> ActiveConstraint:
        if row == WAIST and pinned:
            return ActiveConstraint(
                f"waist rate pinned by the strategy ({bound:+.3f} rad/s)",
                "pinned", "pinned", lam, bound, row, LOWER_JOINTS[WAIST],
            )  # fmt: skip
        return joint_bound(
            row, LOWER_JOINTS[row], lam, bound, speed, (float(q_min[row]), float(q_max[row]))
        )

    return explain_qp(
        "ik",
        qp,
        x,
        res.ok,
        res.status,
        solver,
        terms,
        name,
        "held the last command: zero joint velocities this tick",
        0.5 * float(v @ v) + (0.5 * w * q_waist**2 if free else 0.0),
    )


@kernel
def log3(R):
    """Rotation vector (axis * angle, (3,)) of a rotation matrix R (3, 3); angle in [0, pi]."""
    r00, r01, r02 = R[0, 0], R[0, 1], R[0, 2]
    r10, r11, r12 = R[1, 0], R[1, 1], R[1, 2]
    r20, r21, r22 = R[2, 0], R[2, 1], R[2, 2]
    cos = 0.5 * ((r00 + r11 + r22) - 1.0)
    cos = -1.0 if cos < -1.0 else (1.0 if cos > 1.0 else cos)
    angle = math.acos(cos)
    w = np.array([r21 - r12, r02 - r20, r10 - r01])  # 2 sin(a) axis
    if angle < 1e-6:
        return 0.5 * w  # first order: R ~ I + [phi]x
    if math.pi - angle > 1e-4:
        return angle / (2.0 * math.sin(angle)) * w
    # Near pi: axis from the diagonal of R = 2 a a' - I (+ small antisymmetric part).
    B = 0.5 * (R + np.eye(3))
    i = int(np.argmax(np.diag(B)))
    axis = B[:, i] / np.sqrt(max(B[i, i], 1e-12))
    axis = axis / np.linalg.norm(axis)
    if axis @ w < 0.0:
        axis = -axis
    return angle * axis


@kernel
def _pose_error(T_cur, R_des, p_des):
    """[p_des - p_cur; log3(R_des R_cur^T)] (6,) of the pose T_cur (4, 4)."""
    e = np.empty(6)
    e[:3] = p_des - T_cur[:3, 3]
    e[3:] = log3(R_des @ np.ascontiguousarray(T_cur[:3, :3].T))
    return e


@kernel
def _foot_twists(T_left, R_left, p_left, v_ff_left, T_right, R_right, p_right, v_ff_right, gain):
    """(12,) feed-forward + gain * pose error, left then right (:func:`foot_velocity_command`)."""
    v = np.empty(12)
    v[:6] = v_ff_left + gain * _pose_error(T_left, R_left, p_left)
    v[6:] = v_ff_right + gain * _pose_error(T_right, R_right, p_right)
    return v


_FLAT = np.eye(3)  # R_des of a flat foot


def _rotation_and_position(T_des: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R_des (3, 3), p_des (3,)) of a desired pose (4, 4) or position (3,) (a flat foot)."""
    T_des = np.asarray(T_des, dtype=float)
    if T_des.ndim == 1:
        return _FLAT, T_des
    return np.ascontiguousarray(T_des[:3, :3]), np.ascontiguousarray(T_des[:3, 3])


def pose_error(T_cur: np.ndarray, T_des: np.ndarray) -> np.ndarray:
    """[p_des - p_cur; log3(R_des R_cur^T)] (6,), both poses (4, 4) in the same frame.

    ``T_des`` may be a position (3,): a flat foot, R_des = I, so the rotation error is
    log3(R_cur^T) (the walker's feet never turn).
    """
    return _pose_error(np.asarray(T_cur, dtype=float), *_rotation_and_position(T_des))


def flat_foot_velocity_command(
    T_cur_left: np.ndarray,
    p_des_left: np.ndarray,
    v_ff_left: np.ndarray,
    T_cur_right: np.ndarray,
    p_des_right: np.ndarray,
    v_ff_right: np.ndarray,
    gain: float,
) -> np.ndarray:
    """:func:`foot_velocity_command` for flat feet given by their desired positions (3,), the
    walker's case, with float arrays taken as they are (no conversions: once a tick)."""
    return _foot_twists(
        T_cur_left, _FLAT, p_des_left, v_ff_left, T_cur_right, _FLAT, p_des_right, v_ff_right,
        float(gain),
    )  # fmt: skip


def foot_velocity_command(
    T_cur_left: np.ndarray,
    T_des_left: np.ndarray,
    v_ff_left: np.ndarray,
    T_cur_right: np.ndarray,
    T_des_right: np.ndarray,
    v_ff_right: np.ndarray,
    gain: float,
) -> np.ndarray:
    """Desired foot twists for eq. (39): feed-forward + gain * pose error, per foot.

    All poses (4, 4) and twists (6,) = [linear; angular] are in the pelvis frame; a desired
    pose given as a position (3,) is a flat foot (:func:`pose_error`). The rotation error
    ``log3(R_des R_cur^T)`` is expressed in that same frame, matching the angular part of the
    twist.

    Returns:
        (12,) [left twist (6); right twist (6)].
    """
    R_left, p_left = _rotation_and_position(T_des_left)
    R_right, p_right = _rotation_and_position(T_des_right)
    return _foot_twists(
        np.asarray(T_cur_left, dtype=float),
        R_left,
        p_left,
        np.asarray(v_ff_left, dtype=float),
        np.asarray(T_cur_right, dtype=float),
        R_right,
        p_right,
        np.asarray(v_ff_right, dtype=float),
        float(gain),
    )
