"""A sweep's grid: which parameters take which values, over which methods, measuring what.

A grid comes from repeated ``--set GROUP.NAME=V1,V2,...`` options or from a YAML or JSON file
(:func:`load_grid_file`)::

    walk.dsp_ratio: [0.1, 0.2, 0.3]   # an axis: a list of values
    pelvis.k_pel: [0.15, 0.25, 0.35]
    walk.n_steps: 6                   # a single value: fixed for every cell
    fixed: {com.horizon: 1.4}         # more fixed values (optional)
    methods: [fixed, mpc]             # optional; default all three
    measure: limit                    # optional; limit | summary (default limit)

Any field of ``controller/params.py`` can be named by its dotted name, and a strategy's own
parameter by ``NAME.FIELD`` (``gain.k: [2, 4, 8]``: the other methods' runs do not read it, so
each of theirs is the same run for every value); each value is converted
and range-checked by :func:`app.cli.options.parse_assignment`, the same check as ``simulate
--set``. The cells are the cartesian product of the axes (the first axis varies slowest); an
axis of one value counts as fixed. Every problem raises :class:`GridError` with one line.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from controller import strategy
from controller.params import GROUPS, ControllerParams
from pelvic_walk.core.params import parse_assignment, split_list
from pelvic_walk.core.run_spec import RunSpec

MEASURES = ("limit", "summary")
DEFAULT_MEASURE = "limit"
SEARCHED = "walk.step_length"  # what the limit measure searches over
FILE_KEYS = ("methods", "measure", "fixed")  # the grid file's keys besides parameters

Value = str | int | float | bool
Assignment = tuple[str, Value]  # ("group.name", value)


class GridError(ValueError):
    """A bad grid: the message is one line, fit for ``error: <message>``."""


@dataclass(frozen=True)
class Axis:
    """One varied parameter: its dotted name and its values (at least two, all different)."""

    name: str
    values: tuple[Value, ...]


@dataclass(frozen=True)
class Cell:
    """One point of the grid: the axes' values plus the fixed ones."""

    index: int
    values: tuple[Assignment, ...]  # the axes' values, in axis order
    fixed: tuple[Assignment, ...]

    @property
    def label(self) -> str:
        return " ".join(f"{name}={value}" for name, value in self.values) or "(one cell)"

    def spec(self, method: str, step_length: float | None = None) -> RunSpec:
        """The run of this cell for ``method`` (``step_length`` overrides the cell's own).
        Another strategy's own parameters (``gain.k`` for the MPC) are not the method's: its
        run is the same for every value of them."""
        chosen = {
            name: value
            for name, value in (*self.fixed, *self.values)
            if name.partition(".")[0] in GROUPS or name.partition(".")[0] == method
        }
        walk = ControllerParams().walk
        step = chosen.pop("walk.step_length", walk.step_length)
        n_steps = chosen.pop("walk.n_steps", walk.n_steps)
        arms = chosen.pop("arms.enabled", ControllerParams().arms.enabled)
        return RunSpec(
            method=method,
            step_length=float(step if step_length is None else step_length),
            n_steps=int(n_steps),
            arms=bool(arms),
            seed=None,
            overrides=tuple(chosen.items()),
        )


@dataclass(frozen=True)
class Grid:
    """What a sweep runs: the axes, the fixed values, the methods and the measure."""

    axes: tuple[Axis, ...]
    fixed: tuple[Assignment, ...]
    methods: tuple[str, ...]
    measure: str

    @property
    def names(self) -> tuple[str, ...]:
        """Every parameter the grid sets: the axes, then the fixed ones."""
        return tuple(a.name for a in self.axes) + tuple(n for n, _ in self.fixed)

    def cells(self) -> list[Cell]:
        """The cartesian product of the axes (first axis slowest)."""
        combos = itertools.product(*(a.values for a in self.axes))
        names = [a.name for a in self.axes]
        return [
            Cell(i, tuple(zip(names, combo, strict=True)), self.fixed)
            for i, combo in enumerate(combos)
        ]

    def as_dict(self) -> dict[str, Any]:
        """The grid in the file format (``--grid`` reads it back)."""
        out: dict[str, Any] = {a.name: list(a.values) for a in self.axes}
        if self.fixed:
            out["fixed"] = dict(self.fixed)
        out["methods"] = list(self.methods)
        out["measure"] = self.measure
        return out


