"""The MJCF model: structure, constants, keyframe geometry and standing stability."""

import mujoco
import numpy as np
import pytest

from models.dyros_jet import (
    ANKLE_BODIES,
    ANKLE_TO_SOLE,
    ARM_JOINTS,
    FOOT_GEOMS,
    FOOT_SITES,
    FOOT_SIZE,
    HIP_BODIES,
    HIP_HEIGHT_Z0,
    HIP_OFFSET,
    JOINTS,
    KEYFRAME,
    LOWER_JOINTS,
    NOMINAL_PELVIS_HEIGHT,
    ROBOT_XML,
    ROOT_BODY,
    SCENE_XML,
    TOTAL_MASS,
    W_STEP,
    walk_ready_joint_angles,
)


@pytest.fixture(scope="module")
def model():
    return mujoco.MjModel.from_xml_path(str(SCENE_XML))


def _keyframe_data(model):
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(KEYFRAME).id)
    mujoco.mj_forward(model, data)
    return data


def test_paths_and_sizes(model):
    assert SCENE_XML.is_absolute() and SCENE_XML.exists()
    assert ROBOT_XML.is_absolute() and ROBOT_XML.exists()
    assert (model.nq, model.nv, model.nu) == (26, 25, 19)
    assert len(LOWER_JOINTS) == 13 and len(ARM_JOINTS) == 6
    assert abs(mujoco.mj_getTotalmass(model) - TOTAL_MASS) < 1e-9
    assert 49.0 < TOTAL_MASS < 51.0
    assert abs(NOMINAL_PELVIS_HEIGHT - 0.8969) < 1e-12


def test_joint_and_actuator_order(model):
    root = model.joint(0)
    assert root.name == "root" and model.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    assert model.body(model.jnt_bodyid[0]).name == ROOT_BODY
    names = tuple(model.joint(i).name for i in range(1, model.njnt))
    assert names == JOINTS
    for i, name in enumerate(JOINTS):
        assert model.jnt_qposadr[i + 1] == 7 + i
        act = model.actuator(i)
        assert act.name == name
        assert model.joint(act.trnid[0]).name == name
        np.testing.assert_allclose(model.actuator_ctrlrange[i], model.jnt_range[i + 1])
        assert model.jnt_limited[i + 1]


def test_collision_filters(model):
    floor = model.geom("floor").id
    for g in range(model.ngeom):
        if g == floor:
            continue
        assert model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 1
    assert model.geom_contype[floor] == 1 and model.geom_conaffinity[floor] == 1
    for g in FOOT_GEOMS:
        assert model.geom_friction[model.geom(g).id][0] == pytest.approx(1.0)


def test_keyframe_geometry(model):
    data = _keyframe_data(model)
    key = model.key(KEYFRAME)
    np.testing.assert_allclose(key.qpos[7:], walk_ready_joint_angles(), atol=1e-12)
    np.testing.assert_allclose(key.ctrl, walk_ready_joint_angles(), atol=1e-12)
    assert key.qpos[2] == pytest.approx(NOMINAL_PELVIS_HEIGHT)
    for side, sign in ((0, 1.0), (1, -1.0)):
        site = data.site(FOOT_SITES[side])
        np.testing.assert_allclose(site.xpos, [0.0, sign * W_STEP / 2, 0.0], atol=1e-6)
        np.testing.assert_allclose(site.xmat.reshape(3, 3), np.eye(3), atol=1e-6)
        hip = data.body(HIP_BODIES[side]).xpos
        ankle = data.body(ANKLE_BODIES[side]).xpos
        np.testing.assert_allclose(
            hip - data.body(ROOT_BODY).xpos, [0.0, sign * HIP_OFFSET[1], HIP_OFFSET[2]], atol=1e-9
        )
        assert hip[2] - ankle[2] == pytest.approx(HIP_HEIGHT_Z0, abs=1e-6)
        assert ankle[2] - site.xpos[2] == pytest.approx(ANKLE_TO_SOLE, abs=1e-6)
        geom = model.geom(FOOT_GEOMS[side])
        assert 2 * geom.size[0] == pytest.approx(FOOT_SIZE[0])
        assert 2 * geom.size[1] == pytest.approx(FOOT_SIZE[1])
        # bottom face of the foot box at the sole
        assert data.geom(FOOT_GEOMS[side]).xpos[2] - geom.size[2] == pytest.approx(0.0, abs=1e-6)


def test_keyframe_stands(model):
    data = _keyframe_data(model)
    z0 = data.qpos[2]
    soles0 = np.array([data.site(s).xpos.copy() for s in FOOT_SITES])
    floor = model.geom("floor").id
    foot_ids = {model.geom(g).id for g in FOOT_GEOMS}
    for _ in range(int(2.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        for c in data.contact[: data.ncon]:
            other = c.geom2 if c.geom1 == floor else c.geom1
            assert other in foot_ids
    assert abs(data.qpos[2] - z0) < 5e-3
    soles = np.array([data.site(s).xpos for s in FOOT_SITES])
    assert np.max(np.linalg.norm((soles - soles0)[:, :2], axis=1)) < 2e-3
    assert np.linalg.norm(data.qvel) < 1e-2
