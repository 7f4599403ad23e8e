"""Parameters by name, from text: the one reading of ``controller/params.py``'s field specs that
every face shares (the command line's options, ``--set GROUP.NAME=VALUE`` and sweep grids,
``pelvic_walk.simulate``'s keywords, the API). A strategy's own parameters are named
``NAME.FIELD`` (the strategy's name as their group); a paper parameter a strategy owns is also
named under it (``mpc.alpha`` = ``pelvis.alpha``).

A field is named by its dotted name ``group.name`` or its command-line name (the field's ``cli``
metadata, else ``group-name``); :func:`convert` reads a value from text and
:func:`parse_assignment` reads ``GROUP.NAME=VALUE`` (or ``=V1,V2,...``), each checked against
the field's range (ValueError, one line).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from controller.params import GROUPS, OWN_PARAMS, ControllerParams, check_value, resolve, spec


def fields(own: bool = False) -> Iterable[tuple[str, str, dict[str, Any]]]:
    """(group, name, metadata) of every parameter of the paper, in declaration order; with
    ``own``, then every registered strategy's own (group: the strategy's name)."""
    defaults = ControllerParams()
    for group in GROUPS:
        for name, meta in spec(getattr(defaults, group)).items():
            yield group, name, meta
    if own:
        for group, cls in list(OWN_PARAMS.items()):
            for name, meta in spec(cls).items():
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
        what = "an integer" if kind == "int" else "a number"
        raise ValueError(f"{where} must be {what}, got {text!r}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{where} must be finite, got {text!r}")
    return value


def split_list(items: Iterable[str]) -> list[str]:
    """A list option's items, given with commas or spaces alike: ``--methods fixed mpc``,
    ``--methods fixed,mpc`` and ``--methods fixed, mpc`` all give ``["fixed", "mpc"]``."""
    return [part.strip() for item in items for part in item.split(",") if part.strip()]


def meta_of(dotted: str) -> tuple[str, str, dict[str, Any]]:
    """(group, name, metadata) of a parameter named ``group.name``, a strategy's own
    ``NAME.FIELD``, or a paper parameter under the strategy that owns it (``mpc.alpha``: the
    paper's ``pelvis.alpha`` is returned)."""
    group, _, name = resolve(dotted).partition(".")
    for g, n, meta in fields(own=True):
        if g == group and n == name:
            return g, n, meta
    known = ", ".join(f"{g}.{n}" for g, n, _ in fields(own=True))
    raise ValueError(f"unknown parameter {dotted!r} (one of: {known})")


def parse_assignment(text: str, many: bool = False) -> tuple[str, str, Any]:
    """``GROUP.NAME=VALUE`` (or ``=V1,V2,...`` with ``many``) -> (group, name, value(s)).

    Every value is converted and range-checked; ValueError with one line otherwise.
    """
    dotted, sep, rhs = text.partition("=")
    if not sep or not rhs.strip():
        raise ValueError(f"expected GROUP.NAME=VALUE, got {text!r}")
    group, name, meta = meta_of(dotted.strip())
    values = (
        [convert(group, name, part, meta) for part in rhs.split(",")]
        if many
        else [convert(group, name, rhs, meta)]
    )
    for v in values:
        check_value(group, name, v, meta)
    return group, name, (values if many else values[0])