def _value(name: str, value: Any) -> Assignment:
    """One value of a parameter (a scalar from a file, or text), converted and checked."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, float) and value.is_integer():
        text = str(int(value))  # 2.0 -> "2": also valid for an integer field
    elif isinstance(value, (int, float, str)):
        text = str(value)
    else:
        raise GridError(f"{name}: {value!r} is not a single value (a number, true/false or text)")
    try:
        group, field_name, converted = parse_assignment(f"{name}={text}")
    except ValueError as exc:
        raise GridError(str(exc)) from None
    return f"{group}.{field_name}", converted


def _axis(name: str, values: Sequence[Any]) -> Axis:
    if not values:
        raise GridError(f"{name}: no values")
    converted: list[Value] = []
    dotted = name
    for v in values:
        dotted, c = _value(name, v)
        if c in converted:
            raise GridError(f"{dotted}: the value {c!r} is given twice")
        converted.append(c)
    return Axis(dotted, tuple(converted))


def check_methods(methods: Iterable[Any]) -> tuple[str, ...]:
    """The methods, each a registered strategy (``controller.strategy``), none twice."""
    out: list[str] = []
    for m in methods:
        if not strategy.is_registered(m):
            raise GridError(f"unknown method {m!r} (one of: {', '.join(strategy.names())})")
        if m in out:
            raise GridError(f"the method {m!r} is given twice")
        out.append(m)
    if not out:
        raise GridError("no method given")
    return tuple(out)


def check_measure(measure: Any) -> str:
    if measure not in MEASURES:
        raise GridError(f"unknown measure {measure!r} (one of: {', '.join(MEASURES)})")
    return str(measure)


def make_grid(
    entries: Iterable[tuple[str, Any]],
    methods: Iterable[Any] | None = None,
    measure: Any = None,
) -> Grid:
    """A grid from ``(name, value or list of values)`` pairs; one value = fixed."""
    axes: list[Axis] = []
    fixed: list[Assignment] = []
    seen: set[str] = set()
    for name, raw in entries:
        values = list(raw) if isinstance(raw, (list, tuple)) else [raw]
        axis = _axis(name, values)
        if axis.name in seen:
            raise GridError(f"{axis.name} is given twice")
        seen.add(axis.name)
        if len(axis.values) == 1:
            fixed.append((axis.name, axis.values[0]))
        else:
            axes.append(axis)
    measure = check_measure(DEFAULT_MEASURE if measure is None else measure)
    if measure == "limit" and SEARCHED in seen:
        raise GridError(
            f"{SEARCHED} is what --measure limit searches over: leave it out of the grid "
            "(or use --measure summary)"
        )
    grid = Grid(
        axes=tuple(axes),
        fixed=tuple(fixed),
        methods=check_methods(strategy.names() if methods is None else methods),
        measure=measure,
    )
    return grid


def assignments(tokens: Sequence[str]) -> list[str]:
    """``--set`` tokens as ``GROUP.NAME=V1,V2,...`` texts, values given with commas or spaces
    alike: ``["walk.dsp_ratio=0.1", "0.2", "pelvis.k_pel=0.2,0.3"]`` ->
    ``["walk.dsp_ratio=0.1,0.2", "pelvis.k_pel=0.2,0.3"]`` (a token with ``=`` starts an
    assignment, one without continues the previous one's values)."""
    out: list[list[str]] = []
    for token in tokens:
        name, sep, rhs = token.partition("=")
        if sep:
            out.append([name.strip(), *split_list([rhs])])
        elif out:
            out[-1] += split_list([token])
        else:
            raise GridError(f"--set {token}: expected GROUP.NAME=V1,V2,...")
    return [f"{name}={','.join(values)}" for name, *values in out]


def parse_sets(texts: Sequence[str]) -> list[tuple[str, list[Value]]]:
    """``GROUP.NAME=V1,V2,...`` options -> ``(name, values)`` (converted and checked)."""
    out = []
    for text in texts:
        try:
            group, name, values = parse_assignment(text, many=True)
        except ValueError as exc:
            raise GridError(str(exc)) from None
        out.append((f"{group}.{name}", values))
    return out


def load_grid_file(path: Path) -> dict[str, Any]:
    """The mapping of a YAML or JSON grid file (``.json``: JSON, otherwise YAML)."""
    try:
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise GridError(f"--grid {path}: cannot read it ({reason})") from None
    try:
        if str(path).lower().endswith(".json"):
            data = json.loads(text)
        else:
            import yaml

            data = yaml.safe_load(text)
    except Exception as exc:  # json.JSONDecodeError, yaml.YAMLError
        first = " ".join(str(exc).split())
        raise GridError(f"--grid {path}: not valid YAML or JSON: {first}") from None
    if not isinstance(data, dict) or not data:
        raise GridError(
            f"--grid {path}: expected a mapping of GROUP.NAME to a list of values, "
            f"got {type(data).__name__}"
        )
    return data


def grid_from_file(path: Path, methods: Iterable[Any] | None = None, measure: Any = None) -> Grid:
    """A grid from a file; ``methods`` and ``measure`` (command line) override the file's."""
    data = load_grid_file(path)
    entries: list[tuple[str, Any]] = []
    for key, value in data.items():
        if not isinstance(key, str):
            raise GridError(f"--grid {path}: a key must be GROUP.NAME, got {key!r}")
        if key in FILE_KEYS:
            continue
        entries.append((key, value))
    fixed = data.get("fixed", {})
    if not isinstance(fixed, dict):
        raise GridError(f"--grid {path}: 'fixed' must map GROUP.NAME to one value each")
    for key, value in fixed.items():
        if isinstance(value, (list, tuple, dict)):
            raise GridError(f"--grid {path}: fixed {key} must be a single value")
        entries.append((str(key), value))
    file_methods = data.get("methods")
    if file_methods is not None and not isinstance(file_methods, list):
        file_methods = [file_methods]
    return make_grid(
        entries,
        methods=methods if methods is not None else file_methods,
        measure=measure if measure is not None else data.get("measure"),
    )
