"""Whole-body kinematics with Pinocchio, loaded from the same MJCF as the simulation.

Paper symbols (Park & Park, IEEE Access 2022) -> names here:
- q_low (eq. 8-9): the 13 lower-body joints `LOWER_JOINTS` = [waist yaw, left leg 6, right leg 6];
  `lower_v_idx` are their columns in Pinocchio's velocity vector v.
- J_low (eq. 8-9): `KinState.J_low` (12 x 13), the stacked left/right sole twists
  [v (3), w (3)] per foot, expressed in the pelvis (floating-base) frame, with respect to q_low.
  It is computed with the base at identity, so "pelvis frame" = Pinocchio's world frame and
  LOCAL_WORLD_ALIGNED = pelvis-aligned axes at the sole origin.
- Centroidal momentum matrix A_G (eq. 41-42): `cmm_yaw_low` (A_low, z-angular row, lower-body
  columns) and `cmm_yaw_up` (A_up, z-angular row, `ARM_QP_JOINTS` columns). With the base at
  identity and at rest, the yaw angular momentum about the CoM is
  h_z = cmm_yaw_low @ dq_low + cmm_yaw_up @ dq_up.
- kappa(J) (eq. 45): `condition_number(J)` = sigma_max / sigma_min.

Conventions:
- `pin.buildModelFromMJCF(robot.xml)` (the file with the robot only; `scene.xml` adds the floor
  via <include>) gives a FreeFlyer root joint named "root" and the 19 hinges in the MJCF order,
  which is MuJoCo's qpos order. MJCF sites become OP_FRAMEs, so the soles are frames
  `L_sole` / `R_sole`; bodies are BODY frames.
- Pinocchio's free-flyer q is [p (3), quat xyzw (4)], MuJoCo's qpos is [p (3), quat wxyz (4)].
  Pinocchio's free-flyer v is [linear (3), angular (3)] both in the base (local) frame; MuJoCo's
  qvel has the linear part in the world frame and the angular part in the body frame.
  `from_mujoco(qpos, qvel)` converts.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from controller.compiled import gram_extremes, kernel
from models.dyros_jet import (
    ARM_QP_JOINTS,
    FOOT_SITES,
    HIP_BODIES,
    JOINTS,
    LEG_LENGTH,
    LOWER_JOINTS,
    ROBOT_XML,
)

_ANKLE_JOINTS = ("L_ankle_roll", "R_ankle_roll")  # joint origin = ankle point
_EPS = float(np.finfo(float).eps)
# kappa(J) of an exactly singular Jacobian is infinite; series, summaries and JSON record it as
# this finite cap (far above any kappa of a bent leg: ~100 at 0.1 rad from straight).
KAPPA_CAP = 1e8
_ORIGIN = (0.0, 0.0, 0.0)
_IDENTITY_WXYZ = (1.0, 0.0, 0.0, 0.0)


class KinState(NamedTuple):
    """Kinematic quantities with the base (pelvis) at the identity pose (fresh arrays)."""

    T_pelvis_left_sole: np.ndarray  # (4,4) sole pose in the pelvis frame
    T_pelvis_right_sole: np.ndarray  # (4,4)
    p_pelvis_com: np.ndarray  # (3,)
    J_low: np.ndarray  # (12,13): [left v, left w, right v, right w] x LOWER_JOINTS
    cmm_yaw_low: np.ndarray  # (13,)
    cmm_yaw_up: np.ndarray  # (4,)
    p_pelvis_hips: np.ndarray  # (2,3) left/right hip points
    p_pelvis_ankles: np.ndarray  # (2,3) left/right ankle points


class RobotKinematics:
    """Pinocchio model of the robot plus the few quantities the walking controller needs."""

    def __init__(self, mjcf_path: str | Path = ROBOT_XML):
        self.model = pin.buildModelFromMJCF(str(mjcf_path))
        m = self.model
        if m.joints[1].shortname() != "JointModelFreeFlyer":
            raise ValueError("expected a free-flyer root joint in the MJCF")
        # MuJoCo's free-joint qpos is the absolute body pose: the joint placement must be identity.
        m.jointPlacements[1] = pin.SE3.Identity()
        self.data = m.createData()
        names = list(m.names)
        if tuple(names[2:]) != JOINTS:
            raise ValueError(f"joint order differs from models.dyros_jet.JOINTS: {names[2:]}")
        self.n_joints = m.nv - 6
        self.lower_v_idx = np.array([m.joints[m.getJointId(n)].idx_v for n in LOWER_JOINTS])
        self._lower_cols = _as_slice(self.lower_v_idx)  # a slice when contiguous (it is)
        self.arm_qp_v_idx = np.array([m.joints[m.getJointId(n)].idx_v for n in ARM_QP_JOINTS])
        self.arm_qp_joint_idx = np.array([JOINTS.index(n) for n in ARM_QP_JOINTS])
        self.q_min = m.lowerPositionLimit[7:].copy()
        self.q_max = m.upperPositionLimit[7:].copy()
        self.sole_frame_ids = tuple(m.getFrameId(s, pin.OP_FRAME) for s in FOOT_SITES)
        self.hip_frame_ids = tuple(m.getFrameId(b, pin.BODY) for b in HIP_BODIES)
        # the ankle joints' frames (a joint's frame sits at its origin: the ankle point)
        self.ankle_frame_ids = tuple(m.getFrameId(j, pin.JOINT) for j in _ANKLE_JOINTS)
        self.total_mass = float(pin.computeTotalMass(m))
        self._q_identity_base = np.zeros(m.nq)  # base at the origin, quaternion xyzw identity
        self._q_identity_base[6] = 1.0

    # ------------------------------------------------------------------ configurations
    def configuration(self, q_joints, p_world_base=_ORIGIN, quat_wxyz=_IDENTITY_WXYZ) -> np.ndarray:
        """Pinocchio q from joint angles (19,), base position and MuJoCo-order quaternion."""
        if p_world_base is _ORIGIN and quat_wxyz is _IDENTITY_WXYZ:  # base at the identity
            q = self._q_identity_base.copy()
            q[7:] = q_joints
            return q
        w, x, y, z = np.asarray(quat_wxyz, dtype=float)
        q = np.empty(self.model.nq)
        q[:3] = p_world_base
        q[3:7] = (x, y, z, w)
        q[7:] = q_joints
        return q

    def from_mujoco(self, qpos: np.ndarray, qvel: np.ndarray | None = None):
        """(q, v) for Pinocchio from MuJoCo qpos (26,) and qvel (25,) (v is None if qvel is)."""
        q = self.configuration(qpos[7:], qpos[:3], qpos[3:7])
        if qvel is None:
            return q, None
        v = np.array(qvel, dtype=float)
        R = pin.Quaternion(q[6], q[3], q[4], q[5]).normalized().toRotationMatrix()
        v[:3] = R.T @ qvel[:3]  # world-frame linear velocity -> base frame
        return q, v

    # ------------------------------------------------------------------ main computation
    def compute(self, q_joints: np.ndarray) -> KinState:
        """All controller quantities in one pass, with the base at identity (pelvis = world)."""
        m, d = self.model, self.data
        q = self.configuration(q_joints)
        Ag = pin.computeCentroidalMap(m, d, q)  # forward kinematics + CoM + A_G (about the CoM)
        pin.computeJointJacobians(m, d)  # uses the kinematics just computed
        lws = pin.LOCAL_WORLD_ALIGNED
        fl, fr = self.sole_frame_ids
        low = self._lower_cols
        # column-major like Pinocchio's Jacobians (the layout BLAS then reads J_low in)
        J_low = np.empty((12, len(self.lower_v_idx)), order="F")
        J_low[:6] = pin.getFrameJacobian(m, d, fl, lws)[:, low]
        J_low[6:] = pin.getFrameJacobian(m, d, fr, lws)[:, low]
        # Only the frames used here (not all frames of the model).
        upd = pin.updateFramePlacement
        (hl, hr), (al, ar) = self.hip_frame_ids, self.ankle_frame_ids
        hips, ankles = np.empty((2, 3)), np.empty((2, 3))
        hips[0], hips[1] = upd(m, d, hl).translation, upd(m, d, hr).translation
        ankles[0], ankles[1] = upd(m, d, al).translation, upd(m, d, ar).translation
        return KinState(
            upd(m, d, fl).homogeneous,
            upd(m, d, fr).homogeneous,
            d.com[0].copy(),
            J_low,
            Ag[5][self.lower_v_idx],  # fancy indices: copies (Ag is Data's own buffer); on
            Ag[5][self.arm_qp_v_idx],  # the row's view, a fifth of Ag[5, idx]'s cost
            hips,
            ankles,
        )

    def com_and_soles(self, q_joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """CoM (3,) and the left/right sole positions (2, 3) in the pelvis frame, one pass.

        The base is at the identity, as in :meth:`compute`; one forward-kinematics pass serves
        the CoM and both soles (what :meth:`support_anchored_base` + :meth:`com_world` do in
        two passes per foot).
        """
        m, d = self.model, self.data
        com = pin.centerOfMass(m, d, self.configuration(q_joints), False).copy()
        upd, (fl, fr) = pin.updateFramePlacement, self.sole_frame_ids
        soles = np.empty((2, 3))
        soles[0], soles[1] = upd(m, d, fl).translation, upd(m, d, fr).translation
        return com, soles

    def com_world(self, q_joints, p_world_base, quat_wxyz) -> np.ndarray:
        """Whole-body CoM (3,) in the world for a given base pose (quaternion wxyz)."""
        q = self.configuration(q_joints, p_world_base, quat_wxyz)
        return pin.centerOfMass(self.model, self.data, q, False).copy()

    def sole_pose_pelvis(self, q_joints, side: int) -> np.ndarray:
        """(4,4) pose of the sole of `side` (0 left, 1 right) in the pelvis frame."""
        m, d = self.model, self.data
        pin.forwardKinematics(m, d, self.configuration(q_joints))
        return pin.updateFramePlacement(m, d, self.sole_frame_ids[side]).homogeneous.copy()

    def support_anchored_base(self, q_joints, side: int, p_world_sole: np.ndarray) -> np.ndarray:
        """Base position (identity orientation) putting the sole of `side` at `p_world_sole`.

        This is how a real robot estimates its base (and so its CoM) from joint encoders:
        the support foot is assumed to stay where it was planted.
        """
        T = self.sole_pose_pelvis(q_joints, side)
        return np.asarray(p_world_sole, dtype=float) - T[:3, 3]


def condition_number(J: np.ndarray) -> float:
    """kappa(J) = sigma_max / sigma_min (eq. 45) of a J (m, n) with m <= n, inf when J is
    (numerically) singular (:func:`jacobian_conditions`)."""
    return jacobian_conditions(J)[0]


def jacobian_conditions(J_low: np.ndarray) -> tuple[float, float]:
    """kappa (eq. 45) of J_low (12 x 13) and of its 12 leg columns, each inf when singular.

    sigma^2 are the extreme eigenvalues of J J' (cheaper than an SVD at 200 Hz; kappa is
    resolved up to about 1e7, far above the 1e3 that marks a straight knee). With L the leg
    columns and w the waist column, J J' = L L' + w w'.
    """
    lam_min, lam_max, legs_min, legs_max = gram_extremes(np.asarray(J_low, dtype=float))
    return _kappa(lam_max, lam_min), _kappa(legs_max, legs_min)


def _kappa(lam_max: float, lam_min: float) -> float:
    """sigma_max / sigma_min from the extreme eigenvalues sigma^2; inf when sigma_min is
    within machine precision of zero relative to sigma_max."""
    s_max, s_min = math.sqrt(max(lam_max, 0.0)), math.sqrt(max(lam_min, 0.0))
    if s_max == 0.0 or s_min <= s_max * _EPS:
        return math.inf
    return s_max / s_min


def _as_slice(idx: np.ndarray) -> slice | np.ndarray:
    """``slice(a, b)`` if ``idx`` is the contiguous range a..b-1, else ``idx`` itself."""
    if len(idx) and np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx))):
        return slice(int(idx[0]), int(idx[0]) + len(idx))
    return idx


def leg_reach(kin: KinState) -> np.ndarray:
    """(2,) hip-to-ankle distance / LEG_LENGTH for the left and right leg (1 = straight)."""
    return _reach(kin.p_pelvis_hips, kin.p_pelvis_ankles, LEG_LENGTH)


@kernel
def _reach(hips, ankles, leg_length):
    """(2,) |hip - ankle| / leg_length per leg, from (2, 3) points."""
    d = hips - ankles
    return np.sqrt((d * d).sum(axis=1)) / leg_length
