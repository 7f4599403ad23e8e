"""Keyword arguments -> parameters, with the command line's names and checks.

Every option of ``pelvic-walk simulate`` is a keyword of :func:`pelvic_walk.simulate` (dashes
become underscores: ``--step-time`` -> ``step_time``, ``--pelvis-k-pel`` -> ``pelvis_k_pel``),
and ``**{"pelvis.k_pel": 0.3}`` reaches a field by its dotted name as ``--set`` does: a
strategy's own parameter too (``**{"gain.k": 4}``), and a paper parameter by the name under the
strategy that owns it (``**{"mpc.alpha": 2}`` is ``pelvis.alpha``). Values
are checked by the same function as the command line's (``controller.params.check_value``),
so a bad one raises ValueError with the line the CLI prints after ``error:``.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Mapping
from typing import Any

from controller import strategy
from controller.params import ControllerParams, check_value
from pelvic_walk.core.params import fields, meta_of, option_name

BACKENDS = ("daqp", "osqp")


def keywords() -> dict[str, tuple[str, str, dict[str, Any]]]:
    """Keyword -> (group, field, metadata) of every parameter: the CLI option's name with
    underscores (``step_length``, ``steps``, ``horizon``, ``arms``, ``pelvis_k_pel``)."""
    return {
        option_name(group, name, meta).replace("-", "_"): (group, name, meta)
        for group, name, meta in fields()
    }


def _field_of(key: str) -> tuple[str, str, dict[str, Any]]:
    table = keywords()
    if key in table:
        return table[key]
    if "." in key:
        try:
            return meta_of(key)  # GROUP.NAME, a strategy's NAME.FIELD, an alias (mpc.alpha)
        except ValueError:
            pass
    raise ValueError(
        f"unknown parameter {key!r} (one of: {', '.join(table)}; or GROUP.NAME such as "
        "'pelvis.k_pel', or a strategy's own NAME.FIELD)"
    )


def _plain(value: Any) -> Any:
    """numpy scalars -> Python numbers (a value read from an array or a DataFrame)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if hasattr(value, "item") and getattr(value, "shape", None) == ():
        return value.item()
    return value


def checked(key: str, value: Any) -> tuple[str, str, Any]:
    """(group, field, value) of one keyword, converted and range-checked (ValueError)."""
    group, name, meta = _field_of(key)
    value = _plain(value)
    if (
        meta["type"] == "int"
        and isinstance(value, float)
        and math.isfinite(value)
        and value.is_integer()
    ):
        value = int(value)
    if meta["type"] == "float" and isinstance(value, numbers.Integral):
        value = float(value)
    check_value(group, name, value, meta)
    return group, name, value


def groups_of(params: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """``{"step_length": 0.3, "pelvis.k_pel": 0.2}`` -> ``{"walk": {...}, "pelvis": {...}}``
    (None values are left out: the default stays); a field given twice is a ValueError."""
    out: dict[str, dict[str, Any]] = {}
    for key, value in params.items():
        if value is None:
            continue
        group, name, value = checked(key, value)
        if name in out.setdefault(group, {}):
            raise ValueError(f"{group}.{name} is given twice")
        out[group][name] = value
    return out


def controller_params(method: str, params: Mapping[str, Any]) -> ControllerParams:
    """The parameters of a run of ``method`` (a registered strategy) with ``params`` set."""
    return ControllerParams().replace(method=method, **groups_of(params))


def method_name(method: Any) -> str:
    """A registered strategy's name, else ValueError with the choices."""
    if not isinstance(method, str) or not strategy.is_registered(method):
        raise ValueError(
            f"unknown method {method!r} (choose from {', '.join(strategy.names())}; or give "
            "strategy= a FILE.py[:Class] or a PelvisStrategy subclass)"
        )
    return method


def register_strategy(source: Any) -> str:
    """The method name of ``strategy=``: a file ``"FILE.py[:Class]"`` (loaded as ``--strategy``
    loads it; one strategy, or name the class) or a :class:`PelvisStrategy` subclass defined in
    this process (registered under its ``name``; defining it again replaces it)."""
    if isinstance(source, type):
        if not issubclass(source, strategy.PelvisStrategy):
            raise ValueError(f"strategy={source.__name__}: not a subclass of PelvisStrategy")
        return strategy.register(source, builtin=False).name
    if isinstance(source, strategy.PelvisStrategy):
        raise ValueError(
            f"strategy= takes the class, not an instance: strategy={type(source).__name__} "
            "(each robot makes its own)"
        )
    if not isinstance(source, (str, os.PathLike)):
        raise ValueError(
            f"strategy= takes a file 'FILE.py[:Class]' or a PelvisStrategy subclass, got "
            f"{type(source).__name__}"
        )
    text = os.fspath(source)
    loaded = strategy.load_file(text)  # StrategyLoadError (a ValueError): one line
    if len(loaded) > 1:
        file, _ = strategy.parse_source(text)
        raise ValueError(
            f"strategy={file} defines {len(loaded)} strategies ({', '.join(loaded)}): name "
            f"one class, as '{file}:ClassName'"
        )
    return loaded[0]


def method_of(method: Any, source: Any) -> str:
    """The strategy a call runs: ``method=`` a registered name, or ``strategy=`` (not both;
    neither: the paper's MPC)."""
    if method is not None and source is not None:
        raise ValueError("give method= or strategy=, not both")
    if source is not None:
        return register_strategy(source)
    if isinstance(method, type) or isinstance(method, strategy.PelvisStrategy):
        return register_strategy(method)  # method=MyClass: meant as strategy=MyClass
    return method_name(strategy.MPC if method is None else method)


def in_process_only(method: str) -> bool:
    """A strategy defined in this process (a notebook's class): no other process can load it."""
    i = strategy.info(method)
    return not i.builtin and i.source is None


def check_seed(seed: Any) -> int | None:
    seed = _plain(seed)
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise ValueError(f"seed must be a whole number or None, got {seed!r}")
    return int(seed)
