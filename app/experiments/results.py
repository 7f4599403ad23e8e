"""Everything the report and ``results.json`` show: :class:`StudyResults` (each section's
numbers from its topic module, the claims' verdicts, every run's summary, the run's
:class:`Meta`); :func:`to_json` writes it (``dataclasses.asdict``, NaN / inf as null).

A run's own results are in :mod:`app.experiments.outcomes`; each section's dataclasses in its
topic module (:mod:`~app.experiments.limits`, :mod:`~app.experiments.waist`, ...).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from app.experiments.ablation import AblationSection
from app.experiments.balance import BalanceSection, ZmpSection
from app.experiments.energy import EnergySection
from app.experiments.kappa import KappaSection
from app.experiments.limits import EquivalentLengths, KinematicsSection, MaxStep
from app.experiments.paper import numbers as paper_numbers
from app.experiments.reach import ReachSection
from app.experiments.robustness import RobustnessSection
from app.experiments.sensitivity import SensitivitySection
from app.experiments.waist import LateralSection, WaistSection
from app.experiments.yaw import YawSection
from pelvic_walk.core.run_spec import RunSpec
from pelvic_walk.core.summary import TIMING_KEYS as RUN_TIMING_KEYS

# keys whose values measure time or the machine, not the robot: they differ between two runs
# of the same study (on any backend)
TIMING_KEYS = ("meta", "wall_s", "duration_s", "cpu_s", *RUN_TIMING_KEYS)


@dataclass(frozen=True)
class ClaimResult:
    """One claim of the paper judged on our numbers (see :mod:`app.experiments.claims`)."""

    id: str
    section: str
    claim: str
    paper: str
    ours: str
    verdict: str  # "holds", "partly", "does not hold" or "not measured"
    rule: str
    measured: dict[str, Any]  # the numbers the rule read
    # reading -> verdict, when the claim is judged on other readings of the same numbers (e.g.
    # the energy at 1 ms); with the main reading's when they disagree (verdict DEPENDS)
    variants: dict[str, str] = field(default_factory=dict)
    readings: dict[str, str] = field(default_factory=dict)  # another reading -> our numbers
    reading: str = ""  # the main reading's name (``ours`` is on it), when there are others
    why: str = ""  # why the readings disagree (verdict DEPENDS)
    check: str = ""  # not empty: a consistency check (not counted), and why


@dataclass(frozen=True)
class Meta:
    command: str
    study: str
    date_utc: str
    duration_s: float
    run_seconds_total: float
    n_runs: int
    jobs: int
    cpu_count: int | None
    machine: str
    errors: dict[str, str]
    backend: str = ""  # where the runs ran (pelvic_walk.core.engine)
    load_average: float | None = None  # the machine's 1-minute load average at the end
    load_average_start: float | None = None  # ... and when the runs started
    cpu_s: float | None = None  # CPU time of the runs, all processes (local pool only) [s]


@dataclass(frozen=True)
class RunRecord:
    """A run as ``results.json`` lists it: the summary with every key, no extracts."""

    spec: RunSpec
    wall_s: float
    error: str | None
    summary: dict[str, Any] | None
    command: str = ""  # the pelvic-walk simulate command that reruns it


@dataclass(frozen=True)
class StudyResults:
    """Everything the report and ``results.json`` show."""

    meta: Meta
    kinematics: KinematicsSection
    max_step: dict[str, MaxStep]
    equivalent_lengths: EquivalentLengths
    waist: WaistSection
    yaw_momentum: YawSection
    energy: EnergySection
    kappa: KappaSection
    zmp: ZmpSection
    lateral: LateralSection | None = None
    balance: BalanceSection | None = None
    robustness: RobustnessSection | None = None
    sensitivity: SensitivitySection | None = None
    ablation: AblationSection | None = None  # section 10: strategies beside the MPC
    reach: ReachSection | None = None  # why a walk reaches farther than eq. (4)
    claims: list[ClaimResult] = field(default_factory=list)
    runs: dict[str, RunRecord] = field(default_factory=dict)
    figures: dict[str, str] = field(default_factory=dict)  # name -> file in figures/
    paper: dict[str, Any] = field(default_factory=paper_numbers)  # the paper's, from paper.py

    def claims_of(self, section: str) -> list[ClaimResult]:
        return [c for c in self.claims if c.section == section]

    @property
    def tallied(self) -> list[ClaimResult]:
        """The claims judged as results (the tally), without the consistency checks."""
        return [c for c in self.claims if not c.check]

    @property
    def checks(self) -> list[ClaimResult]:
        """The consistency checks: judged, listed apart, not counted."""
        return [c for c in self.claims if c.check]


def _json_safe(obj: Any) -> Any:
    """Replace NaN / inf by None and numpy scalars by Python numbers, recursively."""
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def to_json(results: StudyResults) -> str:
    """``results.json``: the study's results as JSON (NaN / inf as null)."""
    return json.dumps(_json_safe(dataclasses.asdict(results)), indent=1, allow_nan=False)


def untimed(data: Any) -> Any:
    """``results.json``'s data without :data:`TIMING_KEYS` (at any depth): what two runs of
    the same study share whatever machine or backend ran them."""
    if isinstance(data, dict):
        return {k: untimed(v) for k, v in data.items() if k not in TIMING_KEYS}
    if isinstance(data, list):
        return [untimed(v) for v in data]
    return data
