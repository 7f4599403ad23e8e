"""A robot of a live session: a strategy, its own settings and a label.

Two robots may run the same strategy with different settings (an MPC with H = 0.8 s beside one
with 1.6 s); every robot's parameters are the session's shared ones with its overrides on top
(:func:`params_of`). A robot is written ``NAME[,KEY=VALUE...][@LABEL]`` (``serve --robot``, the
API, the panel): ``mpc,com.horizon=0.8@short horizon``. The label is the robot's key in the
session (frames, plots, ``/api/state``, ``?robot=``); without one it is the strategy's name, or
the name with the overrides (``mpc com.horizon=0.8``).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from controller import strategy
from controller.params import ControllerParams, resolve
from pelvic_walk.core.params import convert, fields, meta_of

# a label: shown on tags and legends, and sent in URLs and commands; no ',' or '@' (the
# robot form's separators), no control characters
LABEL_PATTERN = re.compile(r"^[^,@\x00-\x1f\x7f]{1,40}$")
MAX_ROBOTS = 6  # a session shows at most this many robots side by side


@dataclass(frozen=True)
class Robot:
    """One robot: ``strategy`` (a registered name), ``overrides`` (``("group.name", value)``,
    by their stored names, sorted) and ``label`` (its key in the session)."""

    strategy: str
    overrides: tuple[tuple[str, Any], ...] = ()
    label: str = ""

    @property
    def key(self) -> str:
        return self.label or default_label(self.strategy, self.overrides)

    def text(self) -> str:
        """The robot's form, ``NAME[,KEY=VALUE...][@LABEL]`` (what :func:`parse` reads)."""
        parts = [self.strategy, *(f"{k}={_shown(v)}" for k, v in self.overrides)]
        label = "" if self.key == default_label(self.strategy, self.overrides) else self.key
        return ",".join(parts) + (f"@{label}" if label else "")


