"""Arm swing that cancels the lower body's yaw angular momentum, eq. (41)-(43) of Park & Park.

    h_low = A_low,yaw . q_dot_low                                                   (41)
    h_up  = A_up,yaw  . q_dot_up                                                    (42)
    min_{q_dot_up}  omega1/2 (h_low + h_up)^2
                  + omega2/2 ||q_up_init - (q_up + dt q_dot_up)||^2
                  + omega3/2 ||q_dot_up||^2                                          (43)
    s.t. max((q_min - q_up)/dt, -qd_max) <= q_dot_up <= min((q_max - q_up)/dt, qd_max)

Paper symbols -> code names:
    A^CMM_low,yaw (13,) -> ``a_low_yaw``; A^CMM_up,yaw (4,) -> ``a_up_yaw`` (the yaw row of
    Pinocchio's centroidal momentum matrix, columns of the 4 arm joints of
    ``ARM_QP_JOINTS`` = [L shoulder pitch, L elbow, R shoulder pitch, R elbow]);
    q_dot_low -> ``q_dot_low`` (the IK's solution of this tick, eq. 40); q_up,cur -> ``q_up``;
    q_up^init -> ``q_up_init``; omega1..3 -> ``params.omega1..omega3``; Delta t -> ``dt``.

Choices where the paper is vague:
- The pose term of eq. (43) is read as the pose *after* this tick, q_up + dt q_dot_up (a
  velocity-level QP); its effective pull is a first-order return toward q_up^init with time
  constant about ``(omega3 + omega2 dt^2) / (omega2 dt)`` (2 s with the paper's weights).
- With omega2 = omega3 = 0 the Hessian is rank one (singular); OSQP copes, DAQP may not.

QP: P = omega1 a a' + (omega2 dt^2 + omega3) I, q = omega1 h_low a - omega2 dt (q_init - q_up).
"""

from __future__ import annotations

import numpy as np

from controller.compiled import daqp_call_new_hessian, kernel
from controller.explain import ActiveConstraint, QpExplain, explain_qp, joint_bound
from controller.ik import velocity_bounds
from controller.params import ArmParams
from controller.qp import QP, QpSolver, frozen
from models.dyros_jet import ARM_QP_JOINTS


@kernel
def yaw_momentum(a_yaw, q_dot):
    """Yaw angular momentum a_yaw . q_dot [kg m^2/s] (eq. 41 or 42) of float arrays."""
    return np.dot(a_yaw, q_dot)


@kernel
def _arm_cost(a_low_yaw, q_dot_low, a, q, q_up_init, w1, w2, w3, dt):
    """P (n, n) and q (n,) of eq. (43): h_low = a_low . q_dot_low (eq. 41),
    P = omega1 a a' + (omega2 dt^2 + omega3) I, q = omega1 h_low a - omega2 dt (q_init - q)."""
    h_low = yaw_momentum(a_low_yaw, q_dot_low)
    r = q_up_init - q  # (n,) pose error [rad]
    n = a.shape[0]
    P = w1 * (a.reshape(n, 1) * a.reshape(1, n))  # omega1 a a'
    for i in range(n):
        P[i, i] += w2 * dt * dt + w3  # + (omega2 dt^2 + omega3) I
    return P, w1 * h_low * a - w2 * dt * r


def build_arm_qp(
    a_low_yaw: np.ndarray,
    q_dot_low: np.ndarray,
    a_up_yaw: np.ndarray,
    q_up: np.ndarray,
    q_up_init: np.ndarray,
    q_min: np.ndarray,
    q_max: np.ndarray,
    qd_max: float,
    params: ArmParams,
    dt: float,
) -> QP:
    """The QP of eq. (43).

    Args:
        a_low_yaw: (13,) yaw row of the centroidal momentum matrix, lower-body columns.
        q_dot_low: (13,) lower-body joint velocities of this tick [rad/s].
        a_up_yaw: (4,) yaw row, columns of the 4 arm joints.
        q_up: (4,) current arm joint angles [rad].
        q_up_init: (4,) initial (walk-ready) arm joint angles [rad].
        q_min, q_max: (4,) arm joint limits [rad].
        qd_max: arm joint speed bound [rad/s] (10 in the authors' code).
        params: weights omega1..omega3.
        dt: control period [s].

    Returns:
        QP with variable q_dot_up (4,), A = identity (4 bound rows).
    """
    a = np.asarray(a_up_yaw, dtype=float)
    q = np.asarray(q_up, dtype=float)
    P, c = _arm_cost(
        np.asarray(a_low_yaw, dtype=float),
        np.asarray(q_dot_low, dtype=float),
        a,
        q,
        np.asarray(q_up_init, dtype=float),
        params.omega1,
        params.omega2,
        params.omega3,
        dt,
    )
    lo, hi = velocity_bounds(
        q, np.asarray(q_min, dtype=float), np.asarray(q_max, dtype=float), dt, qd_max
    )
    return QP(P, c, _bound_rows(a.shape[0]), lo, hi)


