"""The MuJoCo world of one robot: stepping, measurement, contacts, falls.

One owner of the simulation loop (mujoco_playground's pattern): ``sim_dt`` (MuJoCo's timestep)
and ``control_dt`` (200 Hz) are separate and ``n_substeps = control_dt / sim_dt``. A control
period = write the servo targets, then ``mj_step`` n_substeps times; servo saturation is
counted over the substeps.

Energy (eq. 44, the positive part of servo torque x joint speed, summed over time) is kept two
ways, per joint:
- ``energy_ctrl_per_joint``: from one sample of torque and speed per control period (200 Hz),
  as a robot logs them: the figure the study and the live plots report (docs/DESIGN.md, "Energy");
- ``energy_substep_per_joint``: from every MuJoCo substep (1 ms), which also counts the servo
  chatter inside a control period: reported beside it;
- ``work_net``: the net work (torque x speed with its sign, every substep, all joints), the
  yardstick of how much of either figure is chatter that does no work.
(The per-substep torques and rates are copied into preallocated buffers; the arithmetic is
done once per control period.)

A push (``push``) is a horizontal force on the torso (the floating base) through MuJoCo's
``xfrc_applied``, held for a set duration of simulated time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

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
# torso tilt beyond this is a fall (docs/DESIGN.md, "What counts as a fall")
MAX_TILT_RAD = np.deg2rad(30.0)


@dataclass(frozen=True)
class Contacts:
    """Foot contact state from the measured contact forces (world frame)."""

    in_contact: np.ndarray  # (2,) bool: left / right foot touches the floor
    normal_force: np.ndarray  # (2,) [N]
    cop: np.ndarray | None  # (2,) centre of pressure x, y [m]; None when airborne
    other_contact: bool  # a body other than the feet touches the floor


class World:
    """A MuJoCo simulation of one robot driven by position targets at ``control_dt``."""

    def __init__(
        self, sim_dt: float = 0.001, control_dt: float = 0.005, xml: str | Path = SCENE_XML
    ):
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
        self._sat_limit = 0.99 * self.force_limit  # [N m] saturation threshold
        self._pyramidal = int(m.opt.cone) == int(mujoco.mjtCone.mjCONE_PYRAMIDAL)
        self._geom_body = m.geom_bodyid.tolist()  # geom -> body
        self._foot_side = {int(g): side for side, g in enumerate(self.foot_geom_ids)}
        # Contiguous index ranges as slices (cheaper than fancy indexing every substep).
        self._act_sel = _as_slice(self.act_idx)
        self._qpos_sel = _as_slice(self.qpos_idx)
        self._qvel_sel = _as_slice(self.qvel_idx)
        n = len(JOINTS)
        self._tau_buf = np.empty((self.n_substeps, n))  # [N m] per substep
        self._qd_buf = np.empty((self.n_substeps, n))  # [rad/s] per substep
        self._energy_buf = np.empty((self.n_substeps + 1, n))  # running sum, see step()
        # Views of MjData's own buffers (MuJoCo never moves them), read after every substep
        # (a fresh view per read costs more than the copy). The model lists the joints and
        # their actuators in one contiguous order (models/dyros_jet/robot.xml).
        if not (isinstance(self._act_sel, slice) and isinstance(self._qvel_sel, slice)):
            raise ValueError(f"{xml}: the joints' actuators and velocities must be contiguous")
        self._force_view = self.data.actuator_force[self._act_sel]
        self._qvel_view = self.data.qvel[self._qvel_sel]
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
        self.energy_ctrl_per_joint = np.zeros(len(JOINTS))  # [J] eq. (44) from 200 Hz samples
        self.energy_substep_per_joint = np.zeros(len(JOINTS))  # [J] eq. (44) at every substep
        self.work_net = 0.0  # [J] torque x speed summed with its sign, every substep, all joints
        self.work_net_ctrl = 0.0  # [J] the same from one sample per control period (200 Hz)
        self.saturated_substeps = 0
        self.data.xfrc_applied[:] = 0.0
        self._push_left = 0  # substeps the current push still lasts

    def push(self, force_xy: np.ndarray, duration: float) -> None:
        """Apply a horizontal force [N] at the torso's centre of mass for ``duration`` [s]."""
        self.data.xfrc_applied[self.root_id, :3] = (float(force_xy[0]), float(force_xy[1]), 0.0)
        self._push_left = max(1, int(round(duration / self.sim_dt)))

    @property
    def pushing(self) -> bool:
        return self._push_left > 0

    @property
    def time(self) -> float:
        return float(self.data.time)

    def q_joints(self) -> np.ndarray:
        return self.data.qpos[self._qpos_sel].copy()

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

    def sole_tilts(self) -> np.ndarray:
        """(2,) [rad] angle of each sole's normal from the vertical (left, right)."""
        zz = self.data.site_xmat[self.sole_site_ids, 8]  # element (2, 2) of each 3x3
        return np.arccos(np.minimum(np.maximum(zz, -1.0), 1.0))  # np.clip without its wrapper

    def torso_tilt(self) -> float:
        """Angle between the base z axis and the world z axis [rad]."""
        zz = float(self.data.xmat[self.root_id, 8])  # row-major 3x3: element (2, 2)
        return math.acos(min(max(zz, -1.0), 1.0))

    # -- stepping ----------------------------------------------------------------------------
    def step(self, q_target: np.ndarray) -> None:
        """Hold ``q_target`` on the servos for one control period (n_substeps MuJoCo steps)."""
        m, d = self.model, self.data
        d.ctrl[self.act_idx] = q_target
        tau, qd = self._tau_buf, self._qd_buf
        force_now, qvel_now = self._force_view, self._qvel_view
        for i in range(self.n_substeps):
            mujoco.mj_step(m, d)
            if self._push_left:  # the push acted on this substep; it ends after the last one
                self._push_left -= 1
                if not self._push_left:
                    d.xfrc_applied[self.root_id, :3] = 0.0
            tau[i] = force_now
            qd[i] = qvel_now
        # Positive work per substep, added substep by substep: row 0 holds the total so far
        # and the cumulative sum adds the rows in order.
        e = self._energy_buf
        e[0] = self.energy_substep_per_joint
        np.maximum(tau * qd * self.sim_dt, 0.0, out=e[1:])
        self.energy_substep_per_joint[:] = np.add.accumulate(e, axis=0)[-1]
        self.work_net += float(np.einsum("ij,ij->", tau, qd)) * self.sim_dt
        self.work_net_ctrl += float(tau[-1] @ qd[-1]) * self.control_dt
        # One sample per control period (the state at the tick), as a robot logs it.
        self.energy_ctrl_per_joint += np.maximum(tau[-1] * qd[-1] * self.control_dt, 0.0)
        self.saturated_substeps += int(
            np.count_nonzero((np.abs(tau) >= self._sat_limit).any(axis=1))
        )

    # -- contacts ----------------------------------------------------------------------------
    def contacts(self) -> Contacts:
        """Foot contact forces, their centre of pressure, and non-foot floor contacts."""
        m, d = self.model, self.data
        in_contact = [False, False]
        fz = [0.0, 0.0]  # [N]
        mx = my = total = 0.0  # moment of the vertical forces about the origin, their sum
        other = False
        ncon = d.ncon
        if ncon:
            # The contact arrays as Python lists once: a few contacts, scalar arithmetic.
            con = d.contact
            g1, g2 = con.geom1.tolist(), con.geom2.tolist()
            frames, pos = con.frame.tolist(), con.pos.tolist()
            dims, adrs, mus = con.dim.tolist(), con.efc_address.tolist(), con.friction.tolist()
            body, floor, foot_side = self._geom_body, self.floor_body, self._foot_side
            efc = d.efc_force
            for i in range(ncon):
                if body[g1[i]] == floor:
                    robot = g2[i]
                elif body[g2[i]] == floor:
                    robot = g1[i]
                else:
                    continue
                side = foot_side.get(robot)
                if side is None:
                    other = True
                    continue
                adr = adrs[i]
                if self._pyramidal and dims[i] == 3 and adr >= 0:
                    # mj_contactForce for a pyramidal cone: normal = sum of the 4 edge forces,
                    # tangent j = (edge 2j - edge 2j+1) * friction j
                    p0, p1, p2, p3 = efc[adr : adr + 4].tolist()
                    fn = ((p0 + p1) + p2) + p3
                    f1 = (p0 - p1) * mus[i][0]
                    f2 = (p2 - p3) * mus[i][1]
                else:
                    mujoco.mj_contactForce(m, d, i, self._force6)
                    fn, f1, f2 = self._force6[:3].tolist()
                fr = frames[i]  # rows: normal, tangent 1, tangent 2
                f_up = abs(fr[2] * fn + fr[5] * f1 + fr[8] * f2)  # (frame.T @ f)[2] [N]
                in_contact[side] = True
                fz[side] += f_up
                mx += f_up * pos[i][0]
                my += f_up * pos[i][1]
                total += f_up
        cop = np.array([mx / total, my / total]) if total > 1e-6 else None
        return Contacts(np.array(in_contact), np.array(fz), cop, other)

    def other_contact(self) -> bool:
        """A body other than the feet touches the floor (what :meth:`contacts` reports as
        ``other_contact``, without the forces)."""
        d = self.data
        if not d.ncon:
            return False
        con = d.contact
        body, floor, feet = self._geom_body, self.floor_body, self._foot_side
        for g1, g2 in zip(con.geom1.tolist(), con.geom2.tolist(), strict=True):
            if body[g1] == floor:
                robot = g2
            elif body[g2] == floor:
                robot = g1
            else:
                continue
            if robot not in feet:
                return True
        return False

    def support_polygon(self, in_contact: np.ndarray) -> np.ndarray:
        """(M, 2) convex hull (counter-clockwise) of the soles in contact."""
        pts = []
        d = self.data
        hx, hy = FOOT_SIZE[0] / 2, FOOT_SIZE[1] / 2
        corners = ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))
        for side in range(2):
            if in_contact[side]:
                site = int(self.sole_site_ids[side])
                px, py = d.site_xpos[site, :2].tolist()
                mat = d.site_xmat[site]
                yaw = math.atan2(mat[3], mat[0])  # (1, 0) and (0, 0) of the 3x3
                c, s = math.cos(yaw), math.sin(yaw)
                pts += [(x * c - y * s + px, x * s + y * c + py) for x, y in corners]
        if not pts:
            return np.zeros((0, 2))
        if len(pts) == 4:  # one foot: its rectangle is already convex and counter-clockwise
            return np.array(pts)
        return convex_hull(np.array(pts))

    def fall_reason(self) -> str | None:
        """Why the robot counts as fallen (docs/DESIGN.md, "What counts as a fall"), or None."""
        if self.data.qpos[2] < 0.5 * NOMINAL_PELVIS_HEIGHT:
            return "pelvis below half its nominal height"
        if self.torso_tilt() > MAX_TILT_RAD:
            return "torso tilted over 30 deg"
        return None


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Andrew's monotone chain; returns the hull counter-clockwise, (M, 2)."""
    pts = sorted(map(tuple, np.round(points, 12).tolist()))
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
    return polygon_test(p, hull, tol)[0]


