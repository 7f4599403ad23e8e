"""The paper's numbers, typed once: the claims, Table 1, the figures and the report read them here.

Copied from Park & Park (IEEE Access 2022), :data:`CITATION`; the section, table or figure each
number comes from is named beside it. Nothing else in ``app/experiments`` types a paper number:
texts such as "0.31 / 0.42 m, +35 %" are formatted from these.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

from controller.strategy import FIXED, MPC, REDUNDANCY

CITATION = (
    'B. Park and J. Park, "Optimization of Pelvic Rotation Walking Pattern Considering Future '
    'States Using Model Predictive Control to Increase the Step Length", IEEE Access, 2022, '
    "doi:10.1109/ACCESS.2022.3169886"
)


@dataclass(frozen=True)
class KinematicInputs:
    """The robot numbers of eq. (1)-(5), keywords of ``controller.analysis.kinematic_analysis``."""

    l_leg: float  # [m] stretched leg, hip to ankle
    z0: float  # [m] hip height above the ankle
    l_pel: float  # [m] distance between the hip joints
    w_step: float  # [m] lateral distance between the feet
    theta_pel_deg: float  # [deg] pelvic rotation


@dataclass(frozen=True)
class KinematicLimits:
    """The longest static step of eq. (4) and eq. (5) and the increase the paper reports."""

    step_max_fixed: float  # [m] eq. (4)
    step_max_rotation: float  # [m] eq. (5)
    increase_percent: float  # [%]


class MeanStd(NamedTuple):
    """One cell of Table 1 [J]."""

    mean: float
    std: float


# Sec. II, eq. (1)-(5).
ROBOT = KinematicInputs(l_leg=0.75, z0=0.68, l_pel=0.21, w_step=0.243, theta_pel_deg=45.0)
KINEMATICS = KinematicLimits(step_max_fixed=0.31, step_max_rotation=0.42, increase_percent=35.0)

# Sec. VI-B: longest step walked in simulation [m].
MAX_STEP: dict[str, float] = {FIXED: 0.30, REDUNDANCY: 0.40, MPC: 0.40}

# Fig. 8-9 (waist angle and rate) and Fig. 12 (yaw momentum) show 0.3 and 0.4 m steps.
FIGURE_LENGTHS: tuple[float, ...] = (0.30, 0.40)
# Sec. VI-C, Fig. 9(a): MPC waist angle from -22 to +22 deg over a 0.4 m step.
WAIST_PEAK_DEG = 22.0
WAIST_PEAK_LENGTH = 0.40  # [m]

# Sec. VI-F, Fig. 16 (experiment): arm swing cuts the yaw angular momentum by up to 60 %.
ARM_REDUCTION_PERCENT = 60.0

# Sec. VI-E, Fig. 13 (0.30, 0.35, 0.40 m): at 0.30 m kappa of the fixed pelvis at landing is
# about twice the rotating methods'; at 0.35 m it diverges for the fixed pelvis.
KAPPA_LENGTHS: tuple[float, ...] = (0.30, 0.35, 0.40)
KAPPA_RATIO = 2.0
KAPPA_RATIO_LENGTH = 0.30  # [m]
KAPPA_DIVERGES_LENGTH = 0.35  # [m]

# Sec. VI-F, Fig. 15: the ZMP inside the support foot, MPC, 0.3 m steps.
ZMP_LENGTH = 0.30  # [m]

# Table 1: energy during two steps [J] (the paper's header says "Mean (W)"; eq. (44) is an
# energy), mean and standard deviation over 100 windows (10 runs x 20 steps); None = "—"
# (the method could not walk that step length).
TABLE1_RUNS = 10
TABLE1_STEPS = 20
TABLE1_WINDOWS = TABLE1_RUNS * TABLE1_STEPS // 2  # two steps per window
TABLE1_LENGTHS: tuple[float, ...] = (0.15, 0.20, 0.25, 0.30, 0.35, 0.40)
TABLE1: dict[str, dict[float, MeanStd | None]] = {
    FIXED: {
        0.15: MeanStd(14.78, 2.89),
        0.20: MeanStd(19.11, 5.55),
        0.25: MeanStd(19.76, 10.23),
        0.30: MeanStd(50.16, 22.32),
        0.35: None,
        0.40: None,
    },
    REDUNDANCY: {
        0.15: MeanStd(12.79, 3.04),
        0.20: MeanStd(18.17, 6.12),
        0.25: MeanStd(27.14, 9.16),
        0.30: MeanStd(60.49, 28.55),
        0.35: MeanStd(411.25, 208.41),
        0.40: MeanStd(941.32, 597.6),
    },
    MPC: {
        0.15: MeanStd(10.06, 0.87),
        0.20: MeanStd(16.92, 3.31),
        0.25: MeanStd(26.53, 2.57),
        0.30: MeanStd(157.92, 9.73),
        0.35: MeanStd(309.64, 32.51),
        0.40: MeanStd(412.34, 34.15),
    },
}
# Sec. VI-D's reading of Table 1: up to this length rotation costs less than the fixed pelvis,
# above it (to the fixed pelvis's limit) more; the MPC's mean is below redundancy's at the
# longest lengths.
ENERGY_ROTATION_CHEAPER_UP_TO = 0.20  # [m]
ENERGY_MPC_BELOW_REDUNDANCY: tuple[float, ...] = (0.35, 0.40)


def max_step_increase_percent() -> float:
    """The paper's gain of the longest step with rotation (MPC) over the fixed pelvis [%]."""
    return 100.0 * (MAX_STEP[MPC] / MAX_STEP[FIXED] - 1.0)


def table1_lengths(method: str, walked: bool = True) -> list[float]:
    """Table 1's lengths where ``method`` has a value (``walked``) or a dash (not ``walked``)."""
    return [x for x in TABLE1_LENGTHS if (TABLE1[method][x] is not None) == walked]


def table1_lengths_mpc_not_below_redundancy() -> list[float]:
    """Table 1's lengths where the MPC's mean is not below redundancy's (0.30 m)."""
    return [
        x
        for x in TABLE1_LENGTHS
        if (a := TABLE1[MPC][x]) and (b := TABLE1[REDUNDANCY][x]) and a.mean >= b.mean
    ]


def numbers() -> dict[str, Any]:
    """The paper's headline numbers as plain data: ``results.json``'s ``paper``, which the web
    tool's lessons quote (they cannot import the study)."""
    return {
        "citation": CITATION,
        "robot": asdict(ROBOT),
        "kinematics": asdict(KINEMATICS),
        "max_step": dict(MAX_STEP),
        "waist_peak_deg": WAIST_PEAK_DEG,
        "waist_peak_length": WAIST_PEAK_LENGTH,
        "arm_reduction_percent": ARM_REDUCTION_PERCENT,
        "kappa_ratio": KAPPA_RATIO,
        "kappa_diverges_length": KAPPA_DIVERGES_LENGTH,
    }
