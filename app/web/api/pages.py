"""``/`` (the page framing the viser scene), ``/report``, ``/static``, ``/docs``, ``/redoc``.

The page, the reference report and the docs' scripts are read from installed packages
(``app.static``, ``app.reference_report``, ``fastapi_offline``), never from the checkout, so
a wheel installed anywhere serves them, and ``/docs`` needs no internet.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from fastapi import APIRouter, FastAPI, Request
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse
from fastapi.staticfiles import StaticFiles

from app.report_dir import package_dir
from app.web.api.edges import file_under, router
from app.web.report_page import render_report_page

DOCS_ASSETS = "/docs-assets"  # swagger-ui / redoc files of the fastapi-offline package


def pages_router(app: FastAPI, viser_port: int, report_dir: Callable[[], Path]) -> APIRouter:
    static_dir = package_dir("app.static")
    r = router()

    @r.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index(request: Request) -> HTMLResponse:
        host = request.url.hostname or "127.0.0.1"
        if ":" in host:  # IPv6 literal
            host = f"[{host}]"
        page = (static_dir / "index.html").read_text(encoding="utf-8")
        page = page.replace("{{VISER_URL}}", f"http://{host}:{viser_port}/")
        return HTMLResponse(page)

    @r.get("/report", response_class=HTMLResponse, include_in_schema=False)
    def report() -> HTMLResponse:
        return HTMLResponse(render_report_page(report_dir()))

    @r.get("/report/{path:path}", include_in_schema=False)
    def report_file(path: str) -> FileResponse:
        return FileResponse(file_under(report_dir(), path))

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
