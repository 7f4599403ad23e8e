"""``/`` (the page framing the viser scene), ``/report``, ``/static``, ``/docs``, ``/redoc``.

The page, the reference report and the docs' scripts are read from installed packages
(``app.static``, ``app.reference_report``, ``fastapi_offline``), never from the checkout, so
a wheel installed anywhere serves them, and ``/docs`` needs no internet.

With an instructor, ``/?token=T`` (the right token) is exchanged once for the instructor
cookie (HttpOnly) and answered with a redirect to ``/``: the token is in no frame's address, no
page and no later request; the cookie goes with the scene's websocket, so the display knows
that browser drives the shared demo (:mod:`app.web.auth`); every other browser reads that the
instructor drives it. A wrong token is redirected too (to ``/?token_wrong=1``, which says so).

With private sessions, ``/`` gives the browser its seat cookie (HttpOnly, once): the scene's
websocket carries it to the display, which opens (or finds again) the browser's own session,
and the page's status line reads that session through ``/api/sessions/mine/state``.
"""

from __future__ import annotations

import html
import os
from collections.abc import Callable
from urllib.parse import urlencode

from fastapi import APIRouter, FastAPI, Request
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles

from app.live.registry import usable_credential
from app.live.session import FALL_HOLD_S
from app.web.api.edges import file_under, router
from app.web.auth import INSTRUCTOR_COOKIE, SEAT_COOKIE, TOKEN_PARAM, Instructor, new_credential
from app.web.overlays import COLOUR_NAMES, DANGER, MEASURED, PLAN, PREDICTED, REFERENCE
from app.web.report_page import render_report_page
from controller import strategy
from pelvic_walk.core.methods import METHOD_INFO
from pelvic_walk.core.report_dir import ReportChoice, package_dir

DOCS_ASSETS = "/docs-assets"  # swagger-ui / redoc files of the fastapi-offline package
WRONG_PARAM = "token_wrong"  # /?token_wrong=1: the page says the token given was wrong


COLOURS = {  # {{COLOR_<name>}} in the page: the scene's colours, from their one definition
    **{m: METHOD_INFO[m].color for m in strategy.BUILTINS},
    "predicted": PREDICTED,
    "reference": REFERENCE,
    "measured": MEASURED,
    "plan": PLAN,
    "danger": DANGER,
}
# {{NAME_<meaning>}}: the words for the overlay colours; {{MARK_<method>}}: a robot's marker
WORDS = {
    **{f"NAME_{k}": COLOUR_NAMES[v] for k, v in COLOURS.items() if v in COLOUR_NAMES},
    **{f"MARK_{m}": METHOD_INFO[m].marker for m in strategy.BUILTINS},
}


def own_robots_html() -> str:
    """The page's list entries of the strategies this server loaded (``serve --strategy``)."""
    items = []
    for name in strategy.names():
        i = strategy.info(name)
        if i.builtin:
            continue
        file = os.path.basename(i.file or "")
        items.append(
            '<li><span class="swatch" style="background:rgb({},{},{})"></span>'.format(*i.color)
            + f"<b>{html.escape(METHOD_INFO[name].marker)} {html.escape(i.label)}</b> (a "
            "strategy of your own, "
            f"<code>{html.escape(file)}</code>): {html.escape(i.description or name)}</li>"
        )
    return "\n      ".join(items)


ROLES = {  # the line the page shows under its title, by role
    "": "",
    "instructor": "<p class='role'><b>Instructor</b>: you drive the shared demo; every "
    "student watches what you do.</p>",
    "student": "<p class='role'>The <b>instructor</b> drives the shared demo: watch it here "
    "(your controls for it are off).</p>",
    "student_private": "<p class='role'>You get <b>robots of your own</b> while the server has "
    "room (the panel on the right says so); else you watch the shared demo, which the "
    "<b>instructor</b> drives.</p>",
    "wrong": "<p class='role'><b>That instructor token is wrong</b>: you watch as a student.</p>",
}
# How scripts do the same, by mode (the routes named work in that mode; a student's changes of
# an instructor's demo are refused, so they are not suggested)
API_HINTS = {
    "shared": '<code>PUT /api/params</code> with <code>{"walk": {"step_length": 0.3}}</code>',
    "instructor": '<code>PUT /api/params</code> with <code>{"walk": {"step_length": '
    "0.3}}</code> and the header <code>Authorization: Bearer &lt;your token&gt;</code>",
    "watch": "<code>GET /api/state</code> (the instructor changes the demo)",
    "private": "<code>POST /api/sessions</code> opens a session of a script's own (its answer's "
    "<code>token</code> goes in <code>Authorization: Bearer</code>), then <code>PUT "
    "/api/sessions/mine/params</code>; in this browser, <code>/api/sessions/mine/...</code> is "
    "this page's session",
}


