"""How the page names and draws each robot shown: its label, colour, marker and line style,
and the settings by which it differs from the others.

A robot is a strategy with settings of its own and a label (``pelvic_walk.core.robots``); its
key in a frame is ``RobotFrame.method`` (the label), its strategy ``RobotFrame.strategy``. The
colour, marker and dash pattern come from the strategy (``pelvic_walk.core.methods``); a second
(third...) robot of the same strategy is told apart by a different shade of that colour AND a
hollow marker (with its number from the third on) and another dash pattern, and always by its
label: colour is never the only cue. A robot named after its strategy keeps the strategy's
title ("pelvic MPC"), so the paper's three read as before.

The settings that differ (:func:`differing_text`) are read from the parameters each robot walks
with (``RobotFrame.params``): every parameter whose value is not the same for all robots shown,
as a short ``H=0.8 s``; a robot without overrides shows the shared value it walks with, so two
robots side by side each say what they run.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from controller.params import ControllerParams
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.params import fields, meta_of

HOLLOW = {"■": "□", "▲": "△", "●": "○", "◆": "◇", "★": "☆", "✚": "✜"}
SUPERSCRIPT = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")
# dash patterns of the second, third... robot of one strategy: unlike every strategy's own
OTHER_DASHES: tuple[tuple[float, ...], ...] = ((6.0, 2.0), (1.0, 2.0), (14.0, 3.0, 1.0, 3.0))
# short names of parameters a comparison names often (the others: their field's name), as
# the sliders' labels spell them (beta_pel, not β_pel: one notation on the page)
SHORT = {
    "com.horizon": "H",
    "pelvis.k_pel": "k_pel",
    "pelvis.alpha": "alpha_pel",
    "pelvis.beta": "beta_pel",
    "walk.step_length": "step",
    "walk.step_time": "T_step",
}


@dataclass(frozen=True)
class RobotLook:
    """How one robot shown is named and drawn."""

    key: str  # its key in the session (frames, plots, pushes): its label
    strategy: str
    title: str  # its label as shown: the strategy's title when named after it
    color: tuple[int, int, int]
    marker: str
    dash: tuple[float, ...]
    # the settings that differ from the other robots' ("H=0.8 s"), but for those the label
    # says already (its tag: "k_pel 0.45", not "k_pel 0.45 · k_pel=0.45")
    settings: str = ""
    differs: str = ""  # all the settings that differ (tables)

    @property
    def tag(self) -> str:
        """Marker and title: "○ short horizon"."""
        return f"{self.marker} {self.title}"

    @property
    def full(self) -> str:
        """Marker, title and the settings that differ: "○ short horizon · H=0.8 s"."""
        return f"{self.tag} · {self.settings}" if self.settings else self.tag


def shade(color: tuple[int, int, int], n: int) -> tuple[int, int, int]:
    """The ``n``-th shade (n >= 1) of a strategy's colour: lighter for a dark colour, darker
    for a light one, further with each robot."""
    lum = (0.2126 * color[0] + 0.7152 * color[1] + 0.0722 * color[2]) / 255
    target = 255 if lum < 0.45 else 0
    f = min(0.4 + 0.3 * (n - 1), 0.85) if target else min(0.35 + 0.25 * (n - 1), 0.75)
    return tuple(round(c + (target - c) * f) for c in color)  # type: ignore[return-value]


def looks(robots: Iterable[Any]) -> dict[str, RobotLook]:
    """Key -> :class:`RobotLook` of the robots shown, in their order: frames' robots
    (``.method``, ``.strategy``, ``.params``), ``(key, strategy)`` pairs or strategies' names."""
    items = []
    for r in robots:
        if isinstance(r, str):  # a strategy's name: its robot named after it
            items.append((r, r, None))
        elif isinstance(r, tuple):
            items.append((r[0], r[1], None))
        else:
            items.append((r.method, r.strategy, r.params))
    return _looks(tuple(items))


@functools.lru_cache(maxsize=64)
def _looks(items: tuple[tuple[str, str, ControllerParams | None], ...]) -> dict[str, RobotLook]:
    params = [p for _k, _s, p in items if p is not None]
    keys = [k for k, _s, _p in items]
    complete = len(params) == len(items)
    texts = differing_texts(params, keys) if complete else {}
    every = differing_texts(params) if complete else {}
    out: dict[str, RobotLook] = {}
    seen: dict[str, int] = {}
    for i, (key, name, _p) in enumerate(items):
        n = seen.get(name, 0)
        seen[name] = n + 1
        try:
            info = METHOD_INFO[name]
            color, marker, dash, title = info.color, info.marker, info.dash, info.title
        except KeyError:  # a strategy no longer registered (a recording's): grey
            color, marker, dash, title = (90, 90, 90), "●", (), name
        if key != name:
            title = key
        if n:
            color = shade(color, n)
            marker = HOLLOW.get(marker, marker) + (
                str(n + 1).translate(SUPERSCRIPT) if n > 1 else ""
            )
            dash = OTHER_DASHES[(n - 1) % len(OTHER_DASHES)]
        out[key] = RobotLook(
            key, name, title, color, marker, dash, texts.get(i, ""), every.get(i, "")
        )
    return out


def value_text(dotted: str, value: Any) -> str:
    """``H=0.8 s``: a parameter's short name, its value and unit."""
    name, shown = _parts(dotted, value)
    unit = ""
    try:
        unit = meta_of(dotted)[2].get("unit") or ""
    except ValueError:
        pass
    return f"{name}={shown}" + (f" {unit}" if unit else "")


def _parts(dotted: str, value: Any) -> tuple[str, str]:
    name = SHORT.get(dotted, dotted.partition(".")[2])
    if isinstance(value, bool):
        return name, "on" if value else "off"
    return name, number_text(value) if isinstance(value, float) else str(value)


def number_text(value: float) -> str:
    """A value as the lessons write it: ``0.01``, ``1e-6`` (not ``1e-06``)."""
    return re.sub(r"e([+-])0*(\d)", lambda m: f"e{m.group(1).strip('+')}{m.group(2)}", f"{value:g}")


def said_by(label: str, dotted: str, value: Any) -> bool:
    """Whether a robot's label already says this setting ("k_pel 0.45" says k_pel=0.45)."""
    name, shown = _parts(dotted, value)
    return name in label and shown in label


def differing(params: Sequence[ControllerParams]) -> list[list[tuple[str, Any]]]:
    """Per robot: ``(dotted name, value)`` of every parameter not the same for all."""
    if len(params) < 2:
        return [[] for _ in params]
    out: list[list[tuple[str, Any]]] = [[] for _ in params]
    for group, name, _meta in fields(own=True):
        dotted = f"{group}.{name}"
        values = [p.value(dotted) for p in params]
        if any(v != values[0] for v in values[1:]):
            for i, v in enumerate(values):
                out[i].append((dotted, v))
    return out


def differing_texts(
    params: Sequence[ControllerParams], labels: Sequence[str] | None = None
) -> dict[int, str]:
    """Per robot's index: its differing settings as text ("H=0.8 s, k_pel=0.45"), but for
    those its label already says (``labels``)."""
    out = {}
    for i, items in enumerate(differing(params)):
        label = labels[i] if labels is not None else ""
        text = ", ".join(value_text(d, v) for d, v in items if not said_by(label, d, v))
        if text:
            out[i] = text
    return out
