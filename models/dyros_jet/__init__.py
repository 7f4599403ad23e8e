"""DYROS-JET-like humanoid model: file paths, names and key numbers.

The MJCF (`robot.xml`, included by `scene.xml`) is written for this project from the published
numbers of DYROS-JET, the paper's robot; see `README.md` in this folder for the origin of each
number and the joint sign conventions, and `docs/DESIGN.md#robot-model`. This module is pure
(numpy only) so that `controller/` may import it.
"""

from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent

SCENE_XML: Path = _HERE / "scene.xml"
ROBOT_XML: Path = _HERE / "robot.xml"

ROOT_BODY = "pelvis"  # floating base (free joint "root") = torso side of the waist yaw joint
ROOT_JOINT = "root"

LOWER_JOINTS = (
    "waist_yaw",
    "L_hip_yaw",
    "L_hip_roll",
    "L_hip_pitch",
    "L_knee",
    "L_ankle_pitch",
    "L_ankle_roll",
    "R_hip_yaw",
    "R_hip_roll",
    "R_hip_pitch",
    "R_knee",
    "R_ankle_pitch",
    "R_ankle_roll",
)
ARM_JOINTS = (
    "L_shoulder_pitch",
    "L_shoulder_roll",
    "L_elbow",
    "R_shoulder_pitch",
    "R_shoulder_roll",
    "R_elbow",
)
ARM_QP_JOINTS = ("L_shoulder_pitch", "L_elbow", "R_shoulder_pitch", "R_elbow")
JOINTS = LOWER_JOINTS + ARM_JOINTS  # qpos[7:] / ctrl order (19)
LEFT_LEG_JOINTS = LOWER_JOINTS[1:7]
RIGHT_LEG_JOINTS = LOWER_JOINTS[7:13]

FOOT_SITES = ("L_sole", "R_sole")  # centre of the bottom face of the foot box
FOOT_GEOMS = ("L_foot", "R_foot")
HIP_BODIES = ("L_hip_yaw_link", "R_hip_yaw_link")  # body origin = hip point
ANKLE_BODIES = ("L_foot_link", "R_foot_link")  # body origin = ankle point (ankle roll link)
KEYFRAME = "walk_ready"

THIGH_LENGTH = 0.3713
SHIN_LENGTH = 0.3729
LEG_LENGTH = THIGH_LENGTH + SHIN_LENGTH  # 0.7442 hip point to ankle, knee straight
HIP_OFFSET = (0.0, 0.105, -0.1119)  # pelvis origin -> left hip point (right: y mirrored)
ANKLE_TO_SOLE = 0.105
FOOT_SIZE = (0.30, 0.17)  # length (x), width (y)
HIP_HEIGHT_Z0 = 0.68  # ankle-to-hip height while walking (paper z0)
W_STEP = 0.243  # lateral distance between the feet in walk_ready
NOMINAL_PELVIS_HEIGHT = HIP_HEIGHT_Z0 + ANKLE_TO_SOLE - HIP_OFFSET[2]  # 0.8969
TOTAL_MASS = 50.19

# Joint angles of the walk_ready keyframe (order JOINTS), from the analytic leg IK
# documented in README.md; tests/test_model.py checks they equal the MJCF keyframe.
_LEFT_LEG = (0.0, 0.0242599454, -0.4187109530, 0.8355132392, -0.4168022862, -0.0242599454)
_RIGHT_LEG = (0.0, -0.0242599454, -0.4187109530, 0.8355132392, -0.4168022862, 0.0242599454)
_ARMS = (0.0, 0.15, -0.3, 0.0, -0.15, -0.3)
_WALK_READY = np.array((0.0, *_LEFT_LEG, *_RIGHT_LEG, *_ARMS))


def walk_ready_joint_angles() -> np.ndarray:
    """(19,) joint angles of the `walk_ready` keyframe in JOINTS order (a fresh copy)."""
    return _WALK_READY.copy()