def pages_router(
    app: FastAPI,
    viser_port: int,
    report: Callable[[], ReportChoice],
    instructor: Instructor | None = None,
    private: bool = False,
) -> APIRouter:
    """The pages; ``private``: browsers get sessions of their own (the page says so)."""
    static_dir = package_dir("app.static")
    instructor = instructor or Instructor(None)
    r = router()

    @r.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index(request: Request) -> Response:  # noqa: C901 - one branch per role
        if TOKEN_PARAM in request.query_params:
            return exchange(request)
        host = request.url.hostname or "127.0.0.1"
        if ":" in host:  # IPv6 literal
            host = f"[{host}]"
        viser_url = f"http://{host}:{viser_port}/"
        scene_url, role = viser_url, ""  # the frame's address never carries a credential
        if instructor.enabled:
            if instructor.is_cookie(request.cookies.get(INSTRUCTOR_COOKIE)):
                role = "instructor"
            elif request.query_params.get(WRONG_PARAM):
                role = "wrong"
            else:
                role = "student_private" if private else "student"
        page = (static_dir / "index.html").read_text(encoding="utf-8")
        page = page.replace("{{SCENE_URL}}", html.escape(scene_url, quote=True))
        # the link to open the scene alone never carries the token (a projected page's links
        # are read by the room): it opens the scene as a viewer
        page = page.replace("{{SCENE_LINK}}", html.escape(viser_url, quote=True))
        page = page.replace("{{VISER_URL}}", viser_url)
        page = page.replace("{{ROLE}}", ROLES[role])
        page = page.replace("{{OWN_ROBOTS}}", own_robots_html())
        page = page.replace("{{FALL_HOLD_S}}", f"{FALL_HOLD_S:g}")
        hint = (
            "instructor"
            if role == "instructor"
            else "private"
            if private
            else "watch"
            if role in ("student", "wrong")
            else "shared"
        )
        page = page.replace("{{API_HINT}}", API_HINTS[hint])
        page = page.replace("{{PRIVATE}}", "true" if private else "false")
        shared_label = (
            "Shared demo (no session of your own yet)"
            if private and role != "instructor"
            else "Shared demo"
            if private
            else "Shared session"
        )
        page = page.replace("{{SHARED_LABEL}}", shared_label)
        for name, rgb in COLOURS.items():
            page = page.replace(f"{{{{COLOR_{name}}}}}", "rgb({},{},{})".format(*rgb))
        for key, words in WORDS.items():
            page = page.replace(f"{{{{{key}}}}}", html.escape(words))
        response = HTMLResponse(page, headers={"Cache-Control": "no-store"})
        if private and usable_credential(request.cookies.get(SEAT_COOKIE)) is None:
            # the browser's credential for its own session: HttpOnly (no script reads it),
            # sent to this host only, the scene's port included (cookies know no ports)
            response.set_cookie(
                SEAT_COOKIE, new_credential(), httponly=True, samesite="strict", path="/"
            )
        return response

    def exchange(request: Request) -> Response:
        """``/?token=T``: the right token for the instructor cookie, then ``/`` (303); a wrong
        one (or any, without an instructor) to ``/`` with a line saying so. The token leaves
        the address bar and the history at once, and is never answered back."""
        token = request.query_params.get(TOKEN_PARAM)
        keep = [(k, v) for k, v in request.query_params.multi_items() if k != TOKEN_PARAM]
        right = instructor.is_token(token)
        if not right and instructor.enabled:
            keep.append((WRONG_PARAM, "1"))
        response = RedirectResponse(
            "/" + (f"?{urlencode(keep)}" if keep else ""),
            status_code=303,
            headers={"Cache-Control": "no-store", "Referrer-Policy": "no-referrer"},
        )
        if right:
            # HttpOnly: no script reads it; SameSite=Strict: no other site's page sends it;
            # no Max-Age: it ends with the browser's session
            response.set_cookie(
                INSTRUCTOR_COOKIE,
                instructor.issue_cookie(),
                httponly=True,
                samesite="strict",
                path="/",
            )
        return response

    @r.get("/favicon.ico", include_in_schema=False)
    def favicon() -> FileResponse:
        return FileResponse(static_dir / "favicon.svg", media_type="image/svg+xml")

    @r.get("/report", response_class=HTMLResponse, include_in_schema=False)
    def report_page() -> HTMLResponse:
        choice = report()
        return HTMLResponse(render_report_page(choice.path, choice.about))

    @r.get("/report/{path:path}", include_in_schema=False)
    def report_file(path: str) -> FileResponse:
        return FileResponse(file_under(report().path, path))

    @r.get("/static/{path:path}", include_in_schema=False)
    def static_file(path: str) -> FileResponse:
        return FileResponse(file_under(static_dir, path))

    @r.get("/docs", include_in_schema=False)
    def docs() -> HTMLResponse:
        return get_swagger_ui_html(
            openapi_url=app.openapi_url or "/openapi.json",
            title=f"{app.title} - API",
            swagger_js_url=f"{DOCS_ASSETS}/swagger-ui-bundle.js",
            swagger_css_url=f"{DOCS_ASSETS}/swagger-ui.css",
            swagger_favicon_url=f"{DOCS_ASSETS}/favicon.png",
            oauth2_redirect_url=None,
        )

    @r.get("/redoc", include_in_schema=False)
    def redoc() -> HTMLResponse:
        return get_redoc_html(
            openapi_url=app.openapi_url or "/openapi.json",
            title=f"{app.title} - API",
            redoc_js_url=f"{DOCS_ASSETS}/redoc.standalone.js",
            redoc_favicon_url=f"{DOCS_ASSETS}/favicon.png",
            with_google_fonts=False,
        )

    return r


def mount_docs_assets(app: FastAPI) -> None:
    app.mount(
        DOCS_ASSETS, StaticFiles(packages=[("fastapi_offline", "static")]), name="docs-assets"
    )
