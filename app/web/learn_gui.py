"""The Learn tab of one view's panel: the per-layer explanations and the kinematic analysis
(Fig. 1-2, eq. 1-5). The text lives in :mod:`app.web.lessons`; this module builds the controls.

Like the rest of the panel, every control only writes intent into the view's session.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from app.web.lessons import EXPLAIN, analysis_svg

if TYPE_CHECKING:
    from app.web.panel import ControlPanel


class LearnTab:
    """The Learn tab's controls (built inside the tab by :class:`~app.web.panel.ControlPanel`)."""

    def __init__(self, gui: Any, panel: ControlPanel):
        self.gui = gui
        self.panel = panel
        with gui.add_folder("Explain"):
            self.lesson_choice = gui.add_dropdown(
                "Layer", tuple(EXPLAIN), initial_value=next(iter(EXPLAIN))
            )
            self.lesson = gui.add_markdown(EXPLAIN[self.lesson_choice.value])
            self.lesson_choice.on_update(
                lambda _e: setattr(self.lesson, "content", EXPLAIN[self.lesson_choice.value])
            )
        with gui.add_folder("Kinematic analysis (Fig. 1-2, eq. 1-5)"):
            self.theta_slider = gui.add_slider("Pelvic angle [deg]", 0.0, 45.0, 1.0, 0.0)
            self.analysis_view = gui.add_html(analysis_svg(0.0))
            self.theta_slider.on_update(
                lambda _e: setattr(
                    self.analysis_view, "content", analysis_svg(self.theta_slider.value)
                )
            )

    def update(self, frame: Any, now: float) -> None:
        """Refresh live numbers from the published ``frame`` (display thread)."""
