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

from controller.compiled import kernel
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
LEFT_FOOT, RIGHT_FOOT = 0, 1  # the order of FOOT_GEOMS and FOOT_SITES
# torso tilt beyond this is a fall (docs/DESIGN.md, "What counts as a fall")
MAX_TILT_RAD = np.deg2rad(30.0)


@dataclass(slots=True)  # not frozen: a frozen init costs a setattr call per field
class Contacts:
    """Foot contact state from the measured contact forces (world frame). Read-only by
    contract."""

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
        self._geom_body_arr = m.geom_bodyid.astype(np.intp)  # the contact kernel's tables
        self._geom_foot_side = np.full(m.ngeom, -1, dtype=np.intp)  # geom -> foot side or -1
        self._geom_foot_side[self.foot_geom_ids] = (LEFT_FOOT, RIGHT_FOOT)
        # Contiguous index ranges as slices (cheaper than fancy indexing every substep).
        self._act_sel = _as_slice(self.act_idx)
        self._qpos_sel = _as_slice(self.qpos_idx)
        self._qvel_sel = _as_slice(self.qvel_idx)
        n = len(JOINTS)
        self._tau_buf = np.empty((self.n_substeps, n))  # [N m] per substep
        self._qd_buf = np.empty((self.n_substeps, n))  # [rad/s] per substep
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
        d.ctrl[self._act_sel] = q_target
        tau, qd = self._tau_buf, self._qd_buf
        force_now, qvel_now, mj_step = self._force_view, self._qvel_view, mujoco.mj_step
        for i in range(self.n_substeps):
            mj_step(m, d)
            if self._push_left:  # the push acted on this substep; it ends after the last one
                self._push_left -= 1
                if not self._push_left:
                    d.xfrc_applied[self.root_id, :3] = 0.0
            tau[i] = force_now
            qd[i] = qvel_now
        work, work_ctrl, saturated = _period_energy(
            tau,
            qd,
            self.sim_dt,
            self.control_dt,
            self._sat_limit,
            self.energy_substep_per_joint,
            self.energy_ctrl_per_joint,
        )
        self.work_net += work
        self.work_net_ctrl += work_ctrl
        self.saturated_substeps += saturated

    # -- contacts ----------------------------------------------------------------------------
    def contacts(self) -> Contacts:
        """Foot contact forces, their centre of pressure, and non-foot floor contacts."""
        d = self.data
        if not d.ncon:
            return Contacts(np.zeros(2, dtype=bool), np.zeros(2), None, False)
        con = d.contact
        in_contact, fz, cop, other = _foot_contacts(
            con.geom,
            con.frame,
            con.pos,
            con.dim,
            con.efc_address,
            con.friction,
            d.efc_force,
            self._geom_body_arr,
            self._geom_foot_side,
            self.floor_body,
            self._pyramidal,
        )
        return Contacts(in_contact, fz, cop if cop[0] == cop[0] else None, other)

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
        d = self.data
        return _support_polygon(
            d.site_xpos,
            d.site_xmat,
            self.sole_site_ids,
            np.asarray(in_contact, dtype=np.bool_),
            FOOT_SIZE[0] / 2,
            FOOT_SIZE[1] / 2,
        )

    def support(self, contacts: Contacts) -> tuple[np.ndarray, bool | None, float, float]:
        """The support polygon of the feet in contact (:meth:`support_polygon`), whether the
        CoP lies in it and its margin (:func:`polygon_test`), and the largest tilt of a sole
        in contact [rad] (:meth:`sole_tilts`); None, NaN, NaN without a CoP."""
        d, cop = self.data, contacts.cop
        polygon, inside, margin, tilt = _support_and_cop(
            d.site_xpos,
            d.site_xmat,
            self.sole_site_ids,
            contacts.in_contact,
            FOOT_SIZE[0] / 2,
            FOOT_SIZE[1] / 2,
            math.nan if cop is None else float(cop[0]),
            math.nan if cop is None else float(cop[1]),
        )
        if cop is None:
            return polygon, None, math.nan, math.nan
        return polygon, bool(inside), margin, tilt

    def fall_reason(self) -> str | None:
        """Why the robot counts as fallen (docs/DESIGN.md, "What counts as a fall"), or None."""
        if self.data.qpos[2] < 0.5 * NOMINAL_PELVIS_HEIGHT:
            return "pelvis below half its nominal height"
        if self.torso_tilt() > MAX_TILT_RAD:
            return "torso tilted over 30 deg"
        return None


