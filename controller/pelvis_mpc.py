"""Pelvic-rotation MPC, eq. (34)-(38) of Park & Park (2022).

State theta_bar = [theta, theta_dot] (waist yaw angle [rad] and rate [rad/s]), input the yaw
acceleration theta_ddot [rad/s^2], sampled at T_p over N samples:

    theta_bar_{k+1} = A theta_bar_k + B theta_ddot_k,   A = [[1, T_p], [0, 1]],
                                                        B = [T_p^2 / 2, T_p]          (34)
    Theta_{i+1} = P_A theta_bar_i + P_B U                                             (35)
    min_U  alpha/2 ||Theta_ref - Theta_angle||^2 + beta/2 ||U||^2                    (37)
    s.t.   -angle_limit <= theta_k <= angle_limit   (k = 1..N)
           -acc_limit <= theta_ddot_k <= acc_limit  (k = 0..N-1)

Paper symbols -> code names:
    A_theta, B_theta -> ``self._A``, ``self._B``; P_A_theta, P_B_theta (eq. 35) ->
    ``self._PA`` (2N, 2), ``self._PB`` (2N, N) (rows interleaved [theta_1, theta_dot_1, ...]);
    Theta_angle rows -> ``self._PA_ang``, ``self._PB_ang``; Theta_pel^ref -> ``theta_ref``;
    Theta_ddot_i (eq. 36) -> U (N,), ``PelvisPlan.acc``; alpha_pel, beta_pel ->
    ``params.alpha``, ``params.beta``; Delta t of eq. (38) -> ``control_dt``.

**QP variable: the predicted angles Theta (N,), not U.** P_B's angle rows ``PB_ang`` (N, N)
are lower triangular with T_p^2/2 on the diagonal, hence invertible, so
``U = M (Theta - f)`` with ``M = PB_ang^-1`` and the free response ``f = PA_ang x0``. The
Hessian condensed onto U, ``alpha PB_ang' PB_ang + beta I``, has a condition number of 6e5
(beta 1e-6) to 4e7 (beta 1e-10, the paper's): OSQP then misses the exact optimum by
1e-3..1e-1 rad/s^2 and even reports failures. Onto Theta it is ``alpha I + beta M'M``
(condition ~1 + 6e7 beta / alpha at T_p = 0.1 s, N = 16: 63 at beta 1e-6, 1.006 at 1e-10),
and beta = 0 is a plain projection. The QP is

    min 1/2 Theta' (alpha I + beta M'M) Theta - (alpha ref + beta M'M f)' Theta
    s.t. -angle_limit <= Theta <= angle_limit                       (identity rows)
         s (-acc_limit + M f) <= s M Theta <= s (acc_limit + M f)   (s = T_p^2 / 2 scales rows)

and the inputs (and rates) of the plan are recovered from Theta. The prediction matrices
P_A, P_B of eq. (35) and M are built once per :meth:`PelvisMpc.set_params`.

Choices where the paper is vague:
- **Eq. (38)** is applied over *one control period* ``control_dt`` (5 ms), not one MPC sample:
  ``next_rate = theta_dot + control_dt u_0`` and
  ``next_angle = theta + control_dt theta_dot + control_dt^2 / 2 u_0``. ``next_rate`` is the
  waist-yaw velocity the IK pins (eq. 39).
- The yaw acceleration bound (not in the paper; the authors' code has one) keeps the inputs
  sane with the tiny input weight beta = 1e-10 of the paper; beta = 0 is allowed.
- **On failure** (infeasible start, e.g. |theta| beyond the limit with an outward rate the
  acceleration bound cannot stop, or a solver error) the plan is a *brake*: the rate decays to
  0 at the acceleration bound (``u = clip(-theta_dot / control_dt, +-acc_limit)`` in the first
  period, then whatever brings the rate to 0 on the predicted samples), ``ok=False``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.compiled import daqp_call, kernel
from controller.explain import ActiveConstraint, QpExplain, ahead_text, explain_qp, side_of
from controller.params import PelvisMpcParams
from controller.qp import QP, QpSolver, frozen


@dataclass(slots=True, eq=False)
class PelvisPlan:
    """Output of one pelvic-rotation MPC solve. Read-only by contract."""

    angles: np.ndarray  # (N,) predicted theta_k, k = 1..N [rad]
    rates: np.ndarray  # (N,) predicted theta_dot_k, k = 1..N [rad/s]
    acc: np.ndarray  # (N,) optimal inputs theta_ddot_k, k = 0..N-1 [rad/s^2]
    reference: np.ndarray  # (N,) theta_ref it tracked [rad]
    next_angle: float  # theta after ONE control period with the first input (eq. 38) [rad]
    next_rate: float  # theta_dot_{i+1} [rad/s]: the waist-yaw velocity pinned in the IK
    ok: bool


@kernel
def _qp_vectors(ref, x0, PA_ang, alpha, bMtM, sM, angle_limit, s_acc_limit):
    """The free response f = P_A,angle x0 (N,) of the state x0 = [theta, theta_dot] and the
    QP on Theta (module docstring) for the reference (N,): q = -alpha ref - beta M'M f (N,),
    l, u (2N,): the angle rows -angle_limit <= Theta <= angle_limit, the acceleration rows
    s (-acc_limit + M f) <= s M Theta <= s (acc_limit + M f) (``s_acc_limit`` = s acc_limit,
    ``sM`` = s M, ``bMtM`` = beta M'M)."""
    n = ref.shape[0]
    free = PA_ang @ x0  # (N,) angles with zero input
    q = -alpha * ref - bMtM @ free
    mf = sM @ free  # s M f
    lo = np.empty(2 * n)
    hi = np.empty(2 * n)
    lo[:n] = -angle_limit
    hi[:n] = angle_limit
    lo[n:] = -s_acc_limit + mf
    hi[n:] = s_acc_limit + mf
    return free, q, lo, hi


@kernel
def _inputs_and_rates(angles, free, M, PA_rate, PB_rate, x0):
    """The inputs U = M (Theta - f) (N,) that produce the angles Theta from the free response
    f, and the predicted rates theta_dot_1..N = P_A,rate x0 + P_B,rate U (eq. 35)."""
    u = M @ (angles - free)
    return u, PA_rate @ x0 + PB_rate @ u


@kernel
def _step(theta, theta_dot, theta_ref, maps, k, q, lo, hi, out, *workspace):
    """Eq. (37) built (:func:`_qp_vectors`) and solved by DAQP on the solver's workspace
    (``workspace``), the inputs and rates recovered (:func:`_inputs_and_rates`): ``out``
    (4, N) gets the angles, rates, inputs and the reference. Returns DAQP's (status, flag)
    and eq. (38)'s next angle and rate (valid when the status is 0).
    ``maps``: (PA_ang, beta M'M, s M, M, PA_rate, PB_rate); ``k``: (alpha, angle limit,
    s acc_limit, control dt)."""
    PA_ang, bMtM, sM, M, PA_rate, PB_rate = maps
    x0 = np.array([theta, theta_dot])
    out[3] = theta_ref
    free, q[:], lo[:], hi[:] = _qp_vectors(out[3], x0, PA_ang, k[0], bMtM, sM, k[1], k[2])
    status, flag = daqp_call(q, lo, hi, out[0], *workspace)
    out[2], out[1] = _inputs_and_rates(out[0], free, M, PA_rate, PB_rate, x0)
    dt, u0 = k[3], out[2, 0]
    return status, flag, theta + dt * theta_dot + 0.5 * dt * dt * u0, theta_dot + dt * u0


class PelvisMpc:
    """Pelvic-rotation MPC (eq. 34-38), condensed onto the angles, with a warm-started solver."""

    def __init__(
        self,
        params: PelvisMpcParams,
        sample_time: float,
        n_samples: int,
        control_dt: float = 0.005,
        backend: str = "osqp",
    ):
        """Args:
        params: weights and limits (``alpha``, ``beta``, ``angle_limit_deg``, ``acc_limit``).
        sample_time: T_p [s], the MPC sample.
        n_samples: N, samples in the horizon.
        control_dt: control period [s] over which the first input is applied (eq. 38).
        backend: ``"osqp"`` or ``"daqp"`` (see :mod:`controller.qp`).
        """
        self.control_dt = float(control_dt)
        self.solver = QpSolver(backend)
        self.set_params(params, sample_time, n_samples)

    def set_params(self, params: PelvisMpcParams, sample_time: float, n_samples: int) -> None:
        """Rebuild the prediction matrices (eq. 35) and the constant QP parts."""
        if sample_time <= 0.0 or n_samples < 1:
            raise ValueError(
                f"need sample_time > 0 and n_samples >= 1, got {sample_time}, {n_samples}"
            )
        n = int(n_samples)
        T = float(sample_time)
        shape_changed = getattr(self, "n_samples", None) != n
        self.params = params
        self.sample_time = T
        self.n_samples = n
        self._A = np.array([[1.0, T], [0.0, 1.0]])  # A_theta (2, 2)
        self._B = np.array([0.5 * T * T, T])  # B_theta (2,)
        powers = [np.eye(2)]
        for _ in range(n):
            powers.append(self._A @ powers[-1])
        self._PA = np.vstack(powers[1:])  # (2N, 2): A, A^2, ..., A^N
        PB = np.zeros((2 * n, n))
        for k in range(n):  # block row k = state k+1
            for j in range(k + 1):
                PB[2 * k : 2 * k + 2, j] = powers[k - j] @ self._B
        self._PB = PB  # (2N, N)
        # angle rows (N, 2), (N, N) and rate rows, contiguous (the kernels' matrix products)
        self._PA_ang, self._PB_ang = (np.ascontiguousarray(a[0::2]) for a in (self._PA, self._PB))
        self._PA_rate, self._PB_rate = (np.ascontiguousarray(a[1::2]) for a in (self._PA, self._PB))
        self._M = np.linalg.inv(self._PB_ang)  # (N, N): U = M (Theta - f)
        a, b = params.alpha, params.beta
        self._MtM = self._M.T @ self._M
        self._P = frozen(a * np.eye(n) + b * self._MtM)  # (N, N)
        self._acc_scale = 0.5 * T * T  # s: makes the acceleration rows O(1)
        self._Acon = frozen(np.vstack([np.eye(n), self._acc_scale * self._M]))  # (2N, N)
        self._angle_limit = math.radians(params.angle_limit_deg)
        # Constant parts of the per-tick vectors (same arithmetic as written out in build).
        self._bMtM = b * self._MtM  # (N, N)
        self._sM = self._acc_scale * self._M  # (N, N)
        self._s_acc_limit = params.acc_limit * self._acc_scale
        # the compiled step's constants and the QP it writes each tick (q, l, u in place)
        self._maps = (self._PA_ang, self._bMtM, self._sM, self._M, self._PA_rate, self._PB_rate)
        self._k = np.array([a, self._angle_limit, self._s_acc_limit, self.control_dt])
        z = np.zeros(n)
        self._qp = QP(self._P, z, self._Acon, np.zeros(2 * n), np.zeros(2 * n))
        if shape_changed:
            self.solver.reset()

    def build(self, theta: float, theta_dot: float, theta_ref: np.ndarray) -> QP:
        """The QP of eq. (37) for the state [theta, theta_dot] and reference (N,).

        The QP's variable is the predicted angle vector Theta (N,) (see the module docstring);
        the inputs are ``self.inputs_from_angles(x, theta, theta_dot)``.
        """
        ref = np.asarray(theta_ref, dtype=float).reshape(-1)
        return self._build(ref, np.array([theta, theta_dot], dtype=float))[1]

    def _build(self, ref: np.ndarray, x0: np.ndarray) -> tuple[np.ndarray, QP]:
        """The free response f = P_A,angle x0 (N,) and the QP for the reference (N,)."""
        n = self.n_samples
        if ref.shape[0] != n:
            raise ValueError(f"theta_ref has {ref.shape[0]} samples, the MPC has {n}")
        free, q, lo, hi = _qp_vectors(
            ref,
            x0,
            self._PA_ang,
            self.params.alpha,
            self._bMtM,
            self._sM,
            self._angle_limit,
            self._s_acc_limit,
        )
        return free, QP(self._P, q, self._Acon, lo, hi)

    def solve(self, theta: float, theta_dot: float, theta_ref: np.ndarray) -> PelvisPlan:
        """Solve eq. (37) and integrate the first input over one control period (eq. 38)."""
        n = self.n_samples
        if not (
            isinstance(theta_ref, np.ndarray) and theta_ref.ndim == 1 and theta_ref.dtype == float
        ):  # (the walker's is: no conversion then)
            theta_ref = np.asarray(theta_ref, dtype=float).reshape(-1)
        theta, theta_dot = float(theta), float(theta_dot)
        args = self.solver.step_args(self._P, self._Acon)
        if args is not None and len(theta_ref) == n:  # eq. (37) and (38) in one compiled step
            qp, out = self._qp, np.empty((4, n))
            status, flag, next_angle, next_rate = _step(
                theta, theta_dot, theta_ref, self._maps, self._k, qp.q, qp.l, qp.u, out, *args
            )
            res = self.solver.settle(qp, out[0], status, flag, args[1])
            if res.ok:
                angles, rates, u, ref = out
                return PelvisPlan(angles, rates, u, ref, next_angle, next_rate, True)
            ref = out[3]  # the copy the plan keeps
            x0 = np.array([theta, theta_dot])
            free = self._build(ref, x0)[0]  # for the brake (as below)
        else:
            x0 = np.array([theta, theta_dot])
            ref = theta_ref.copy()  # a copy: the plan keeps it
            free, qp = self._build(ref, x0)
            res = self.solver.solve(qp)
        if res.ok:
            angles = res.x  # the QP's variable (module docstring)
        else:  # the brake's angles (eq. 35's angle rows)
            angles = free + self._PB_ang @ self._brake(theta_dot)
        u, rates = _inputs_and_rates(angles, free, self._M, self._PA_rate, self._PB_rate, x0)
        if res.ok:
            u0 = float(u[0])
        else:  # brake within this control period
            acc = self.params.acc_limit
            u0 = float(np.clip(-theta_dot / self.control_dt, -acc, acc))
        dt = self.control_dt
        next_rate = theta_dot + dt * u0
        next_angle = theta + dt * theta_dot + 0.5 * dt * dt * u0
        return PelvisPlan(angles, rates, u, ref, next_angle, next_rate, res.ok)

    def inputs_from_angles(self, angles: np.ndarray, theta: float, theta_dot: float) -> np.ndarray:
        """U (N,) [rad/s^2] that produces the predicted angles (N,) from [theta, theta_dot]."""
        x0 = np.array([theta, theta_dot], dtype=float)
        free = self._PA_ang @ x0
        return _inputs_and_rates(
            np.asarray(angles, dtype=float), free, self._M, self._PA_rate, self._PB_rate, x0
        )[0]

    def _brake(self, theta_dot: float) -> np.ndarray:
        """Inputs (N,) that bring the rate to 0 at the acceleration bound, then hold."""
        n, T, acc = self.n_samples, self.sample_time, self.params.acc_limit
        u = np.zeros(n)
        rate = float(theta_dot)
        for k in range(n):
            u[k] = np.clip(-rate / T, -acc, acc)
            rate += T * u[k]
        return u

    # -- explanation (controller.explain; never in a tick) ----------------------------------
    def explain(self, plan: PelvisPlan) -> QpExplain:
        """What the last solve did (``plan``: its result): the cost of eq. (37) split into
        angle tracking and acceleration, each angle or acceleration bound that binds. The
        acceleration rows' multipliers are given per rad/s^2 (the QP scales those rows)."""
        qp = self.solver.last_qp
        assert qp is not None, "explain after a solve"
        n, T, s = self.n_samples, self.sample_time, self._acc_scale
        a, b = self.params.alpha, self.params.beta
        terms = {
            "waist angle tracking (alpha)": 0.5
            * a
            * float(np.sum((plan.angles - plan.reference) ** 2)),
            "yaw acceleration (beta)": 0.5 * b * float(np.sum(plan.acc**2)),
        }
        # U = M (Theta - f): M f = M Theta - U; the QP leaves out alpha/2 |ref|^2 + beta/2 |M f|^2
        mf = self._M @ plan.angles - plan.acc
        constant = 0.5 * a * float(plan.reference @ plan.reference) + 0.5 * b * float(mf @ mf)
        limit_deg = self.params.angle_limit_deg
        acc = self.params.acc_limit

        def name(row: int, lam: float, bound: float) -> ActiveConstraint:
            side = side_of(lam, False)
            sign = "+" if side == "upper" else "-"
            if row < n:
                ahead = round((row + 1) * T, 6)
                return ActiveConstraint(
                    f"waist angle limit ({sign}{limit_deg:g} deg) at {ahead_text(ahead)}",
                    "angle limit", side, lam, math.radians(limit_deg) * (1 if sign == "+" else -1),
                    row, None, ahead,
                )  # fmt: skip
            k = row - n
            ahead = round(k * T, 6)
            return ActiveConstraint(
                f"waist acceleration limit ({sign}{acc:g} rad/s^2) at {ahead_text(ahead)}",
                "acceleration limit", side, lam * s, acc if sign == "+" else -acc, row, None,
                ahead,
            )  # fmt: skip

        return explain_qp(
            "pelvis_mpc",
            qp,
            plan.angles,
            plan.ok,
            self.solver.last_result.status if self.solver.last_result is not None else "",
            self.solver,
            terms,
            name,
            "a brake: the waist rate brought to 0 at the acceleration bound",
            constant,
        )