_BOUND_ROWS: dict[int, np.ndarray] = {}


def _bound_rows(n: int) -> np.ndarray:
    """(n, n) identity, one shared read-only object per size (controller.qp)."""
    if n not in _BOUND_ROWS:
        _BOUND_ROWS[n] = frozen(np.eye(n))
    return _BOUND_ROWS[n]


@kernel
def _step(a_low_yaw, q_dot_low, a, q, q_up_init, limits, k, H, qp_vectors, x, *workspace):
    """Eq. (43) built (:func:`_arm_cost`, :func:`velocity_bounds`) into DAQP's
    ``H`` and ``qp_vectors`` (c, lo, hi) and solved into ``x`` (:func:`solve_arm_step`);
    returns (status, flag). ``limits``: (q_min, q_max); ``k``: (omega1, omega2, omega3, dt,
    qd_max)."""
    P, c = _arm_cost(a_low_yaw, q_dot_low, a, q, q_up_init, k[0], k[1], k[2], k[3])
    lo, hi = velocity_bounds(q, limits[0], limits[1], k[3], k[4])
    return daqp_call_new_hessian(P, c, lo, hi, H, qp_vectors, x, *workspace)


def solve_arm_step(
    solver: QpSolver,
    a_low_yaw: np.ndarray,
    q_dot_low: np.ndarray,
    a_up_yaw: np.ndarray,
    q_up: np.ndarray,
    q_up_init: np.ndarray,
    limits: np.ndarray,
    constants: np.ndarray,
) -> tuple[np.ndarray, bool] | None:
    """:func:`build_arm_qp` and :func:`solve_arm` in one compiled step (the same arithmetic),
    or None when the solver runs no compiled step (then the caller makes those two calls).
    ``limits``: (2, n) q_min, q_max; ``constants``: :func:`arm_constants`."""
    n = a_up_yaw.shape[0]
    A = _bound_rows(n)
    args = solver.step_args(None, A)
    if args is None:
        return None
    vectors, x, H = np.empty((3, n)), np.zeros(n), solver.hessian
    status, flag = _step(
        a_low_yaw, q_dot_low, a_up_yaw, q_up, q_up_init, limits, constants, H, vectors, x, *args
    )
    c, lo, hi = vectors
    res = solver.settle(QP(H, c, A, lo, hi), x, status, flag, args[1])
    return res.x, res.ok


def arm_constants(params: ArmParams, dt: float, qd_max: float) -> np.ndarray:
    """(5,) the constants of :func:`solve_arm_step`: omega1..3, dt [s], qd_max [rad/s]."""
    return np.array([params.omega1, params.omega2, params.omega3, dt, qd_max])


def solve_arm(qp: QP, solver: QpSolver) -> tuple[np.ndarray, bool]:
    """Solve eq. (43); returns (q_dot_up (4,), ok). On failure: the solver's fallback."""
    res = solver.solve(qp)
    return res.x, res.ok


def explain_arm(
    qp: QP,
    solver: QpSolver,
    a_up_yaw: np.ndarray,
    h_low: float,
    q_min: np.ndarray,
    q_max: np.ndarray,
    qd_max: float,
    params: ArmParams,
    dt: float,
) -> QpExplain:
    """What the arm QP's last solve (``qp``) did: the cost of eq. (43) split into the yaw
    momentum left over, the pull back to the arms' pose and the arm speed; each arm joint at
    a bound. ``h_low``: the lower body's yaw momentum this tick (eq. 41); the pose error is
    recovered from the QP's linear term."""
    res = solver.last_result
    assert res is not None and solver.last_qp is qp, "explain right after the solve"
    x = res.x if res.ok else np.zeros(len(a_up_yaw))  # the walker holds the arms on failure
    a = np.asarray(a_up_yaw, dtype=float)
    w1, w2, w3 = params.omega1, params.omega2, params.omega3
    # q = omega1 h_low a - omega2 dt r  ->  the pose error r = q_init - q_up
    r = (w1 * h_low * a - qp.q) / (w2 * dt) if w2 > 0.0 else np.zeros_like(a)
    pose = r - dt * x
    terms = {
        "yaw momentum left over (omega1)": 0.5 * w1 * float(h_low + a @ x) ** 2,
        "back to the arm pose (omega2)": 0.5 * w2 * float(pose @ pose),
        "arm speed (omega3)": 0.5 * w3 * float(x @ x),
    }

    def name(row: int, lam: float, bound: float) -> ActiveConstraint:
        return joint_bound(
            row, ARM_QP_JOINTS[row], lam, bound, qd_max, (float(q_min[row]), float(q_max[row]))
        )

    constant = 0.5 * w1 * h_low**2 + 0.5 * w2 * float(r @ r)
    return explain_qp(
        "arm_swing", qp, x, res.ok, res.status, solver, terms, name,
        "held the arms: zero arm velocities this tick", constant,
    )  # fmt: skip