def _shown(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def default_label(name: str, overrides: Sequence[tuple[str, Any]] = ()) -> str:
    if not overrides:
        return name
    text = " ".join([name, *(f"{k.partition('.')[2]}={_shown(v)}" for k, v in overrides)])
    return text if len(text) <= 40 else text[:39] + "~"


def make(
    name: str, overrides: dict[str, Any] | Iterable[tuple[str, Any]] = (), label: str = ""
) -> Robot:
    """A robot checked: a registered strategy, known parameters in range, a usable label
    (ValueError with one line otherwise)."""
    strategy.info(name)
    items = overrides.items() if isinstance(overrides, dict) else overrides
    checked = dict(_setting(str(dotted), value) for dotted, value in items)
    robot = Robot(name, tuple(sorted(checked.items())), label.strip())
    params_of(ControllerParams(), robot)  # every value in range
    if not LABEL_PATTERN.match(robot.key):
        raise ValueError(f"robot label {robot.key!r}: 1-40 characters, without ',' or '@'")
    return robot


def full_name(name: str) -> str:
    """A parameter's ``GROUP.NAME`` from its name alone when one group has it (``k_pel`` ->
    ``pelvis.k_pel``; a robot's settings are typed in a panel, where the labels show short
    names); a dotted name as it is. ValueError for a bare name two groups share."""
    if "." in name:
        return name
    found = [f"{g}.{n}" for g, n, _meta in fields(own=True) if n == name]
    if len(found) == 1:
        return found[0]
    if found:
        raise ValueError(f"{name!r} is ambiguous: write {' or '.join(found)}")
    return name  # meta_of says it is unknown, with the known names


def parse(text: str) -> Robot:
    """``NAME[,KEY=VALUE...][@LABEL]`` -> a checked :class:`Robot` (ValueError, one line)."""
    body, at, label = str(text).partition("@")
    if at and not label.strip():
        raise ValueError(f"robot {text!r}: an empty label after '@'")
    name, *assignments = [p.strip() for p in body.split(",")]
    if not name:
        raise ValueError(f"robot {text!r}: expected NAME[,KEY=VALUE...][@LABEL]")
    overrides: dict[str, Any] = {}
    for a in assignments:
        dotted, eq, rhs = a.partition("=")
        if not eq or not rhs.strip():
            raise ValueError(f"robot {text!r}: expected KEY=VALUE, got {a!r}")
        group, fname, meta = meta_of(full_name(dotted.strip()))
        overrides[f"{group}.{fname}"] = convert(group, fname, rhs, meta)
    return make(name, overrides, label)


def params_of(base: ControllerParams, robot: Robot) -> ControllerParams:
    """The robot's parameters: the session's ``base`` with its overrides and its strategy."""
    groups: dict[str, dict[str, Any]] = {}
    for dotted, value in robot.overrides:
        group, _, fname = resolve(dotted).partition(".")
        groups.setdefault(group, {})[fname] = value
    return base.replace(method=robot.strategy, **groups)


def stored_name(dotted: str) -> str:
    """A parameter's stored name (``mpc.alpha`` -> ``pelvis.alpha``, ``k_pel`` ->
    ``pelvis.k_pel``); ValueError if unknown."""
    group, fname, _meta = meta_of(full_name(dotted))
    return f"{group}.{fname}"


def _setting(dotted: str, value: Any) -> tuple[str, Any]:
    """One setting by its stored name, a whole number for a real parameter made a real (as
    the shared parameters keep it: the API's JSON gives 25 for 25.0), so settings read and
    compare alike however they were typed."""
    group, fname, meta = meta_of(full_name(dotted))
    if meta.get("type") == "float" and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    return f"{group}.{fname}", value


def with_settings(robot: Robot, values: dict[str, Any], base: ControllerParams) -> Robot:
    """``robot`` with these settings of its own (``"group.name"`` -> value), checked; a value
    equal to the shared one in ``base`` is no setting of its own (dropped)."""
    mine = dict(robot.overrides) | dict(_setting(k, v) for k, v in values.items())
    kept = {k: v for k, v in mine.items() if not _same(base.value(k), v)}
    # its key stays (the label it had, or the one made from its settings before): a slider
    # moved for one robot changes its walk from the next tick, not which robot it is
    new = Robot(robot.strategy, tuple(sorted(kept.items())), robot.key)
    params_of(base, new)
    return new


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    return a == b


def of_methods(methods: Iterable[str]) -> tuple[Robot, ...]:
    """One robot per strategy, with no settings of its own (the session's robots before
    robots had settings: ``--methods``, the lessons that name strategies)."""
    return tuple(Robot(m) for m in methods)


def check_all(robots: Sequence[Robot]) -> tuple[Robot, ...]:
    """A session's robot list: 1 to MAX_ROBOTS, labels unique (ValueError otherwise)."""
    robots = tuple(robots)
    if not robots:
        raise ValueError("a session shows at least one robot")
    if len(robots) > MAX_ROBOTS:
        raise ValueError(f"a session shows at most {MAX_ROBOTS} robots, got {len(robots)}")
    # a robot is named by its key, and one named after its strategy is shown by the strategy's
    # title ("mpc" as "pelvic MPC"): no two robots may answer to the same name
    names: dict[str, int] = {}
    for i, r in enumerate(robots):
        shown = [r.key]
        if r.key == r.strategy:
            shown.append(strategy.info(r.strategy).label)
        for name in shown:
            if names.setdefault(name.casefold(), i) != i:
                raise ValueError(
                    f"two robots would both be called {name!r}: give one of them another label"
                )
    return robots


def differing(robots: Sequence[Robot]) -> dict[str, dict[str, Any]]:
    """Per robot (by key): its own settings that not every robot shown has, with that value
    (a setting all of them share is no difference)."""
    common = set.intersection(*(set(r.overrides) for r in robots)) if robots else set()
    return {r.key: {k: v for k, v in r.overrides if (k, v) not in common} for r in robots}
