"""Section 3: the waist angle and rate over one mid-walk step (paper Fig. 8-9), and the three
readings of eq. (31)-(32)'s lateral distance.

The paper: with the MPC "the waist yaw joint rotates in advance before the swing starts"
(Fig. 9); with redundancy "in the non-swinging DSP, the waist joint angle decreases toward
zero" (Fig. 8) and the waist "starts to rotate when the foot of the robot starts swinging".
So the claim is about *timing*, read here as:

- *toward the swing*: the direction the waist turns over the step (the sign of its angle at
  the step's end minus at its start); the *toward rate* is the waist rate in that direction;
- *the turn*: the rise of the toward rate to its peak after lift-off; it *starts* at the last
  minimum of the toward rate before that peak (:func:`turn_onset`). A decay toward zero in the
  DSP slows down (its toward rate falls), so its last minimum is at the lift-off, where the
  swing's turn begins: a decay is not an early turn. A turn that anticipates the swing builds
  up from before the lift-off;
- the turn's *size*: how far the angle moves toward the swing from the turn's start to the
  lift-off, as a share of its range over the step (:attr:`WaistCase.early_turn_share`; 0 when
  the turn starts at the lift-off), against the share a sine over the step moves in the DSP
  (``(1 - cos(pi r)) / 2`` for a DSP of share ``r``, 9.5 % for r = 0.2; the paper's Fig. 9:
  "in a similar manner to a sine function");
- the waist *anticipates* the swing when its turn starts at least :data:`ANTICIPATION_MIN`
  before the lift-off, the toward rate at the lift-off is positive, and the turn's size is at
  least :data:`EARLY_TURN_MIN` of a sine's (a rate that barely leans toward the swing while
  the angle stays put, or still moves away, is not a turn).

The *DSP share* (how far the waist moves toward the swing over the whole DSP, as a share of
its range) is reported beside it: a decay toward zero moves the angle toward the swing too, so
it cannot tell a decay from a turn; the turn's size can (a decay's turn starts at the lift-off).

The *ablation* (``pelvis.reference`` = now: the reference angle computed from the state now and
held over the horizon, no prediction) shows whether the early turn comes from the prediction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.experiments.definitions import LATERAL, ROTATING, Study
from app.experiments.outcomes import Results, StepExtract, array, case_key, step_of, summary_of
from controller.params import CONTROL_DT, LATERAL_MODES, ControllerParams
from controller.strategy import MPC
from pelvic_walk.core.measure import walks

DEG = 180.0 / math.pi
# The onset is found on 200 Hz samples: one sample either side of the lift-off is noise.
ANTICIPATION_MIN = 2 * CONTROL_DT  # [s]
# An early turn must move the angle toward the swing by at least this share of what a sine over
# the step moves in the DSP (0.95 % of the range at a DSP share of 0.2): less is not visible
# on the paper's Fig. 9 and is not a turn.
EARLY_TURN_MIN = 0.1


def sine_share(dsp_ratio: float) -> float:
    """Share of its range a sine over the step moves in a DSP of share ``dsp_ratio``."""
    return (1.0 - math.cos(math.pi * dsp_ratio)) / 2.0


def turn_onset(t: np.ndarray, toward: np.ndarray, i_lift: int) -> int:
    """Index where the turn toward the swing starts: the last minimum of ``toward`` (the
    waist rate toward the swing) before its largest value after the lift-off ``i_lift``."""
    after = toward[i_lift:]
    if not np.any(np.isfinite(after)):
        return i_lift
    i_peak = i_lift + int(np.nanargmax(after))
    before = toward[: i_peak + 1]
    filled = np.where(np.isfinite(before), before, np.inf)
    return int(len(before) - 1 - np.argmin(filled[::-1]))


@dataclass(frozen=True)
class WaistCase:
    """Waist angle and rate over one mid-walk step."""

    method: str
    step_length: float
    complete: bool
    angle_start_deg: float
    angle_dsp_end_deg: float
    angle_end_deg: float
    angle_min_deg: float
    angle_max_deg: float
    peak_abs_angle_deg: float
    dsp_change_deg: float
    range_deg: float
    dsp_share_of_range: float  # |DSP change| / range
    dsp_share_toward_swing: float  # the same, signed: > 0 toward the coming swing
    peak_abs_rate_deg_s: float
    peak_abs_rate_change_deg_s2: float
    rate_at_liftoff_toward_swing_deg_s: float
    turn_onset_before_liftoff_s: float  # > 0: the turn toward the swing starts before lift-off
    anticipates: bool  # the turn starts >= ANTICIPATION_MIN before lift-off, rate and size
    dsp_time: float
    step_time: float
    step_index: int
    # the angle's move toward the swing from the turn's start to the lift-off / its range
    early_turn_share: float = 0.0
    sine_share: float = 0.0  # what a sine over the step moves in this DSP, / its range

    @property
    def early_turn_of_sine(self) -> float:
        """The early turn's size as a share of a sine's (NaN without a DSP)."""
        return self.early_turn_share / self.sine_share if self.sine_share > 0 else math.nan


@dataclass(frozen=True)
class WaistSection:
    cases: dict[str, WaistCase | None]


def waist_case(m: str, x: float, ex: StepExtract) -> WaistCase:
    """Waist angle and rate over one step: the timing and size of the turn toward the swing,
    the sharpness of the rate."""
    t = array(ex.t)
    ang = array(ex.waist_angle_cmd) * DEG
    rate = array(ex.waist_rate) * DEG
    i_lift = int(np.argmin(np.abs(t - ex.dsp)))
    swing = float(np.nanmax(ang) - np.nanmin(ang))
    dsp_change = float(ang[i_lift] - ang[0])
    acc = np.diff(rate) / CONTROL_DT
    turn_dir = float(np.sign(ang[-1] - ang[0])) or 1.0
    toward = rate * turn_dir
    i_on = turn_onset(t, toward, i_lift)
    lead = float(t[i_lift] - t[i_on])
    share = abs(dsp_change) / swing if swing > 1e-9 else 0.0
    rate_lift = float(toward[i_lift])
    early = float((ang[i_lift] - ang[i_on]) * turn_dir / swing) if swing > 1e-9 else 0.0
    early = early if i_on < i_lift else 0.0
    sine = sine_share(ex.dsp / ex.duration) if ex.duration > 0 else 0.0
    return WaistCase(
        method=m,
        step_length=x,
        complete=ex.complete,
        angle_start_deg=float(ang[0]),
        angle_dsp_end_deg=float(ang[i_lift]),
        angle_end_deg=float(ang[-1]),
        angle_min_deg=float(np.nanmin(ang)),
        angle_max_deg=float(np.nanmax(ang)),
        peak_abs_angle_deg=float(np.nanmax(np.abs(ang))),
        dsp_change_deg=dsp_change,
        range_deg=swing,
        dsp_share_of_range=share,
        dsp_share_toward_swing=share * (1.0 if dsp_change * turn_dir > 0 else -1.0),
        peak_abs_rate_deg_s=float(np.nanmax(np.abs(rate))),
        peak_abs_rate_change_deg_s2=float(np.nanmax(np.abs(acc))),
        rate_at_liftoff_toward_swing_deg_s=rate_lift,
        turn_onset_before_liftoff_s=lead,
        anticipates=bool(
            lead >= ANTICIPATION_MIN - 1e-9
            and rate_lift > 0.0
            and early >= EARLY_TURN_MIN * sine - 1e-12
        ),
        dsp_time=ex.dsp,
        step_time=ex.duration,
        step_index=ex.step_index,
        early_turn_share=early,
        sine_share=sine,
    )


def waist(study: Study, results: Results) -> WaistSection:
    cases: dict[str, WaistCase | None] = {}
    for x in study.figure_lengths:
        for m in ROTATING:
            ex = step_of(results, study.figure_run(m, x))
            ok = ex is not None and len(ex.t) >= 3
            cases[case_key(m, x)] = waist_case(m, x, ex) if ex is not None and ok else None
    return WaistSection(cases)


# -- the lateral distance ---------------------------------------------------------------------
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
    anticipates: bool  # the turn toward the swing starts before lift-off (WaistCase)
    turn_onset_before_liftoff_s: float
    early_turn_share: float  # the turn's size before lift-off, share of the range (WaistCase)
    rate_at_liftoff_toward_swing_deg_s: float
    peak_abs_rate_deg_s: float
    peak_abs_rate_change_deg_s2: float  # peak |yaw acceleration|
    kappa_legs_max: float | None  # kappa(legs) over the run
    reference: str = "predicted"  # pelvis.reference: "now" in the ablation


@dataclass(frozen=True)
class LateralSection:
    dsp_ratio: float
    sine_share: float  # share of its range a sine over the step moves in the DSP
    default_mode: str
    cases: dict[str, LateralCase | None]  # "<mode>@<length>"
    limits: dict[str, dict[str, float | None]]  # mode -> walks / clean limit (sensitivity)
    # the default reading with the reference from the state now (no prediction), by length
    ablation: dict[str, LateralCase | None] = field(default_factory=dict)


def lateral(
    study: Study, results: Results, limits: dict[str, dict[str, float | None]] | None = None
) -> LateralSection:
    """The MPC's waist at the figure lengths with each reading of the lateral distance;
    ``limits``: each mode's walks and clean limits (from the sensitivity section)."""
    p = ControllerParams()
    default = p.pelvis.lateral_distance
    cases: dict[str, LateralCase | None] = {}
    ablation: dict[str, LateralCase | None] = {}
    for x in study.figure_lengths:
        for mode in LATERAL_MODES:
            cases[case_key(mode, x)] = _lateral_case(
                results, study.lateral_run(mode, x), mode, x, mode == default
            )
        ablation[case_key(default, x)] = _lateral_case(
            results, study.ablation_run(x), default, x, True, "now"
        )
    return LateralSection(
        dsp_ratio=p.walk.dsp_ratio,
        sine_share=sine_share(p.walk.dsp_ratio),
        default_mode=default,
        cases=cases,
        limits=limits or {},
        ablation=ablation,
    )


