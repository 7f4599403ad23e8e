"""Command-line options generated from ``controller/params.py`` (the one source of parameters).

Every field of every parameter group becomes an option of ``simulate`` (its ``cli`` name from
the field's metadata, else ``--group-name``; a bool becomes ``--name`` / ``--no-name``), and
``--set GROUP.NAME=VALUE`` (repeatable) reaches any field by its dotted name. ``sweep`` uses the
same :func:`parse_assignment` for its ``--set GROUP.NAME=V1,V2,...`` grids. Values are
checked against the field's range when the parameters are built (ValueError, one line).
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from typing import Any

from controller.params import ControllerParams, check_value
from pelvic_walk.core.params import convert, fields, option_name, parse_assignment, split_list
from pelvic_walk.core.run_spec import OWN_FIELDS


def positive_int(text: str) -> int:
    """An argparse type: a whole number of at least 1 (counts of steps, workers, seconds)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


JOBS_HELP = (
    "worker processes (default: the CPU count); with --ray and no address, the local Ray "
    "instance's CPUs"
)


def add_jobs_argument(
    parser: argparse.ArgumentParser, default: int | None = None, help: str = JOBS_HELP
) -> None:
    """``--jobs J``: how many runs at once on the run engine (``pelvic_walk.core.engine``)."""
    parser.add_argument("--jobs", type=positive_int, default=default, metavar="J", help=help)


def add_ray_argument(parser: argparse.ArgumentParser) -> None:
    """``--ray [ADDRESS]``: the runs on a Ray cluster, or on a local Ray instance without one
    (``args.ray``: None without the option, "" for a local instance)."""
    parser.add_argument(
        "--ray",
        nargs="?",
        const="",
        default=None,
        metavar="ADDRESS",
        help="run on Ray: a cluster at ADDRESS, or without one a local Ray instance "
        "(pip install 'pelvic-walk[cluster]')",
    )


def add_set_argument(parser: argparse.ArgumentParser, grid: bool = False) -> None:
    """``--set GROUP.NAME=VALUE`` (repeatable): any parameter by its dotted name; with
    ``grid`` a sweep's axis, ``GROUP.NAME=V1,V2,...`` (``args.grid_set``)."""
    if grid:
        parser.add_argument(
            "--set",
            dest="grid_set",
            action="extend",
            nargs="+",
            default=[],
            metavar="GROUP.NAME=V1,V2,...",
            help="an axis of the grid: any parameter of controller/params.py and its values, "
            "separated by commas or spaces (repeatable; one value = fixed)",
        )
        return
    parser.add_argument(
        "--set",
        dest="param_set",
        action="append",
        default=[],
        metavar="GROUP.NAME=VALUE",
        help="any parameter of controller/params.py by its dotted name",
    )


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


def robot_spec(text: str) -> Any:
    """An argparse type: a robot ``NAME[,KEY=VALUE...][@LABEL]`` (``serve --robot``),
    checked (a :class:`~pelvic_walk.core.robots.Robot`; the parser's one-line error else)."""
    from pelvic_walk.core.robots import parse

    try:
        return parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


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
    add_set_argument(parser)


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


def study_overrides(texts: Iterable[str]) -> tuple[tuple[str, Any], ...]:
    """``--set GROUP.NAME=VALUE`` items as a study's overrides (``("group.name", value)`` by
    their stored names, sorted; ValueError with one line for a bad one, or for a parameter
    the study sets itself per run)."""
    out: dict[str, Any] = {}
    for text in texts:
        group, name, value = parse_assignment(text)
        dotted = f"{group}.{name}"
        if dotted in OWN_FIELDS:
            raise ValueError(f"--set {dotted}: the study sets it for each run")
        out[dotted] = value
    return tuple(sorted(out.items()))
