"""How the robots are named and drawn everywhere: the live scene, its legend and plots,
recordings, the study's figures and report, the sweep's heatmaps.

A robot is a pelvis strategy (``controller.strategy``): the paper's three methods and any a
user loaded. Their names, labels and colours come from the strategy registry; this module
gives the displays one view of it (:data:`METHOD_INFO`, :func:`method_hex`).

Colours for every student (docs/TEACHING.md, "Colours"): the fixed pelvis wears Okabe-Ito
blue, the pelvic MPC an orange (Okabe-Ito's, a shade deeper), the redundancy robot a dark
plum, and a user's strategy without a colour of its own black, then yellow
(``controller.strategy.PALETTE``). Measured in CAM02-UCS, every pair stays apart
(``tests/test_colours.py`` states the distance) for normal vision, deuteranopia, protanopia,
tritanopia and in grayscale: from dark to light the five are black, plum, blue, orange and
yellow, so lightness alone tells them apart when hue fails.

Colour is never the only cue: each robot also has a :attr:`MethodInfo.marker` (a symbol on its
label in the scene and before its name in every legend) and a :attr:`MethodInfo.dash` (its line
style in the live plots; ``mpl_style`` in matplotlib's figures), given by its place in the
registry (the paper's three first).
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
    marker: str = "●"  # a symbol beside its name: a cue that is not colour
    dash: tuple[float, ...] = ()  # its plot lines' dash pattern [px on, off, ...]; () solid
    mpl_marker: str = "o"  # matplotlib's marker of the same shape

    @property
    def tag(self) -> str:
        """Marker and title, as legends and labels show the robot: "■ fixed pelvis"."""
        return f"{self.marker} {self.title}"

    def mpl_style(self) -> dict[str, object]:
        """matplotlib keywords drawing this robot's lines: colour, dashes and marker."""
        return {
            "color": "#{:02x}{:02x}{:02x}".format(*self.color),
            "linestyle": (0, self.dash) if self.dash else "-",
            "marker": self.mpl_marker,
        }


# Cues by place in the registry (the paper's three first, then a user's strategies in the
# order they were loaded): (marker, dash pattern, matplotlib marker). The MPC, the paper's
# method, draws solid lines; the others dashed, dotted, dash-dotted...
CUES: tuple[tuple[str, tuple[float, ...], str], ...] = (
    ("■", (10.0, 5.0), "s"),  # fixed
    ("▲", (2.0, 4.0), "^"),  # redundancy
    ("●", (), "o"),  # mpc
    ("◆", (12.0, 4.0, 2.0, 4.0), "D"),
    ("★", (18.0, 6.0), "*"),
    ("✚", (6.0, 3.0, 6.0, 9.0), "P"),
)


class _Registered(Mapping[str, MethodInfo]):
    """The registry as ``name -> MethodInfo``, read at each lookup (strategies a user loads
    after this module was imported are there too)."""

    def __getitem__(self, name: str) -> MethodInfo:
        try:
            i = strategy.info(name)
        except ValueError:
            raise KeyError(name) from None
        names = strategy.names()
        marker, dash, mpl = CUES[names.index(name) % len(CUES)]
        return MethodInfo(i.name, i.label, i.paper_label, i.color, marker, dash, mpl)

    def __iter__(self) -> Iterator[str]:
        return iter(strategy.names())

    def __len__(self) -> int:
        return len(strategy.names())


METHOD_INFO: Mapping[str, MethodInfo] = _Registered()


def method_hex(method: str) -> str:
    """``#rrggbb`` of a robot's colour (matplotlib, HTML)."""
    r, g, b = METHOD_INFO[method].color
    return f"#{r:02x}{g:02x}{b:02x}"
