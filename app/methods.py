"""How the walking methods are named and drawn everywhere: the live scene, its legend and
plots, recordings, the study's figures and report, the sweep's heatmaps.

Display data only (the controller knows a method by its name in ``controller.params.METHODS``).
The colours are chosen against the overlay colours of the scene (``app.web.overlays``: red for
references, purple for predictions, black for measurements, grey for the plan, bright red for a
straight knee or a fall), which no method uses, and against each other where it matters most:
the fixed pelvis and the pelvic MPC, compared in most lessons, are blue and orange, the pair
that stays apart for the common colour-vision deficiencies and on a washed-out projector; the
redundancy robot is green, darker than the orange and lighter than the blue. A torso is lit in
the scene, which lightens its colour: the blue is a deep one, so it does not read as cyan.
"""

from __future__ import annotations

from dataclasses import dataclass

from controller.params import METHODS


@dataclass(frozen=True)
class MethodInfo:
    """How a walking method is named and drawn."""

    name: str  # the ``method`` value
    title: str  # short, for labels and legends
    label: str  # long, as the paper names it
    color: tuple[int, int, int]  # RGB


METHOD_INFO: dict[str, MethodInfo] = {
    "fixed": MethodInfo("fixed", "fixed pelvis", "fixed pelvis (W/O rotation)", (20, 80, 190)),
    "redundancy": MethodInfo(
        "redundancy", "redundancy", "rotation by redundancy [21]", (0, 150, 80)
    ),
    "mpc": MethodInfo("mpc", "pelvic MPC", "rotation by MPC (proposed)", (235, 150, 0)),
}
assert tuple(METHOD_INFO) == METHODS  # one entry per method, in the canonical order


def method_hex(method: str) -> str:
    """``#rrggbb`` of a method's colour (matplotlib, HTML)."""
    r, g, b = METHOD_INFO[method].color
    return f"#{r:02x}{g:02x}{b:02x}"
