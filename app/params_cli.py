"""Command-line options generated from ``controller/params.py`` (the one source of parameters).

Every field of every parameter group becomes an option of ``simulate`` (its ``cli`` name from
the field's metadata, else ``--group-name``; a bool becomes ``--name`` / ``--no-name``), and
``--set GROUP.NAME=VALUE`` (repeatable) reaches any field by its dotted name. ``sweep`` uses the
same :func:`parse_assignment` for its ``--set GROUP.NAME=V1,V2,...`` grids. Values are
checked against the field's range when the parameters are built (ValueError, one line).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterable
from typing import Any

from controller.params import GROUPS, ControllerParams, check_value, spec


def fields() -> Iterable[tuple[str, str, dict[str, Any]]]:
    """(group, name, metadata) of every parameter, in declaration order."""
    defaults = ControllerParams()
    for group in GROUPS:
        for name, meta in spec(getattr(defaults, group)).items():
            yield group, name, meta


def option_name(group: str, name: str, meta: dict[str, Any]) -> str:
    return meta.get("cli") or f"{group}-{name}".replace("_", "-")


def convert(group: str, name: str, text: str, meta: dict[str, Any]) -> Any:
    """A field's value from text (ValueError with a one-line message)."""
    where = f"{group}.{name}"
    kind = meta["type"]
    if kind == "bool":
        low = text.strip().lower()
        if low in ("1", "true", "yes", "on"):
            return True
        if low in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"{where} must be true or false, got {text!r}")
    if kind == "str":
        return text.strip()
    try:
        value: Any = int(text) if kind == "int" else float(text)
    except ValueError:
        raise ValueError(f"{where} must be a number, got {text!r}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{where} must be finite, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """An argparse type: a whole number of at least 1 (counts of steps, workers, seconds)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def split_list(items: Iterable[str]) -> list[str]:
    """A list option's items, given with commas or spaces alike: ``--methods fixed mpc``,
    ``--methods fixed,mpc`` and ``--methods fixed, mpc`` all give ``["fixed", "mpc"]``."""
    return [part.strip() for item in items for part in item.split(",") if part.strip()]


STRATEGY_HELP = (
    "FILE.py[:Class]: your own pelvis strategy (a subclass of pelvic_walk.PelvisStrategy; "
    "docs/STRATEGIES.md), loaded once at start; its name becomes a method (repeatable)"
)


def add_strategy_argument(parser: argparse.ArgumentParser, help: str = STRATEGY_HELP) -> None:
    """``--strategy FILE.py[:Class]`` (repeatable). The files are loaded before the options
    are parsed (:func:`load_strategy_options`), so ``--method(s)`` know their names."""
    parser.add_argument(
        "--strategy",
        dest="strategies",
        action="append",
        default=[],
        metavar="FILE.py[:Class]",
        help=help,
    )


def strategy_options(argv: Iterable[str]) -> list[str]:
    """The values of every ``--strategy`` in a command line (``--strategy X``, ``--strategy=X``)."""
    out: list[str] = []
    args = iter(argv)
    for arg in args:
        if arg == "--strategy":
            out.append(next(args, ""))
        elif arg.startswith("--strategy="):
            out.append(arg.partition("=")[2])
    return out


def load_strategy_options(argv: Iterable[str]) -> str | None:
    """Load the strategy files a command line names; a one-line error, or None."""
    from controller import strategy

    for source in strategy_options(argv):
        if not source:
            return "argument --strategy: expected FILE.py[:Class]"
        try:
            strategy.load_file(source)
        except strategy.StrategyLoadError as exc:
            return f"--strategy {exc}"
    return None


def method_name(text: str) -> str:
    """An argparse type: a registered strategy's name (a built-in, or one --strategy loaded)."""
    from controller import strategy

    if not strategy.is_registered(text):
        raise argparse.ArgumentTypeError(
            f"unknown method {text!r} (choose from {', '.join(strategy.names())}; load your "
            "own with --strategy FILE.py)"
        )
    return text


class MethodList(argparse.Action):
    """``--methods``: walking methods given with commas or spaces alike, each checked (an
    unknown one is the parser's one-line error, exit 2); duplicates dropped, order kept."""

    def __call__(self, parser, namespace, values, option_string=None):
        from controller import strategy

        methods = list(dict.fromkeys(split_list(values)))
        unknown = [m for m in methods if not strategy.is_registered(m)]
        if unknown or not methods:
            parser.error(
                f"argument {option_string}: unknown method {unknown[0]!r} (choose from "
                f"{', '.join(strategy.names())}; load your own with --strategy FILE.py)"
                if unknown
                else f"argument {option_string}: name at least one method"
            )
        setattr(namespace, self.dest, methods)


def _meta_of(dotted: str) -> tuple[str, str, dict[str, Any]]:
    group, _, name = dotted.partition(".")
    for g, n, meta in fields():
        if g == group and n == name:
            return g, n, meta
    known = ", ".join(f"{g}.{n}" for g, n, _ in fields())
    raise ValueError(f"unknown parameter {dotted!r} (one of: {known})")


def parse_assignment(text: str, many: bool = False) -> tuple[str, str, Any]:
    """``GROUP.NAME=VALUE`` (or ``=V1,V2,...`` with ``many``) -> (group, name, value(s)).

    Every value is converted and range-checked; ValueError with one line otherwise.
    """
    dotted, sep, rhs = text.partition("=")
    if not sep or not rhs.strip():
        raise ValueError(f"expected GROUP.NAME=VALUE, got {text!r}")
    group, name, meta = _meta_of(dotted.strip())
    values = (
        [convert(group, name, part, meta) for part in rhs.split(",")]
        if many
        else [convert(group, name, rhs, meta)]
    )
    for v in values:
        check_value(group, name, v, meta)
    return group, name, (values if many else values[0])


def _number(group: str, name: str, meta: dict[str, Any]):
    def parse(text: str) -> Any:
        try:
            value = convert(group, name, text, meta)
            check_value(group, name, value, meta)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return value

    parse.__name__ = meta["type"]  # argparse names the type in its messages
    return parse


def add_param_options(parser: argparse.ArgumentParser, required: Iterable[str] = ()) -> None:
    """One option per parameter field plus ``--set``; ``required``: dotted names."""
    required = set(required)
    for group, name, meta in fields():
        dest = f"param:{group}.{name}"
        opt = "--" + option_name(group, name, meta)
        unit = f" [{meta['unit']}]" if meta.get("unit") else ""
        if meta["type"] == "bool":
            parser.add_argument(
                opt,
                dest=dest,
                action=argparse.BooleanOptionalAction,
                default=None,
                help=f"{meta['label']} (default {meta['default']})",
            )
            continue
        rng = f", {meta['min']:g}..{meta['max']:g}" if "min" in meta and "max" in meta else ""
        choices = f", one of {', '.join(meta['choices'])}" if meta.get("choices") else ""
        parser.add_argument(
            opt,
            dest=dest,
            type=_number(group, name, meta),
            default=None,
            required=f"{group}.{name}" in required,
            metavar="VALUE" if not choices else "MODE",
            help=f"{meta['label']}{unit} (default {meta['default']}{rng}{choices})",
        )
    parser.add_argument(
        "--set",
        dest="param_set",
        action="append",
        default=[],
        metavar="GROUP.NAME=VALUE",
        help="any parameter of controller/params.py by its dotted name",
    )


def params_from_args(
    args: argparse.Namespace, base: ControllerParams | None = None, **top: Any
) -> ControllerParams:
    """The parameters the options ask for, on top of ``base`` (ValueError on a bad value)."""
    groups: dict[str, dict[str, Any]] = {}
    for key, value in vars(args).items():
        if key.startswith("param:") and value is not None:
            group, name = key[len("param:") :].split(".")
            groups.setdefault(group, {})[name] = value
    for text in getattr(args, "param_set", []) or []:
        group, name, value = parse_assignment(text)
        groups.setdefault(group, {})[name] = value
    return (base or ControllerParams()).replace(**top, **groups)
