"""What a panel's parts see of the panel and of the view they live in (typing protocols).

A browser's :class:`~app.web.view.View` owns its :class:`~app.web.panel.ControlPanel`, and the
panel owns its folders and tabs (:class:`~app.web.learn_gui.LearnTab`,
:class:`~app.web.record_gui.RecordFolder`). The parts reach back to their owner only through
these protocols, so no module imports the one that builds it: the imports run one way, from
the view down to its parts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from app.live.session import SessionView
    from app.web.scene import SceneView


class ViewHost(Protocol):
    """One browser's view, as its panel uses it."""

    @property
    def session(self) -> SessionView: ...

    @property
    def scene(self) -> SceneView: ...

    @property
    def notice(self) -> str | None:
        """A line the panel shows on top (who drives the demo, the workers are full...)."""
        ...

    def alerts(self) -> list[str]: ...


class PanelHost(Protocol):
    """One view's control panel, as its folders and tabs use it."""

    @property
    def view(self) -> ViewHost: ...

    @property
    def session(self) -> SessionView: ...

    def writer(self, handle: Any) -> Any:
        """Register a control that changes the session (disabled on a read-only panel)."""
        ...

    def guarded(self) -> bool:
        """True when a change must not be applied now (the panel is reflecting the session,
        or is read-only: then the refusal is said once)."""
        ...
