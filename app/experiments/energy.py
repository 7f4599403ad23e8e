"""Section 5: energy per two-step window (eq. 44, paper Table 1) over the seeded repeats, and
when two cells differ.

A cell is one (method, length): the windows of the repeats that did not fall, at 200 Hz (one
sample of servo torque and joint speed per control period, as a robot logs them) and from
every 1 ms substep (:meth:`EnergySection.at_substep` gives the section at that rate).

Two cells differ only when the repeats say so; otherwise their ordering is a *tie*:

- means: Welch's t-test over the repeats' mean windows (:func:`welch_p`, p <
  :data:`SIGNIFICANCE`); the windows of one run are not independent, so the runs are the
  samples;
- standard deviations (of all windows of a cell, as the paper's): a bootstrap over the runs
  (:func:`std_gap_p`: the runs resampled with replacement in each cell, the windows of a run
  kept together), two-sided, p < :data:`SIGNIFICANCE`.

A significant difference also has to be large enough to count: two means within
:data:`MIN_EFFECT_MEAN` of the larger one (two stds within :data:`MIN_EFFECT_STD`) tie
however small the p-value, in both readings. With 10 repeats of 20 steps a gap of 0.2 J in
26 J is significant (p = 0.035 at 0.15 m) yet says nothing about a method: the repeats'
means spread by 1-2 % of the cell's mean and the two readings of eq. (44) differ by a factor
of 2-4. The thresholds are stated, not fitted: they were set before the verdicts were read.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from app.experiments import paper
from app.experiments.definitions import Study
from app.experiments.outcomes import Results, length_key, summary_of

SIGNIFICANCE = 0.05  # two cells differ when the test's p is below this
BOOTSTRAP = 2000  # resamples of the std test (seeded: the same p every time)
MIN_EFFECT_MEAN = 0.02  # two means closer than this share of the larger one tie
MIN_EFFECT_STD = 0.10  # two stds closer than this share of the larger one tie
# joints grouped for the energy breakdown: group -> name fragments of models.dyros_jet.JOINTS
JOINT_GROUPS = {
    "hip yaw": ("hip_yaw",),
    "hip roll": ("hip_roll",),
    "hip pitch": ("hip_pitch",),
    "knee": ("knee",),
    "ankle pitch": ("ankle_pitch",),
    "ankle roll": ("ankle_roll",),
    "waist": ("waist",),
    "arms": ("shoulder", "elbow"),
}


def joint_groups(per_joint: list[float], joints: list[str]) -> dict[str, float]:
    """Per-joint figures summed into :data:`JOINT_GROUPS` (both legs together)."""
    return {
        g: sum(v for v, j in zip(per_joint, joints, strict=True) if any(f in j for f in frags))
        for g, frags in JOINT_GROUPS.items()
    }


@dataclass(frozen=True)
class EnergyCell:
    """One cell of Table 1, ours (over the runs that did not fall) and the paper's."""

    mean: float | None  # [J]
    std: float | None
    n_windows: int
    n_runs: int
    n_not_fallen: int
    n_clean: int
    paper_mean: float | None
    paper_std: float | None
    paper_dash: bool  # the paper has "—" (the method could not walk that length)
    run_means: list[float] = field(default_factory=list)  # [J] each repeat's mean window
    mean_substep: float | None = None  # [J] the same windows from every 1 ms substep
    std_substep: float | None = None
    per_joint_mean: list[float] = field(default_factory=list)  # [J] mean window, per joint
    run_windows: list[list[float]] = field(default_factory=list)  # [J] each repeat's windows
    run_windows_substep: list[list[float]] = field(default_factory=list)

    def at_substep(self) -> EnergyCell:
        """This cell with the 1 ms figures in place of the 200 Hz ones."""
        return dataclasses.replace(
            self,
            mean=self.mean_substep,
            std=self.std_substep,
            run_means=[float(np.mean(w)) for w in self.run_windows_substep if w],
            run_windows=self.run_windows_substep,
        )


@dataclass(frozen=True)
class EnergySection:
    table: dict[str, dict[str, EnergyCell]]  # method -> length_key -> cell
    lengths: list[float]
    repeats: int
    steps: int
    # Welch's t-test over the repeats' means: "<length>:<a>-<b>" -> p-value
    p_values: dict[str, float] = field(default_factory=dict)
    joints: list[str] = field(default_factory=list)  # per_joint_mean's order
    rate: str = "200 Hz"  # the sampling of mean / std: "200 Hz" or "1 ms"

    def p_value(self, x: float, a: str, b: str) -> float | None:
        return self.p_values.get(
            f"{length_key(x)}:{a}-{b}", self.p_values.get(f"{length_key(x)}:{b}-{a}")
        )

    def cell(self, method: str, x: float) -> EnergyCell | None:
        """The cell where we measured a mean, else None."""
        c = self.table.get(method, {}).get(length_key(x))
        return c if c and c.mean is not None else None

    def at_substep(self) -> EnergySection:
        """The section with every cell's 1 ms figures (means, stds, runs' windows)."""
        table = {m: {k: c.at_substep() for k, c in row.items()} for m, row in self.table.items()}
        methods = list(table)
        p_values = {}
        for x in self.lengths:
            for i, a in enumerate(methods):
                for b in methods[i + 1 :]:
                    ca, cb = table[a].get(length_key(x)), table[b].get(length_key(x))
                    p = welch_p(ca.run_means, cb.run_means) if ca and cb else None
                    if p is not None:
                        p_values[f"{length_key(x)}:{a}-{b}"] = p
        return dataclasses.replace(self, table=table, p_values=p_values, rate="1 ms")


