"""How a claim is judged: conditions on measured numbers, and the one verdict helper.

A :class:`Rule` is data: the :class:`Bound` s that must all be met for "holds" (or any one, with
``any_holds``), and those for "partly". :func:`verdict` applies a rule to the numbers a claim
measured; a claim whose numbers are missing is "not measured". A bound on NaN or None is not met.
A :class:`Claim` ties a claim of the paper to its measurement and rule (the table of them is
:data:`app.experiments.claims.CLAIMS`). A claim judged on other readings of the same numbers
(its ``variants``, e.g. the energy at 1 ms) holds, partly holds or does not only where every
reading agrees; otherwise its verdict is :data:`DEPENDS`, with each reading's verdict (unless
the main reading is ``primary``: the others are then reported beside it and do not decide). A
*consistency check* (``check``: why) is judged the same way but is not a result: its inputs
were chosen to match the paper, or it follows from another rule; it is listed apart and not
counted.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from app.experiments.definitions import Study
from app.experiments.results import ClaimResult, StudyResults

Measure = Callable[[Study, StudyResults], dict[str, Any] | None]

HOLDS, PARTLY, FAILS, NOT_MEASURED = "holds", "partly", "does not hold", "not measured"
INCONCLUSIVE = "inconclusive"  # the evidence cannot tell (within resolution, not significant)
DEPENDS = "depends on the reading"  # the readings of the same numbers disagree
VERDICTS = (HOLDS, PARTLY, INCONCLUSIVE, FAILS, DEPENDS, NOT_MEASURED)
_OPS = {
    ">": operator.gt,
    ">=": operator.ge,
    "<": operator.lt,
    "<=": operator.le,
    "==": operator.eq,
}


@dataclass(frozen=True)
class Bound:
    """``measured[measure] <op> limit``; booleans compare with ``==``."""

    measure: str
    op: str
    limit: float | bool

    def __post_init__(self) -> None:
        if self.op not in _OPS:
            raise ValueError(f"unknown comparison {self.op!r}")

    def met(self, measured: Mapping[str, Any]) -> bool:
        v = measured[self.measure]
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return False
        return bool(_OPS[self.op](v, self.limit))

    def words(self, names: Mapping[str, str], short: bool = False) -> str:
        """E.g. ``ratio >= 1.5`` (``short``: ``>= 1.5``); ``not (run clean)`` for a flag."""
        what = names.get(self.measure, self.measure)
        if isinstance(self.limit, bool):
            return what if self.limit else f"not ({what})"
        return f"{'' if short else what + ' '}{self.op} {self.limit:g}"


@dataclass(frozen=True)
class Rule:
    """Holds when every ``holds`` bound is met (any one with ``any_holds``); else partly when
    every ``partly`` bound is met (never without partly bounds); else *inconclusive* when every
    ``inconclusive`` bound is met (the evidence cannot tell: its differences are within the
    measurement's resolution or not significant; never without such bounds); else does not
    hold."""

    holds: tuple[Bound, ...]
    partly: tuple[Bound, ...] = ()
    any_holds: bool = False
    inconclusive: tuple[Bound, ...] = ()

    def measures(self) -> set[str]:
        return {b.measure for b in self.holds + self.partly + self.inconclusive}

    def words(self, names: Mapping[str, str]) -> str:
        joint = " or " if self.any_holds else " and "
        text = "holds if " + joint.join(b.words(names) for b in self.holds)
        if self.partly:  # a measure the holds rule named already is not named again
            named = {b.measure for b in self.holds} if len(self.holds) == 1 else set()
            partly = (b.words(names, short=b.measure in named) for b in self.partly)
            text += "; partly if " + " and ".join(partly)
        if self.inconclusive:
            text += "; else inconclusive if " + " and ".join(
                b.words(names) for b in self.inconclusive
            )
        return text


def verdict(measured: Mapping[str, Any] | None, rule: Rule) -> str:
    """The verdict of ``rule`` on ``measured`` (None: the claim could not be measured)."""
    if measured is None:
        return NOT_MEASURED
    met = [b.met(measured) for b in rule.holds]
    if any(met) if rule.any_holds else all(met):
        return HOLDS
    if rule.partly and all(b.met(measured) for b in rule.partly):
        return PARTLY
    if rule.inconclusive and all(b.met(measured) for b in rule.inconclusive):
        return INCONCLUSIVE
    return FAILS


def at_least(measure: str, limit: float) -> Bound:
    return Bound(measure, ">=", limit)


def above(measure: str, limit: float) -> Bound:
    return Bound(measure, ">", limit)


def below(measure: str, limit: float) -> Bound:
    return Bound(measure, "<", limit)


def at_most(measure: str, limit: float) -> Bound:
    return Bound(measure, "<=", limit)


def is_(measure: str, value: bool) -> Bound:
    return Bound(measure, "==", value)


def _always(study: Study, r: StudyResults) -> bool:
    return True


@dataclass(frozen=True)
class Claim:
    """One claim of the paper and how it is judged on our model."""

    id: str
    section: str  # of the report
    claim: str  # in words
    paper: str  # the paper's value
    measure: Measure
    ours: str  # our value: a ``str.format`` template over the measured numbers
    rule: Rule
    names: Mapping[str, str]  # measured number -> words, for the rule's text
    note: str = ""  # why the rule is what it is
    applies: Callable[[Study, StudyResults], bool] = _always
    # other readings of the same numbers, judged by the same rule (e.g. "1 ms": the energy
    # from every 1 ms substep instead of 200 Hz samples)
    variants: Mapping[str, Measure] = field(default_factory=dict)
    reading: str = ""  # the main reading's name, when there are variants (e.g. "200 Hz")
    why_readings: str = ""  # why the readings can disagree (said when they do)
    # the main reading decides alone (the others are reported, e.g. the energy at 200 Hz,
    # which aliases, beside the 1 ms reading)
    primary: bool = False
    check: str = ""  # not empty: a consistency check, not a result; why

    def judge(self, study: Study, r: StudyResults) -> ClaimResult:
        measured = self.measure(study, r)
        rule = self.rule.words(self.names) + (f" ({self.note})" if self.note else "")
        ours = self.ours.format(**measured) if measured is not None else "-"
        v = verdict(measured, self.rule)
        variants, readings = {}, {}
        for name, m in self.variants.items():
            other = m(study, r)
            variants[name] = verdict(other, self.rule)
            readings[name] = self.ours.format(**other) if other is not None else "-"
        if v != NOT_MEASURED and any(x != v for x in variants.values()):
            variants = {self.reading or "main": v, **variants}
            v = v if self.primary else DEPENDS
        return ClaimResult(
            self.id,
            self.section,
            self.claim,
            self.paper,
            ours,
            v,
            rule,
            measured or {},
            variants,
            readings=readings,
            reading=self.reading,
            why=self.why_readings if v == DEPENDS or (self.primary and len(variants) > 1) else "",
            check=self.check,
        )