def _lateral_case(
    results: Results, spec: Any, mode: str, x: float, default: bool, reference: str = "predicted"
) -> LateralCase | None:
    s, ex = summary_of(results, spec), step_of(results, spec)
    if s is None or ex is None or len(ex.t) < 3:
        return None
    w = waist_case(MPC, x, ex)
    return LateralCase(
        mode=mode,
        step_length=x,
        default=default,
        clean=s.clean,
        walks=walks(s.as_dict()),
        range_deg=w.range_deg,
        dsp_change_deg=w.dsp_change_deg,
        dsp_share_of_range=w.dsp_share_of_range,
        anticipates=w.anticipates,
        turn_onset_before_liftoff_s=w.turn_onset_before_liftoff_s,
        early_turn_share=w.early_turn_share,
        rate_at_liftoff_toward_swing_deg_s=w.rate_at_liftoff_toward_swing_deg_s,
        peak_abs_rate_deg_s=w.peak_abs_rate_deg_s,
        peak_abs_rate_change_deg_s2=w.peak_abs_rate_change_deg_s2,
        kappa_legs_max=s.condition_number_legs_max,
        reference=reference,
    )


def lateral_overrides(mode: str) -> tuple[tuple[str, Any], ...]:
    """The overrides of one reading of the lateral distance (none for the default)."""
    return () if mode == ControllerParams().pelvis.lateral_distance else ((LATERAL, mode),)