@kernel
def _period_energy(tau, qd, sim_dt, control_dt, sat_limit, energy_substep, energy_ctrl):
    """One control period's energy bookkeeping from its substeps' servo torques ``tau`` and
    joint rates ``qd`` (substeps, joints), in place on the per-joint totals (eq. 44):
    ``energy_substep`` += the positive work of every substep, added substep by substep;
    ``energy_ctrl`` += the positive part of the last substep's power x control_dt (one sample
    per period, as a robot logs it). Returns the net work of the substeps and of the sample
    [J], and the substeps with a servo at 99 % of its force limit."""
    n_sub, n_joints = tau.shape
    for j in range(n_joints):
        total = energy_substep[j]
        for i in range(n_sub):
            w = tau[i, j] * qd[i, j] * sim_dt
            total += 0.0 if w < 0.0 else w  # max(w, 0), NaN kept
        energy_substep[j] = total
        w = tau[n_sub - 1, j] * qd[n_sub - 1, j] * control_dt
        energy_ctrl[j] += 0.0 if w < 0.0 else w
    net = 0.0
    for i in range(n_sub):
        for j in range(n_joints):
            net += tau[i, j] * qd[i, j]
    saturated = 0
    for i in range(n_sub):
        for j in range(n_joints):
            if abs(tau[i, j]) >= sat_limit[j]:
                saturated += 1
                break
    return net * sim_dt, np.dot(tau[n_sub - 1], qd[n_sub - 1]) * control_dt, saturated


@kernel
def _foot_contacts(
    geom, frame, pos, dim, efc_address, friction, efc_force, geom_body, foot_side, floor, pyramidal
):
    """The feet's contacts with the floor from MjData's contact arrays (one row per contact):
    (in contact (2,), vertical force (2,) [N], centre of pressure (2,) [m] (NaN when no force),
    a body other than the feet touches the floor).

    A contact's force in its frame [normal, tangent 1, tangent 2] as ``mj_contactForce``
    decodes it: a pyramidal cone's normal force is the sum of its 2 (dim - 1) edge forces and
    tangent j is (edge 2j - edge 2j+1) friction j; an elliptic cone's are the constraint
    forces themselves; a contact outside the constraints (address -1) carries none. Its
    vertical component is (frame' f)_z; the CoP is the mean contact point weighted by it."""
    in_contact = np.zeros(2, dtype=np.bool_)
    fz = np.zeros(2)
    mx = my = total = 0.0  # moment of the vertical forces about the origin, their sum
    other = False
    for i in range(geom.shape[0]):
        if geom_body[geom[i, 0]] == floor:
            robot = geom[i, 1]
        elif geom_body[geom[i, 1]] == floor:
            robot = geom[i, 0]
        else:
            continue
        side = foot_side[robot]
        if side < 0:
            other = True
            continue
        adr, n = efc_address[i], dim[i]
        fn = f1 = f2 = 0.0
        if adr >= 0:
            if n == 1:
                fn = efc_force[adr]
            elif pyramidal:
                fn = efc_force[adr] + efc_force[adr + 1]
                for k in range(2, 2 * (n - 1)):
                    fn += efc_force[adr + k]
                f1 = (efc_force[adr] - efc_force[adr + 1]) * friction[i, 0]
                f2 = (efc_force[adr + 2] - efc_force[adr + 3]) * friction[i, 1]
            else:
                fn, f1, f2 = efc_force[adr], efc_force[adr + 1], efc_force[adr + 2]
        f_up = abs(frame[i, 2] * fn + frame[i, 5] * f1 + frame[i, 8] * f2)  # (frame' f)_z
        in_contact[side] = True
        fz[side] += f_up
        mx += f_up * pos[i, 0]
        my += f_up * pos[i, 1]
        total += f_up
    cop = np.full(2, np.nan)
    if total > 1e-6:
        cop[0] = mx / total
        cop[1] = my / total
    return in_contact, fz, cop, other