def welch_p(a: Sequence[float], b: Sequence[float]) -> float | None:
    """Welch's t-test p-value of two samples of repeat means (None: fewer than 2 each, or
    both without spread)."""
    from scipy import stats

    if len(a) < 2 or len(b) < 2:
        return None
    if np.std(a) == 0 and np.std(b) == 0:
        return 0.0 if np.mean(a) != np.mean(b) else 1.0
    return float(stats.ttest_ind(a, b, equal_var=False).pvalue)


def significant(a: EnergyCell, b: EnergyCell) -> bool:
    """The repeats' means differ (Welch's t-test, p < SIGNIFICANCE); with fewer than two
    repeats, by at least twice the standard error of the windows' means."""
    p = welch_p(a.run_means, b.run_means)
    if p is not None:
        return p < SIGNIFICANCE
    assert a.mean is not None and a.std is not None  # cells of EnergySection.cell()
    assert b.mean is not None and b.std is not None
    se = math.sqrt(a.std**2 / max(a.n_windows, 1) + b.std**2 / max(b.n_windows, 1))
    return abs(a.mean - b.mean) >= 2 * se


def below_effect(a: float, b: float, share: float) -> bool:
    """``a`` and ``b`` closer than ``share`` of the larger magnitude: too small to count."""
    return abs(a - b) < share * max(abs(a), abs(b))


def order_means(a: EnergyCell, b: EnergyCell) -> int:
    """-1 if ``a``'s mean is significantly below ``b``'s (and by at least
    :data:`MIN_EFFECT_MEAN`), +1 if above, 0 a tie."""
    assert a.mean is not None and b.mean is not None
    if below_effect(a.mean, b.mean, MIN_EFFECT_MEAN) or not significant(a, b):
        return 0
    return -1 if a.mean < b.mean else 1


def std_gap_p(a: EnergyCell, b: EnergyCell, n: int = BOOTSTRAP) -> float | None:
    """Two-sided p-value that the stds of ``a``'s and ``b``'s windows differ: a bootstrap
    over the runs (None: fewer than two runs with windows in a cell)."""
    rng = np.random.default_rng(0)

    def resampled_stds(runs: list[list[float]]) -> np.ndarray | None:
        runs = [w for w in runs if len(w)]
        if len(runs) < 2:
            return None
        # each run's count, sum and sum of squares: a resample's pooled std from their sums
        stats = np.array([(len(w), np.sum(w), np.sum(np.square(w))) for w in runs])
        pick = rng.integers(0, len(runs), (n, len(runs)))
        cnt, s1, s2 = (stats[:, k][pick].sum(axis=1) for k in range(3))
        return np.sqrt(np.maximum(s2 / cnt - (s1 / cnt) ** 2, 0.0))

    sa, sb = resampled_stds(a.run_windows), resampled_stds(b.run_windows)
    if sa is None or sb is None:
        return None
    share = float(np.mean(sa < sb))
    return float(min(1.0, 2 * min(share, 1.0 - share)))


def order_stds(a: EnergyCell, b: EnergyCell) -> int:
    """-1 if ``a``'s std is significantly below ``b``'s, +1 if above, 0 a tie; without runs'
    windows (fewer than two runs) the raw ordering."""
    assert a.std is not None and b.std is not None
    if below_effect(a.std, b.std, MIN_EFFECT_STD):
        return 0
    p = std_gap_p(a, b)
    if p is not None and p >= SIGNIFICANCE:
        return 0
    return -1 if a.std < b.std else (1 if a.std > b.std else 0)


def energy(study: Study, results: Results) -> EnergySection:
    """Table 1: energy per two-step window over the repeats that did not fall."""
    table: dict[str, dict[str, EnergyCell]] = {}
    for m in study.methods:
        table[m] = {}
        for x in study.energy_lengths:
            sums = [summary_of(results, s) for s in study.energy_runs(m, x)]
            ok = [s for s in sums if s and not s.fell]
            runs = [list(s.energy_two_step_windows) for s in ok]
            runs_sub = [list(s.energy_two_step_windows_substep) for s in ok]
            windows = [w for r in runs for w in r]
            substep = [w for r in runs_sub for w in r]
            joints = [
                s.other["energy_two_step_per_joint_mean"]
                for s in ok
                if s.other.get("energy_two_step_per_joint_mean")
            ]
            theirs = paper.TABLE1.get(m, {}).get(x)
            table[m][length_key(x)] = EnergyCell(
                mean=float(np.mean(windows)) if windows else None,
                std=float(np.std(windows)) if windows else None,
                n_windows=len(windows),
                n_runs=len(sums),
                n_not_fallen=len(ok),
                n_clean=sum(1 for s in sums if s and s.clean),
                paper_mean=theirs.mean if theirs else None,
                paper_std=theirs.std if theirs else None,
                paper_dash=theirs is None,
                run_means=[float(np.mean(r)) for r in runs if r],
                mean_substep=float(np.mean(substep)) if substep else None,
                std_substep=float(np.std(substep)) if substep else None,
                per_joint_mean=np.mean(joints, axis=0).tolist() if joints else [],
                run_windows=runs,
                run_windows_substep=runs_sub,
            )
    p_values = {}
    for x in study.energy_lengths:
        cells = {m: table[m][length_key(x)] for m in study.methods}
        for i, a in enumerate(study.methods):
            for b in study.methods[i + 1 :]:
                p = welch_p(cells[a].run_means, cells[b].run_means)
                if p is not None:
                    p_values[f"{length_key(x)}:{a}-{b}"] = p
    from pelvic_walk.core.world import JOINTS

    return EnergySection(
        table,
        list(study.energy_lengths),
        study.energy_repeats,
        study.energy_steps,
        p_values=p_values,
        joints=list(JOINTS),
    )
