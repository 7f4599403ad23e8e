"""CoM MPC with minimal velocity fluctuation, eq. (10)-(18), and the CoM prediction (25)-(26).

Model: linear inverted pendulum with constant CoM height z_c, decoupled in x and y. Per axis
the state is x_i = [p, v, a] (eq. 10-11: position [m], velocity [m/s], acceleration [m/s^2])
and the input is the jerk [m/s^3], held constant over one MPC sample T_p (eq. 12-13):

    x_{i+1} = A x_i + B u_i,  A = [[1, T, T^2/2], [0, 1, T], [0, 0, 1]],  B = [T^3/6, T^2/2, T].

The ZMP is z = p - (z_c / g) a = C x (eq. 14-15; the paper's ``C A x_i`` is C applied to the
next state, i.e. the ZMP of the predicted samples).

Paper symbols -> code names:
    P_A, P_B (eq. 25-26) -> ``state_from_state`` (3N, 3), ``state_from_jerk`` (3N, N), rows
        ordered [p_1..p_N, v_1..v_N, a_1..a_N] (sample k = 1..N after the current state);
    Z (eq. 16-17) = ``zmp_from_state`` x_0 + ``zmp_from_jerk`` U;
    Delta V (eq. 18) = ``dvel_from_state`` x_0 + ``dvel_from_jerk`` U = [v_1 - v_0, v_2 - v_1,
        ..., v_N - v_{N-1}] (the first difference uses the current velocity v_0);
    alpha, beta, gamma (eq. 18) -> ``ComMpcParams.alpha``, ``beta``, ``gamma`` (same for x, y);
    Z^min, Z^max (eq. 18) -> ``PlanSample.zmp_lo`` / ``zmp_hi`` of
        :meth:`controller.footsteps.FootstepPlan.sample` with ``ComMpcParams.zmp_margin``;
        Z^ref -> ``PlanSample.zmp_ref``.

The QP (one for both axes, 2N variables U = [U_x; U_y], block diagonal):
    min 1/2 U' P U + q' U  s.t.  Z^min - Pzs x_0 <= Pzu U <= Z^max - Pzs x_0, with
    P = alpha Pzu'Pzu + beta Pdu'Pdu + gamma I, q = alpha Pzu'(Pzs x_0 - Z^ref)
    + beta Pdu'(Pds x_0) per axis. P and the constraint matrix depend on the parameters only
    and are built once (closed-form index arithmetic, no loop over the horizon) and frozen; a
    tick changes q, l, u only, and :class:`controller.qp.QpSolver` warm-starts the solver.

Choices where the paper is vague:
- The samples are at t + k T_p, k = 1..N, with N = ``horizon_samples(params)``; the ZMP is
  constrained and tracked at those N samples (the current ZMP is already fixed by the state).
- The first jerk is applied for one control period ``control_dt`` (5 ms), not T_p: the MPC is
  re-solved every tick (``ComPlan.next_state``).
- On a failed QP the previous optimal jerk sequence, shifted by the time elapsed since it was
  computed (the last value repeated), is used with ``ok=False``; zeros if there is none.
- g = 9.81 m/s^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.compiled import daqp_call, kernel
from controller.explain import ActiveConstraint, QpExplain, ahead_text, explain_qp, side_of
from controller.footsteps import FootstepPlan
from controller.params import ComMpcParams, horizon_samples
from controller.qp import QP, QpSolver, frozen

GRAVITY = 9.81  # [m/s^2]
# which edge of the support a ZMP bound is, by axis and side (world x forward, y left)
_EDGE = {
    ("x", "upper"): "front",
    ("x", "lower"): "back",
    ("y", "upper"): "left",
    ("y", "lower"): "right",
}


@dataclass(slots=True, eq=False)
class ComPlan:
    """One CoM MPC solution: the predicted horizon (eq. 25-26) and the state after one tick.

    Read-only by contract. The predicted ZMP (eq. 16-17) feeds no layer: it is computed from
    the solution on first read (``zmp``), at the rate of the display that draws it.
    """

    times: np.ndarray  # (N,) [s] absolute times of the predicted samples t + k T_p, k = 1..N
    com: np.ndarray  # (N, 2) [m] predicted CoM x, y (eq. 25-26)
    zmp_ref: np.ndarray  # (N, 2) [m]
    jerk: np.ndarray  # (N, 2) [m/s^3] optimal inputs
    next_state: np.ndarray  # (3, 2) [pos, vel, acc] x (x, y) after one control period
    ok: bool  # False when the QP failed (the previous jerk sequence, shifted, was used)
    zmp_lo: np.ndarray | None = None  # (N, 2) [m] ZMP lower bound at the samples
    zmp_hi: np.ndarray | None = None  # (N, 2) [m] ZMP upper bound at the samples
    status: str = ""  # solver status text
    state: np.ndarray | None = None  # (3, 2) the CoM state the horizon starts from
    zmp_maps: tuple[np.ndarray, np.ndarray] | None = None  # (Pzs, Pzu) of eq. (16-17)
    _zmp: np.ndarray | None = None

    @property
    def zmp(self) -> np.ndarray:
        """(N, 2) [m] predicted ZMP, Z = Pzs x0 + Pzu U (eq. 16-17)."""
        if self._zmp is None:
            assert self.zmp_maps is not None and self.state is not None
            from_state, from_jerk = self.zmp_maps
            self._zmp = from_state @ self.state + from_jerk @ self.jerk
        return self._zmp


@kernel
def _qp_vectors(zmp_from_state, q_zmp, q_dv, x0, zmp_ref, zmp_lo, zmp_hi, q, l, u):
    """q, l, u (2N,) of eq. (18) for the state x0 (3, 2), per axis stacked [x; y], written
    into ``q``, ``l``, ``u`` (:meth:`ComMpc.build`)."""
    n = zmp_ref.shape[0]
    z_free = zmp_from_state @ x0  # (N, 2) ZMP with zero jerk, Pzs x0 (eq. 16-17)
    qa = q_zmp @ (z_free - zmp_ref) + q_dv @ x0  # alpha Pzu'(Pzs x0 - Zref) + beta Pdu'(Pds x0)
    la = zmp_lo - z_free  # Z^min - Pzs x0 <= Pzu U
    ua = zmp_hi - z_free  # Pzu U <= Z^max - Pzs x0
    for axis in range(2):
        q[axis * n : (axis + 1) * n] = qa[:, axis]
        l[axis * n : (axis + 1) * n] = la[:, axis]
        u[axis * n : (axis + 1) * n] = ua[:, axis]


@kernel
def _predicted(com_from_state, com_from_jerk, A_ctrl, B_ctrl, x0, jerk):
    """The predicted CoM (N, 2) (eq. 25-26) and the state after one control period (3, 2),
    A x0 + B u0, from the state x0 (3, 2) and the jerks (N, 2)."""
    com = com_from_state @ x0 + com_from_jerk @ jerk
    next_state = A_ctrl @ x0 + B_ctrl.reshape(3, 1) * jerk[0]
    return com, next_state


@kernel
def _step(maps, x0, zmp_ref, zmp_lo, zmp_hi, q, l, u, x, com, next_state, *workspace):
    """Eq. (18) built (:func:`_qp_vectors`) and solved by DAQP on the solver's workspace
    (:meth:`controller.qp.QpSolver.step_args`: ``workspace``), the horizon predicted from the
    jerks U = x (2N,) (:func:`_predicted`), all written into the arrays given; returns DAQP's
    (status, flag). ``maps``: (Pzs, q_zmp, q_dv, com_from_state, com_from_jerk, A, B)."""
    zmp_from_state, q_zmp, q_dv, com_from_state, com_from_jerk, A_ctrl, B_ctrl = maps
    _qp_vectors(zmp_from_state, q_zmp, q_dv, x0, zmp_ref, zmp_lo, zmp_hi, q, l, u)
    status, flag = daqp_call(q, l, u, x, *workspace)
    n = zmp_ref.shape[0]
    com[:], next_state[:] = _predicted(
        com_from_state, com_from_jerk, A_ctrl, B_ctrl, x0, x.reshape(2, n).T
    )
    return status, flag


def lipm_discrete(T: float) -> tuple[np.ndarray, np.ndarray]:
    """A (3, 3), B (3,) of eq. (12) for a jerk held over T [s]."""
    A = np.array([[1.0, T, T * T / 2.0], [0.0, 1.0, T], [0.0, 0.0, 1.0]])
    B = np.array([T**3 / 6.0, T * T / 2.0, T])
    return A, B


def prediction_matrices(T: float, N: int) -> tuple[np.ndarray, np.ndarray]:
    """P_A (3N, 3) and P_B (3N, N) of eq. (25), rows [p_1..p_N, v_1..v_N, a_1..a_N].

    Closed form of x_k = A^k x_0 + sum_{j<k} A^(k-1-j) B u_j: with i = k - 1 - j >= 0,
    p gets (1 + 3i + 3i^2) T^3/6 u_j, v gets (1 + 2i) T^2/2 u_j, a gets T u_j.
    """
    k = np.arange(1, N + 1, dtype=float)[:, None]  # (N, 1) sample index
    kT = k * T
    one, zero = np.ones_like(kT), np.zeros_like(kT)
    PA = np.vstack(
        [
            np.hstack([one, kT, kT**2 / 2.0]),
            np.hstack([zero, one, kT]),
            np.hstack([zero, zero, one]),
        ]
    )
    i = np.arange(N)[:, None] - np.arange(N)[None, :]  # k-1-j for rows k-1, columns j
    lower = i >= 0
    i = np.maximum(i, 0).astype(float)
    PB = np.vstack(
        [
            np.where(lower, (1.0 + 3.0 * i + 3.0 * i**2) * T**3 / 6.0, 0.0),
            np.where(lower, (1.0 + 2.0 * i) * T**2 / 2.0, 0.0),
            np.where(lower, T, 0.0),
        ]
    )
    return PA, PB


class ComMpc:
    """Builds and solves the CoM MPC QP of eq. (18) every control tick.

    Args:
        params: horizon, sample time, weights and ZMP margin.
        com_height: z_c [m], the constant CoM height of the LIPM.
        control_dt: [s] control period over which the first jerk is applied.
        backend: ``"osqp"`` (warm-started) or ``"daqp"`` (exact active set).
    """

    def __init__(
        self,
        params: ComMpcParams,
        com_height: float,
        control_dt: float = 0.005,
        backend: str = "osqp",
    ):
        self.com_height = float(com_height)  # z_c [m]
        self.control_dt = float(control_dt)  # [s]
        self.solver = QpSolver(backend)
        self.params: ComMpcParams | None = None
        self.last_qp: QP | None = None
        self._prev_jerk: np.ndarray | None = None  # (N, 2) last optimal jerks
        self._prev_t: float = 0.0
        self.set_params(params)

    # -- matrices -------------------------------------------------------------------------
    def set_params(self, params: ComMpcParams) -> None:
        """Rebuild the matrices if ``params`` changed; reset the solver if N changed."""
        if params == self.params:
            return
        old_n = getattr(self, "N", None)
        self.params = params
        self.T = float(params.sample_time)  # T_p [s]
        self.N = horizon_samples(params)
        N, T, c = self.N, self.T, self.com_height / GRAVITY
        self.state_from_state, self.state_from_jerk = prediction_matrices(T, N)  # P_A, P_B
        PA, PB = self.state_from_state, self.state_from_jerk
        self._com_from_state, self._com_from_jerk = PA[:N].copy(), PB[:N].copy()  # positions
        self.zmp_from_state = PA[:N] - c * PA[2 * N :]  # (N, 3)
        self.zmp_from_jerk = PB[:N] - c * PB[2 * N :]  # (N, N)
        self._zmp_maps = (self.zmp_from_state, self.zmp_from_jerk)
        D = np.eye(N) - np.eye(N, k=-1)  # consecutive differences of [v_1..v_N]
        e1v = np.zeros((N, 3))
        e1v[0, 1] = 1.0  # the first difference subtracts v_0
        self.dvel_from_state = D @ PA[N : 2 * N] - e1v  # (N, 3)
        self.dvel_from_jerk = D @ PB[N : 2 * N]  # (N, N)
        Pzu, Pdu = self.zmp_from_jerk, self.dvel_from_jerk
        H = params.alpha * Pzu.T @ Pzu + params.beta * Pdu.T @ Pdu + params.gamma * np.eye(N)
        H = (H + H.T) / 2.0
        Z = np.zeros((N, N))
        self.hessian = frozen(np.block([[H, Z], [Z, H]]))  # (2N, 2N)
        self.constraint = frozen(np.block([[Pzu, Z], [Z, Pzu]]))  # (2N, 2N)
        # q = G_ref (Pzs x0 - Zref) + G_dv x0, per axis
        self._q_zmp = params.alpha * Pzu.T  # (N, N)
        self._q_dv = params.beta * Pdu.T @ self.dvel_from_state  # (N, 3)
        self.A_ctrl, self.B_ctrl = lipm_discrete(self.control_dt)
        # the compiled step's constants and the QP it writes each tick (q, l, u in place)
        self._maps = (
            self.zmp_from_state, self._q_zmp, self._q_dv, self._com_from_state,
            self._com_from_jerk, self.A_ctrl, self.B_ctrl,
        )  # fmt: skip
        z = np.zeros(2 * N)
        self._qp = QP(self.hessian, z, self.constraint, z.copy(), z.copy())
        # (N,) k T_p [s], one object per set_params (the walker's plan table keys on it)
        self.sample_offsets = frozen(self.T * np.arange(1, N + 1))  # (N,) [s] k T_p
        if old_n is not None and old_n != N:
            self.solver.reset()
            self._prev_jerk = None

    def reset(self) -> None:
        """Forget the warm start and the fallback jerk sequence (e.g. on a simulation reset)."""
        self.solver.reset()
        self._prev_jerk = None

    # -- QP -------------------------------------------------------------------------------
    def build(
        self,
        state: np.ndarray,
        zmp_ref: np.ndarray,
        zmp_lo: np.ndarray,
        zmp_hi: np.ndarray,
    ) -> QP:
        """The QP of eq. (18) for the current state.

        Args:
            state: (3, 2) [pos, vel, acc] x (x, y) of the CoM now.
            zmp_ref: (N, 2) [m] ZMP reference at the N samples.
            zmp_lo, zmp_hi: (N, 2) [m] ZMP bounds at the N samples.

        Returns:
            The QP over U = [U_x; U_y] (2N jerks [m/s^3]).
        """
        n2 = 2 * self.N
        q, l, u = np.empty(n2), np.empty(n2), np.empty(n2)
        _qp_vectors(
            self.zmp_from_state,
            self._q_zmp,
            self._q_dv,
            np.asarray(state, dtype=float),
            np.asarray(zmp_ref, dtype=float),
            np.asarray(zmp_lo, dtype=float),
            np.asarray(zmp_hi, dtype=float),
            q,
            l,
            u,
        )
        return QP(self.hessian, q, self.constraint, l, u)

    def sample_times(self, t: float) -> np.ndarray:
        """(N,) [s] the predicted samples' absolute times t + k T_p, k = 1..N."""
        return t + self.sample_offsets

    def solve(self, state: np.ndarray, t: float, plan: FootstepPlan) -> ComPlan:
        """Solve eq. (18) at time ``t`` [s] from ``state`` (3, 2) along ``plan``.

        Returns:
            The predicted horizon (eq. 25-26) and the state after one control period.
        """
        assert self.params is not None
        times = self.sample_times(t)
        s = plan.sample(times, self.params.zmp_margin)
        return self.solve_references(state, t, times, s.zmp_ref, s.zmp_lo, s.zmp_hi)

    def solve_references(
        self,
        state: np.ndarray,
        t: float,
        times: np.ndarray,
        ref: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
    ) -> ComPlan:
        """:meth:`solve` with the plan's queries already made by the caller.

        Args:
            state: (3, 2) CoM state now; t: [s] time now.
            times: (N,) ``self.sample_times(t)``.
            ref, lo, hi: (N, 2) [m] ZMP reference and bounds at ``times`` (the plan's, with
                ``params.zmp_margin``).
        """
        x0 = np.asarray(state, dtype=float)
        N = self.N
        args = self.solver.step_args(self.hessian, self.constraint)
        if args is not None:  # eq. (18) and (25-26) in one compiled step
            qp = self._qp
            x, com, next_state = np.zeros(2 * N), np.empty((N, 2)), np.empty((3, 2))
            status, flag = _step(
                self._maps, x0, ref, lo, hi, qp.q, qp.l, qp.u, x, com, next_state, *args
            )
            res = self.solver.settle(qp, x, status, flag, args[1])
        else:
            qp = self.build(x0, ref, lo, hi)
            res = self.solver.solve(qp)
        self.last_qp = qp
        jerk = res.x.reshape(2, N).T
        if res.ok:
            self._prev_jerk, self._prev_t = jerk, float(t)
        elif self._prev_jerk is not None:  # the last optimal jerks, shifted (module docstring)
            shift = int(np.floor((t - self._prev_t) / self.T + 1e-9))
            jerk = self._prev_jerk[np.minimum(np.arange(N) + max(shift, 0), N - 1)]
        else:
            jerk = np.zeros((N, 2))
        if not res.ok or args is None:  # eq. (25-26) and A x0 + B u0 over one control period
            com, next_state = _predicted(
                self._com_from_state, self._com_from_jerk, self.A_ctrl, self.B_ctrl, x0, jerk
            )
        return ComPlan(
            times,
            com,
            ref,
            jerk,
            next_state,
            bool(res.ok),
            lo,
            hi,
            res.status,
            x0,
            self._zmp_maps,
        )

    # -- explanation (controller.explain; never in a tick) ----------------------------------
    def explain(self, plan: ComPlan) -> QpExplain:
        """What the last solve did (``plan``: its result): the cost of eq. (18) split into
        ZMP tracking, velocity fluctuation and jerk, each ZMP bound the horizon leans on."""
        assert self.params is not None and plan.state is not None
        qp = self.solver.last_qp
        assert qp is not None, "explain after a solve"
        p, N, T = self.params, self.N, self.T
        x0, U = plan.state, plan.jerk
        Z = self.zmp_from_state @ x0 + self.zmp_from_jerk @ U  # (N, 2) eq. (16-17)
        dV = self.dvel_from_state @ x0 + self.dvel_from_jerk @ U  # (N, 2) eq. (18)
        terms = {
            "ZMP tracking (alpha)": 0.5 * p.alpha * float(np.sum((Z - plan.zmp_ref) ** 2)),
            "velocity fluctuation (beta)": 0.5 * p.beta * float(np.sum(dV**2)),
            "jerk (gamma)": 0.5 * p.gamma * float(np.sum(U**2)),
        }
        # the terms with zero jerk less their linear part: what the QP leaves out
        z0 = self.zmp_from_state @ x0 - plan.zmp_ref
        v0 = self.dvel_from_state @ x0
        constant = 0.5 * p.alpha * float(np.sum(z0**2)) + 0.5 * p.beta * float(np.sum(v0**2))

        def name(row: int, lam: float, bound: float) -> ActiveConstraint:
            axis, k = ("x", row) if row < N else ("y", row - N)
            side = side_of(lam, False)
            ahead = round((k + 1) * T, 6)
            bounds = plan.zmp_hi if side == "upper" else plan.zmp_lo
            assert bounds is not None  # the bound in metres (the QP's row has Pzs x0 taken off)
            z = float(bounds[k, 0 if axis == "x" else 1])
            return ActiveConstraint(
                f"ZMP {axis} {side} bound at {ahead_text(ahead)} ({_EDGE[axis, side]} edge "
                "of the support)",
                "ZMP bound", side, lam, z, row, None, ahead, axis,
            )  # fmt: skip

        return explain_qp(
            "com_mpc",
            qp,
            U.T.ravel(),
            plan.ok,
            plan.status,
            self.solver,
            terms,
            name,
            "the previous optimal jerks, shifted by the time since they were computed",
            constant,
        )
