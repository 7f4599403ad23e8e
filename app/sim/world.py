"""The MuJoCo world of one robot: stepping, measurement, contacts, falls.

One owner of the simulation loop (mujoco_playground's pattern): ``sim_dt`` (MuJoCo's timestep)
and ``control_dt`` (200 Hz) are separate and ``n_substeps = control_dt / sim_dt``. A control
period = write the servo targets, then ``mj_step`` n_substeps times; energy (eq. 44) and servo
saturation are accumulated over the substeps.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from models.dyros_jet import (
    ARM_JOINTS,
    FOOT_GEOMS,
    FOOT_SITES,
    FOOT_SIZE,
    KEYFRAME,
    LOWER_JOINTS,
    NOMINAL_PELVIS_HEIGHT,
    ROOT_BODY,
    SCENE_XML,
)

JOINTS = LOWER_JOINTS + ARM_JOINTS
MAX_TILT_RAD = np.deg2rad(30.0)  # SPEC 4: torso tilt beyond this is a fall


@dataclass(frozen=True)
class Contacts:
    """Foot contact state from the measured contact forces (world frame)."""

    in_contact: np.ndarray  # (2,) bool: left / right foot touches the floor
    normal_force: np.ndarray  # (2,) [N]
    cop: np.ndarray | None  # (2,) centre of pressure x, y [m]; None when airborne
    other_contact: bool  # a body other than the feet touches the floor


class World:
    """A MuJoCo simulation of one robot driven by position targets at ``control_dt``."""

    def __init__(self, sim_dt: float = 0.001, control_dt: float = 0.005, xml: str = SCENE_XML):
        self.model = mujoco.MjModel.from_xml_path(str(xml))
        self.model.opt.timestep = sim_dt
        self.data = mujoco.MjData(self.model)
        self.sim_dt = sim_dt
        self.control_dt = control_dt
        self.n_substeps = max(1, int(round(control_dt / sim_dt)))
        m = self.model
        self.qpos_idx = np.array([m.jnt_qposadr[m.joint(j).id] for j in JOINTS])
        self.qvel_idx = np.array([m.jnt_dofadr[m.joint(j).id] for j in JOINTS])
        self.act_idx = np.array([m.actuator(j).id for j in JOINTS])
        self.root_id = m.body(ROOT_BODY).id
        self.foot_geom_ids = np.array([m.geom(g).id for g in FOOT_GEOMS])
        self.sole_site_ids = np.array([m.site(s).id for s in FOOT_SITES])
        self.floor_body = 0  # world body holds the floor plane
        self.force_limit = np.abs(m.actuator_forcerange[self.act_idx, 1])
        self.key_id = m.key(KEYFRAME).id
        self._force6 = np.zeros(6)
        self.reset()

    # -- state -------------------------------------------------------------------------------
    def reset(self, seed: int | None = None, perturbation: float = 0.0) -> None:
        """Reset to the walk-ready keyframe; a seeded perturbation of the joint angles [rad]."""
        mujoco.mj_resetDataKeyframe(self.model, self.data, self.key_id)
        if seed is not None and perturbation > 0:
            rng = np.random.default_rng(seed)
            # Perturb the arms and waist (not the legs, which would lift a foot) plus a small
            # initial base velocity: repeats then differ while starting from a standing robot.
            self.data.qvel[0:2] += rng.normal(0.0, perturbation, 2)
            arm = self.qpos_idx[13:]
            self.data.qpos[arm] += rng.normal(0.0, perturbation, len(arm))
        mujoco.mj_forward(self.model, self.data)
        self.energy_per_joint = np.zeros(len(JOINTS))  # [J] positive mechanical work (eq. 44)
        self.saturated_substeps = 0

    @property
    def time(self) -> float:
        return float(self.data.time)

    def q_joints(self) -> np.ndarray:
        return self.data.qpos[self.qpos_idx].copy()

    def qd_joints(self) -> np.ndarray:
        return self.data.qvel[self.qvel_idx].copy()

    def keyframe_joints(self) -> np.ndarray:
        return self.model.key_qpos[self.key_id][self.qpos_idx].copy()

    def base_position(self) -> np.ndarray:
        return self.data.qpos[0:3].copy()

    def base_quat(self) -> np.ndarray:
        return self.data.qpos[3:7].copy()

    def sole_positions(self) -> np.ndarray:
        """(2, 3) measured left/right sole site positions [m]."""
        return self.data.site_xpos[self.sole_site_ids].copy()

    def sole_yaws(self) -> np.ndarray:
        mats = self.data.site_xmat[self.sole_site_ids].reshape(2, 3, 3)
        return np.arctan2(mats[:, 1, 0], mats[:, 0, 0])

    def com(self) -> np.ndarray:
        return self.data.subtree_com[self.root_id].copy()

    def yaw_momentum(self) -> float:
        """Whole-body yaw angular momentum about the CoM [kg m^2/s] (MuJoCo's subtree)."""
        mujoco.mj_subtreeVel(self.model, self.data)
        return float(self.data.subtree_angmom[self.root_id][2])

    def torso_tilt(self) -> float:
        """Angle between the base z axis and the world z axis [rad]."""
        zz = self.data.xmat[self.root_id].reshape(3, 3)[2, 2]
        return float(np.arccos(np.clip(zz, -1.0, 1.0)))

    # -- stepping ----------------------------------------------------------------------------
    def step(self, q_target: np.ndarray) -> None:
        """Hold ``q_target`` on the servos for one control period (n_substeps MuJoCo steps)."""
        d = self.data
        d.ctrl[self.act_idx] = q_target
        dt = self.sim_dt
        for _ in range(self.n_substeps):
            mujoco.mj_step(self.model, d)
            tau = d.actuator_force[self.act_idx]
            power = tau * d.qvel[self.qvel_idx]
            self.energy_per_joint += np.maximum(power * dt, 0.0)
            if np.any(np.abs(tau) >= 0.99 * self.force_limit):
                self.saturated_substeps += 1

    # -- contacts ----------------------------------------------------------------------------
    def contacts(self) -> Contacts:
        """Foot contact forces, their centre of pressure, and non-foot floor contacts."""
        m, d = self.model, self.data
        in_contact = np.zeros(2, dtype=bool)
        fz = np.zeros(2)
        moment = np.zeros(2)
        total = 0.0
        other = False
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = c.geom1, c.geom2
            b1, b2 = m.geom_bodyid[g1], m.geom_bodyid[g2]
            if b1 != self.floor_body and b2 != self.floor_body:
                continue
            robot_geom = g2 if b1 == self.floor_body else g1
            hit = np.nonzero(self.foot_geom_ids == robot_geom)[0]
            if len(hit) == 0:
                other = True
                continue
            mujoco.mj_contactForce(m, d, i, self._force6)
            frame = c.frame.reshape(3, 3)
            f_world = frame.T @ self._force6[:3]
            f_up = abs(f_world[2])
            side = int(hit[0])
            in_contact[side] = True
            fz[side] += f_up
            moment += f_up * c.pos[:2]
            total += f_up
        cop = moment / total if total > 1e-6 else None
        return Contacts(in_contact, fz, cop, other)

    def support_polygon(self, in_contact: np.ndarray) -> np.ndarray:
        """(M, 2) convex hull (counter-clockwise) of the soles in contact."""
        pts = []
        soles = self.sole_positions()
        yaws = self.sole_yaws()
        hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
        corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
        for side in range(2):
            if in_contact[side]:
                c, s = np.cos(yaws[side]), np.sin(yaws[side])
                R = np.array([[c, -s], [s, c]])
                pts.append(corners @ R.T + soles[side, :2])
        if not pts:
            return np.zeros((0, 2))
        return convex_hull(np.vstack(pts))

    def fall_reason(self) -> str | None:
        """Why the robot counts as fallen (SPEC 4), or None."""
        if self.data.qpos[2] < 0.5 * NOMINAL_PELVIS_HEIGHT:
            return "pelvis below half its nominal height"
        if self.torso_tilt() > MAX_TILT_RAD:
            return "torso tilted over 30 deg"
        return None


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Andrew's monotone chain; returns the hull counter-clockwise, (M, 2)."""
    pts = sorted(map(tuple, np.round(points, 12)))
    if len(pts) <= 2:
        return np.array(pts)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def point_in_polygon(p: np.ndarray, hull: np.ndarray, tol: float = 1e-3) -> bool:
    """True if p lies inside the counter-clockwise convex polygon (within tol metres)."""
    if len(hull) < 3:
        return False
    a = hull
    b = np.roll(hull, -1, axis=0)
    edge = b - a
    rel = p - a
    cross = edge[:, 0] * rel[:, 1] - edge[:, 1] * rel[:, 0]
    length = np.linalg.norm(edge, axis=1)
    return bool(np.all(cross / length >= -tol))
