"""How the robots are named and drawn everywhere: the live scene, its legend and plots,
recordings, the study's figures and report, the sweep's heatmaps.

A robot is a pelvis strategy (``controller.strategy``): the paper's three methods and any a
user loaded. Their names, labels and colours come from the strategy registry; this module
gives the displays one view of it (:data:`METHOD_INFO`, :func:`method_hex`).

The built-ins' colours are chosen against the overlay colours of the scene
(``app.web.overlays``: red for references, purple for predictions, black for measurements,
grey for the plan, bright red for a straight knee or a fall), which no robot uses, and against
each other where it matters most: the fixed pelvis and the pelvic MPC, compared in most
lessons, are blue and orange, the pair that stays apart for the common colour-vision
deficiencies and on a washed-out projector; the redundancy robot is green, darker than the
orange and lighter than the blue. A torso is lit in the scene, which lightens its colour: the
blue is a deep one, so it does not read as cyan. A user's strategy without a colour of its own
takes the next of ``controller.strategy.PALETTE`` (teal, magenta, brown, ...).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from controller import strategy


@dataclass(frozen=True)
class MethodInfo:
    """How a robot (a registered strategy) is named and drawn."""

    name: str  # the ``method`` value: the strategy's name
    title: str  # short, for labels and legends
    label: str  # long, as the paper names it (a user's strategy: its label)
    color: tuple[int, int, int]  # RGB


class _Registered(Mapping[str, MethodInfo]):
    """The registry as ``name -> MethodInfo``, read at each lookup (strategies a user loads
    after this module was imported are there too)."""

    def __getitem__(self, name: str) -> MethodInfo:
        try:
            i = strategy.info(name)
        except ValueError:
            raise KeyError(name) from None
        return MethodInfo(i.name, i.label, i.paper_label, i.color)

    def __iter__(self) -> Iterator[str]:
        return iter(strategy.names())

    def __len__(self) -> int:
        return len(strategy.names())


METHOD_INFO: Mapping[str, MethodInfo] = _Registered()


def method_hex(method: str) -> str:
    """``#rrggbb`` of a robot's colour (matplotlib, HTML)."""
    r, g, b = METHOD_INFO[method].color
    return f"#{r:02x}{g:02x}{b:02x}"
