"""Time series kept in memory-bounded arrays, and the run summary (docs/DESIGN.md, "Metrics").

``Series`` is a fixed-capacity ring buffer of named float columns: a headless run sizes it to
the whole plan, a live session to a rolling window, so memory never grows with run time.
"""

from __future__ import annotations

import numpy as np

# A walk is "clean" (the criterion for the longest step) when it succeeds with every landing
# within LANDING_ERROR_CLEAN, no QP failure, no servo saturation, no joint at its speed limit,
# and the legs never at the straight-knee singularity: kappa(J) above KAPPA_SINGULAR means the
# knee is within ~0.01 rad of straight (kappa 1283 there, 128 at 0.1 rad:
# tests/test_kinematics.py).
KAPPA_SINGULAR = 1000.0
LANDING_ERROR_CLEAN = 0.02  # [m]

COLUMNS = (
    "t",  # [s]
    "waist_angle",  # [rad] measured waist yaw
    "waist_angle_cmd",  # [rad] commanded waist yaw
    "waist_rate",  # [rad/s] commanded waist yaw rate
    "theta_ref",  # [rad] first sample of the reference pelvic angle
    "yaw_momentum",  # [kg m^2/s] whole body about the CoM, measured (MuJoCo)
    "h_low",  # [kg m^2/s] commanded lower-body yaw momentum (eq. 41)
    "h_up",  # [kg m^2/s] commanded upper-body yaw momentum (eq. 42)
    "kappa_low",  # condition number of J_low, 12 x 13 (eq. 45), every method alike
    "kappa_legs",  # condition number of J_low's 12 leg columns, every method alike
    "cop_x",
    "cop_y",  # [m] centre of pressure of the foot contact forces (nan if none)
    "zmp_in_support",  # 1 if the CoP is inside the support polygon
    "balance_margin",  # [m] CoP to the support polygon's edge, > 0 inside
    "sole_tilt",  # [rad] largest tilt of a foot in contact
    "zmp_ref_x",
    "zmp_ref_y",
    "lipm_zmp_x",
    "lipm_zmp_y",  # [m] ZMP of the LIPM from the measured CoM (paper Fig. 15)
    "com_x",
    "com_y",
    "com_z",  # [m] measured CoM (MuJoCo)
    "com_des_x",
    "com_des_y",  # [m] desired CoM (CoM MPC)
    "reach_left",
    "reach_right",  # hip-to-ankle distance / leg length (commanded)
    "energy",  # [J] cumulative positive joint work (eq. 44), 200 Hz samples
    "energy_substep",  # [J] the same from every 1 ms substep
    "tick_ms",  # [ms] controller tick time
    "strategy_ms",  # [ms] of it, the pelvis strategy's waist_rate call
    "step_index",
    "in_ssp",
    "speed_limited",  # 1 if a joint velocity sat at the IK's speed limit
)


# The unit of each column ("" for counts, flags and ratios): the Python API's tables name
# their columns with it (``pelvic_walk.Run.series``: "waist_angle [rad]").
COLUMN_UNITS: dict[str, str] = {
    "t": "s",
    "waist_angle": "rad",
    "waist_angle_cmd": "rad",
    "waist_rate": "rad/s",
    "theta_ref": "rad",
    "yaw_momentum": "kg m^2/s",
    "h_low": "kg m^2/s",
    "h_up": "kg m^2/s",
    "kappa_low": "",
    "kappa_legs": "",
    "cop_x": "m",
    "cop_y": "m",
    "zmp_in_support": "",
    "balance_margin": "m",
    "sole_tilt": "rad",
    "zmp_ref_x": "m",
    "zmp_ref_y": "m",
    "lipm_zmp_x": "m",
    "lipm_zmp_y": "m",
    "com_x": "m",
    "com_y": "m",
    "com_z": "m",
    "com_des_x": "m",
    "com_des_y": "m",
    "reach_left": "",
    "reach_right": "",
    "energy": "J",
    "energy_substep": "J",
    "tick_ms": "ms",
    "strategy_ms": "ms",
    "step_index": "",
    "in_ssp": "",
    "speed_limited": "",
}
assert tuple(COLUMN_UNITS) == COLUMNS, "one unit per column, in the columns' order"


def with_unit(name: str, unit: str) -> str:
    """A column's name with its unit: ``"waist_angle [rad]"`` (a bare name without one)."""
    return f"{name} [{unit}]" if unit else name


class ColumnIndex:
    """The position of each column by name (``COL.t`` == 0, ...), so a row is written by
    column name into the series' buffer and cannot go out of line with ``COLUMNS``."""

    def __init__(self, columns: tuple[str, ...]):
        for i, name in enumerate(columns):
            setattr(self, name, i)

    def __getattr__(self, name: str) -> int:  # only for names not set above: a typo
        raise AttributeError(f"no column {name!r}")


COL = ColumnIndex(COLUMNS)


class Series:
    """Ring buffer of named float columns with a fixed capacity (rows)."""

    def __init__(self, capacity: int, columns: tuple[str, ...] = COLUMNS):
        self.columns = columns
        self.index = {c: i for i, c in enumerate(columns)}
        self.capacity = int(capacity)
        self.data = np.full((self.capacity, len(columns)), np.nan)
        self.count = 0  # rows ever appended

    def append(self, row: np.ndarray) -> None:
        self.data[self.count % self.capacity] = row
        self.count += 1

    def append_values(self, values: tuple | list) -> None:
        """Append one row given as values in column order."""
        self.data[self.count % self.capacity] = values
        self.count += 1

    def new_row(self) -> np.ndarray:
        return np.full(len(self.columns), np.nan)

    def __len__(self) -> int:
        return min(self.count, self.capacity)

    def column(self, name: str, last: int | None = None) -> np.ndarray:
        """The column in time order (oldest first), optionally only the last rows."""
        n = len(self)
        k = n if last is None else min(last, n)
        start = self.count - k
        idx = np.arange(start, self.count) % self.capacity
        return self.data[idx, self.index[name]].copy()

    def as_dict(self, last: int | None = None) -> dict[str, np.ndarray]:
        return {c: self.column(c, last) for c in self.columns}

    def to_csv(self, path: str) -> None:
        arr = np.column_stack([self.column(c) for c in self.columns])
        np.savetxt(path, arr, delimiter=",", header=",".join(self.columns), comments="")


def two_step_windows(cum_energy_at_step_starts: np.ndarray) -> np.ndarray:
    """Energy per two-step window (eq. 44) from the cumulative energy at consecutive step starts.

    Non-overlapping windows: starts 0-2, 2-4, ... Works along axis 0 (e.g. (steps, joints)).
    """
    e = np.asarray(cum_energy_at_step_starts, dtype=float)
    if len(e) < 3:
        return np.zeros((0, *e.shape[1:]))
    return e[2::2] - e[:-2:2][: len(e[2::2])]
