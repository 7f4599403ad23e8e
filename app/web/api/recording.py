"""``GET /api/recording``: the last seconds of a live session as a file that plays back
without the server (:mod:`app.web.recording`).

Made from what the session already keeps in the web process (its kept frames and plot rows):
the live loop is never paused or stepped for it. Bad input (a length that is not positive or
longer than what is kept, an unknown format) gets a 422 with one readable line.
"""

from __future__ import annotations

from collections.abc import Callable

from fastapi import APIRouter, Depends, Query, Response

from app.live.session import KEEP_S, SessionView
from app.web import recording
from app.web.api.edges import conflict, router, unprocessable

FILE_NAMES = {"zip": "{name}.zip", "html": "{name}.html", "csv": "{name}.csv", "png": "{name}.png"}


def recording_router(prefix: str, resolve: Callable[..., tuple[str, SessionView]]) -> APIRouter:
    """The recording route under ``prefix`` (``/api`` or ``/api/sessions/{sid}``)."""
    r = router(prefix, None)  # each route is tagged (/docs)
    Session = Depends(resolve)

    @r.get(
        "/recording",
        response_class=Response,
        tags=["recording"],
        responses={
            200: {
                "description": "the recording, as an attachment",
                "content": {media: {} for media in recording.MEDIA_TYPES.values()},
            },
            409: {"description": "another recording is being made: try again"},
            422: {"description": "seconds not in (0, kept], or an unknown format"},
        },
    )
    def get_recording(
        seconds: float = Query(
            10.0,
            description=f"how many seconds up to the shown instant (at most what the session "
            f"keeps: {KEEP_S:g} s, less after a restart; GET /api/state reports `kept`)",
        ),
        format: str = Query(
            "zip",
            description="zip: index.html, scene.html, timeseries.csv, plots.png and README.txt; "
            "html: the 3-D scene alone (one self-contained page); csv: the plot rows; "
            "png: the plots",
        ),
        s: tuple[str, SessionView] = Session,
    ) -> Response:
        """The last ``seconds`` of the session (up to the sought instant while paused) as a
        recording that plays back without the server: unzip and open ``index.html`` in a
        browser (the scene loops; its bar pauses and scrubs). viser recordings drop GUI plots,
        so the plots of the same window come as a PNG and their numbers as CSV."""
        if format not in recording.FORMATS:
            raise unprocessable(
                f"format must be one of {', '.join(recording.FORMATS)}, got {format!r}"
            )
        try:
            rec = recording.from_session(s[1], seconds)
        except ValueError as exc:
            raise unprocessable(str(exc)) from None
        try:
            data = recording.render(rec, format)
        except recording.RecorderBusy as exc:
            raise conflict(str(exc)) from None
        filename = FILE_NAMES[format].format(name=rec.name)
        return Response(
            data,
            media_type=recording.MEDIA_TYPES[format],
            headers={"Content-Disposition": f'attachment; filename="{filename}"'},
        )

    return r