def polygon_margin(p: np.ndarray, hull: np.ndarray) -> float:
    """Signed distance [m] from p to the edge of a counter-clockwise convex polygon.

    Positive inside (the distance to the nearest edge); outside, minus the largest distance
    beyond an edge line (the exact distance unless the nearest point is a corner, where it
    is a little less); -inf for a polygon with fewer than 3 vertices.
    """
    return polygon_test(p, hull)[1]


def polygon_test(p: np.ndarray, hull: np.ndarray, tol: float = 1e-3) -> tuple[bool, float]:
    """(:func:`point_in_polygon`, :func:`polygon_margin`) of p in one walk over the edges.

    Inside: p is within ``tol`` of the left of every edge (a degenerate, zero-length edge
    makes it not inside). The margin skips degenerate edges.
    """
    if len(hull) < 3:
        return False, -math.inf
    px, py = float(p[0]), float(p[1])
    pts = np.asarray(hull, dtype=float).tolist()
    inside = True
    margin = math.inf
    outside = 0.0
    for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1], strict=True):
        ex, ey = bx - ax, by - ay
        cross = ex * (py - ay) - ey * (px - ax)  # > 0 left of the edge: inside
        length = math.sqrt(ex * ex + ey * ey)
        if length == 0.0 or not cross / length >= -tol:
            inside = False  # (a degenerate edge gave NaN before: not inside)
        length = math.hypot(ex, ey)
        if length == 0.0:
            continue
        d = cross / length
        margin = min(margin, d)
        if d < 0.0:
            outside = max(outside, -d)
    return inside, (margin if margin >= 0.0 else -outside)


def _as_slice(idx: np.ndarray) -> slice | np.ndarray:
    """``slice(a, b)`` if ``idx`` is the contiguous range a..b-1, else ``idx`` itself."""
    if len(idx) and np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx))):
        return slice(int(idx[0]), int(idx[0]) + len(idx))
    return idx
