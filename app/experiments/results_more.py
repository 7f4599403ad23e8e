"""Typed results of the sections added for a fair reading (issue 13), beside :mod:`results`.

- :class:`LateralSection`: the lateral distance of eq. (31)-(32) in its three readings
  (``pelvis.lateral_distance``), MPC at the figure lengths: how the waist moves in the DSP;
- :class:`BalanceSection`: the measured CoP's distance to the support polygon's edge and the
  support foot's tilt, per method and length (the CoP of contact forces always lies in the
  hull of the contact points, so "inside" alone cannot fail; the margin can be small);
- :class:`SensitivitySection`: the longest step that walks and the longest clean step of
  ``fixed`` and ``mpc`` as one parameter at a time moves off its default (``app.sweep``'s
  limit search).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class LateralCase:
    """MPC at one length with one reading of the lateral distance."""

    mode: str
    step_length: float  # [m]
    default: bool  # the mode of controller/params.py
    clean: bool
    walks: bool
    range_deg: float  # waist angle max - min over the step
    dsp_change_deg: float  # waist angle at lift-off - at the step's start
    dsp_share_of_range: float  # |dsp_change| / range
    toward_swing: bool  # the DSP change has the sign of the step's turn
    peak_abs_rate_deg_s: float
    peak_abs_rate_change_deg_s2: float  # peak |yaw acceleration|
    kappa_legs_max: float | None


@dataclass(frozen=True)
class LateralSection:
    dsp_ratio: float
    sine_share: float  # share of its range a sine over the step moves in the DSP
    default_mode: str
    cases: dict[str, LateralCase | None]  # "<mode>@<length>"
    limits: dict[str, dict[str, float | None]]  # mode -> walks / clean limit (sensitivity)


@dataclass(frozen=True)
class BalanceCase:
    method: str
    step_length: float  # [m]
    clean: bool
    fell: bool
    margin_min_mm: float | None  # CoP to the support polygon's edge, walking ticks
    margin_p5_mm: float | None  # its 5th percentile
    tilt_max_deg: float | None  # largest tilt of a foot in contact


@dataclass(frozen=True)
class BalanceSection:
    lengths: list[float]
    cases: dict[str, BalanceCase | None]  # "<method>@<length>"


@dataclass(frozen=True)
class SensitivityRow:
    """One cell of the sensitivity sweep: one parameter off its default, one method."""

    parameter: str  # "group.name", "" for the baseline (every default)
    value: Any
    method: str
    walks_limit: float | None  # [m]
    walks_first_fail: float | None
    clean_limit: float | None
    clean_first_fail: float | None
    runs: int
    wall_s: float
    error: str | None = None


@dataclass(frozen=True)
class SensitivitySection:
    n_steps: int
    resolution: float  # [m]
    search: tuple[float, float]  # [m] lengths the limit search covers
    defaults: dict[str, Any]  # parameter -> its default
    rows: list[SensitivityRow] = field(default_factory=list)
    n_runs: int = 0
    duration_s: float = 0.0

    def limit(self, parameter: str, value: Any, method: str, key: str) -> float | None:
        """``key`` ("walks_limit", "clean_limit", ...) of one cell, None if it is missing."""
        for r in self.rows:
            if r.parameter == parameter and r.value == value and r.method == method:
                return getattr(r, key)
        return None
