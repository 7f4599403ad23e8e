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
    Theta_ddot_i (eq. 36) -> the decision variable U (N,); alpha_pel, beta_pel ->
    ``params.alpha``, ``params.beta``; Delta t of eq. (38) -> ``control_dt``.

The decision variable is U only (condensed form); the QP is
``P = alpha PB_ang' PB_ang + beta I``, ``q = alpha PB_ang' (PA_ang x0 - ref)`` with the
angle rows ``PB_ang`` and identity rows (acceleration bounds) in ``A``.

Choices where the paper is vague:
- **Eq. (38)** is applied over *one control period* ``control_dt`` (5 ms), not one MPC sample:
  ``next_rate = theta_dot + control_dt u_0`` and
  ``next_angle = theta + control_dt theta_dot + control_dt^2 / 2 u_0``. ``next_rate`` is the
  waist-yaw velocity the IK pins (eq. 39).
- The yaw acceleration bound (not in the paper; the authors' code has one) keeps the QP well
  posed with the tiny input weight beta = 1e-10 of the paper, and beta = 0 is allowed
  (P_B is lower triangular with T_p^2/2 on the diagonal, so P stays positive definite).
- **On failure** (infeasible start, e.g. |theta| beyond the limit with an outward rate the
  acceleration bound cannot stop, or a solver error) the plan is a *brake*: the rate decays to
  0 at the acceleration bound (``u = clip(-theta_dot / control_dt, +-acc_limit)`` in the first
  period, then whatever brings the rate to 0 on the predicted samples), ``ok=False``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.params import PelvisMpcParams
from controller.qp import QP, QpSolver


@dataclass(frozen=True)
class PelvisPlan:
    """Output of one pelvic-rotation MPC solve."""

    angles: np.ndarray  # (N,) predicted theta_k, k = 1..N [rad]
    rates: np.ndarray  # (N,) predicted theta_dot_k, k = 1..N [rad/s]
    acc: np.ndarray  # (N,) optimal inputs theta_ddot_k, k = 0..N-1 [rad/s^2]
    reference: np.ndarray  # (N,) theta_ref it tracked [rad]
    next_angle: float  # theta after ONE control period with the first input (eq. 38) [rad]
    next_rate: float  # theta_dot_{i+1} [rad/s]: the waist-yaw velocity pinned in the IK
    ok: bool


class PelvisMpc:
    """Condensed pelvic-rotation MPC (eq. 34-38) with a warm-started QP solver."""

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
            raise ValueError(f"need sample_time > 0 and n_samples >= 1 ({sample_time}, {n_samples})")
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
        self._PA_ang, self._PB_ang = self._PA[0::2], self._PB[0::2]  # angle rows (N, 2), (N, N)
        self._PA_rate, self._PB_rate = self._PA[1::2], self._PB[1::2]
        a, b = params.alpha, params.beta
        self._P = a * self._PB_ang.T @ self._PB_ang + b * np.eye(n)  # (N, N)
        self._Acon = np.vstack([self._PB_ang, np.eye(n)])  # (2N, N)
        self._angle_limit = math.radians(params.angle_limit_deg)
        if shape_changed:
            self.solver.reset()

    def build(self, theta: float, theta_dot: float, theta_ref: np.ndarray) -> QP:
        """The QP of eq. (37) for the current state [theta, theta_dot] and reference (N,)."""
        ref = np.asarray(theta_ref, dtype=float).reshape(-1)
        n = self.n_samples
        if ref.shape[0] != n:
            raise ValueError(f"theta_ref has {ref.shape[0]} samples, the MPC has {n}")
        x0 = np.array([theta, theta_dot], dtype=float)
        free = self._PA_ang @ x0  # (N,) angles with zero input
        q = self.params.alpha * self._PB_ang.T @ (free - ref)
        lim, acc = self._angle_limit, self.params.acc_limit
        lo = np.concatenate([-lim - free, np.full(n, -acc)])
        hi = np.concatenate([lim - free, np.full(n, acc)])
        return QP(self._P, q, self._Acon, lo, hi)

    def solve(self, theta: float, theta_dot: float, theta_ref: np.ndarray) -> PelvisPlan:
        """Solve eq. (37) and integrate the first input over one control period (eq. 38)."""
        qp = self.build(theta, theta_dot, theta_ref)
        ref = np.asarray(theta_ref, dtype=float).reshape(-1)
        res = self.solver.solve(qp)
        if res.ok:
            u = res.x
        else:
            u = self._brake(theta_dot)
        x0 = np.array([theta, theta_dot], dtype=float)
        angles = self._PA_ang @ x0 + self._PB_ang @ u
        rates = self._PA_rate @ x0 + self._PB_rate @ u
        dt = self.control_dt
        if res.ok:
            u0 = float(u[0])
        else:
            u0 = float(np.clip(-theta_dot / dt, -self.params.acc_limit, self.params.acc_limit))
        next_rate = theta_dot + dt * u0
        next_angle = theta + dt * theta_dot + 0.5 * dt * dt * u0
        return PelvisPlan(angles, rates, u.copy(), ref.copy(), next_angle, next_rate, res.ok)

    def _brake(self, theta_dot: float) -> np.ndarray:
        """Inputs (N,) that bring the rate to 0 at the acceleration bound, then hold."""
        n, T, acc = self.n_samples, self.sample_time, self.params.acc_limit
        u = np.zeros(n)
        rate = float(theta_dot)
        for k in range(n):
            u[k] = np.clip(-rate / T, -acc, acc)
            rate += T * u[k]
        return u