@kernel
def _support_polygon(site_xpos, site_xmat, sole_ids, in_contact, hx, hy):
    """(M, 2) the soles in contact as rectangles (half sizes hx, hy, yawed as their sites),
    their convex hull when both are down (counter-clockwise)."""
    pts = np.empty((8, 2))
    m = 0
    for side in range(2):
        if in_contact[side]:
            site = sole_ids[side]
            px, py = site_xpos[site, 0], site_xpos[site, 1]
            yaw = math.atan2(site_xmat[site, 3], site_xmat[site, 0])  # (1, 0), (0, 0)
            c, s = math.cos(yaw), math.sin(yaw)
            for x, y in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)):
                pts[m, 0] = x * c - y * s + px
                pts[m, 1] = x * s + y * c + py
                m += 1
    if m == 8:
        return convex_hull(pts)
    return pts[:m].copy()  # none, or one foot: its rectangle is convex and counter-clockwise


@kernel
def _support_and_cop(site_xpos, site_xmat, sole_ids, in_contact, hx, hy, cop_x, cop_y):
    """:meth:`World.support`: the polygon, the CoP's test against it (1 mm tolerance) and the
    largest sole tilt of a foot in contact, arccos of its z axis's vertical component."""
    polygon = _support_polygon(site_xpos, site_xmat, sole_ids, in_contact, hx, hy)
    inside, margin = _polygon_test(cop_x, cop_y, polygon, 1e-3)
    tilt = -np.inf
    for side in range(2):
        if in_contact[side]:
            zz = site_xmat[sole_ids[side], 8]  # element (2, 2) of the 3x3
            tilt = max(tilt, np.arccos(min(max(zz, -1.0), 1.0)))
    return polygon, inside, margin, tilt


@kernel
def convex_hull(points):
    """Andrew's monotone chain over points (n, 2) rounded to 1e-12 m; returns the hull
    counter-clockwise, (M, 2)."""
    n = points.shape[0]
    pts = np.round(points, 12)
    # sort by x, then y (insertion sort: a handful of points)
    for i in range(1, n):
        x, y = pts[i, 0], pts[i, 1]
        j = i - 1
        while j >= 0 and (pts[j, 0] > x or (pts[j, 0] == x and pts[j, 1] > y)):
            pts[j + 1] = pts[j]
            j -= 1
        pts[j + 1, 0], pts[j + 1, 1] = x, y
    if n <= 2:
        return pts
    hull = np.empty((2 * n, 2))
    k = 0
    for start, stop, step in ((0, n, 1), (n - 1, -1, -1)):  # lower, then upper chain
        base = k
        for i in range(start, stop, step):
            while k - base >= 2 and _cross(hull[k - 2], hull[k - 1], pts[i]) <= 0.0:
                k -= 1
            hull[k] = pts[i]
            k += 1
        k -= 1  # each chain's last point starts the other
    return hull[:k].copy()


@kernel
def _cross(o, a, b):
    """z of (a - o) x (b - o): > 0 when o, a, b turn counter-clockwise."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


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
    return _polygon_test(
        float(p[0]), float(p[1]), np.asarray(hull, dtype=float).reshape(-1, 2), float(tol)
    )


@kernel
def _polygon_test(px, py, pts, tol):
    """:func:`polygon_test` of the point (px, py) and the polygon (M, 2)."""
    n = pts.shape[0]
    if n < 3:
        return False, -math.inf
    inside = True
    margin = math.inf
    outside = 0.0
    for i in range(n):
        ax, ay = pts[i, 0], pts[i, 1]
        bx, by = pts[(i + 1) % n, 0], pts[(i + 1) % n, 1]
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
