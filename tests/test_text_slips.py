"""Small things a class reads: /docs lists each route once, the icon is there, the lessons say
what the buttons do, the plots say what their axes count, the page's status line names the
robots of its own scene and routes that work in the mode served."""

from __future__ import annotations

import re

import viser
from fastapi.testclient import TestClient

from app.bench.local_server import free_port
from app.live.registry import SessionRegistry
from app.web.api import create_app
from app.web.auth import Instructor
from app.web.lessons import LESSONS
from app.web.plots import PLOTS, HorizonInspector


def test_docs_list_every_operation_under_one_tag_and_the_icon_is_served(live):
    app = create_app(live)
    with TestClient(app) as client:
        paths = client.get("/openapi.json").json()["paths"]
        multi = [
            (m.upper(), p)
            for p, ops in paths.items()
            for m, op in ops.items()
            if len(op["tags"]) > 1
        ]
        assert not multi, multi  # Swagger UI lists an operation once per tag
        assert paths["/api/params/spec"]["get"]["tags"] == ["params"]
        icon = client.get("/favicon.ico")
        assert icon.status_code == 200 and icon.headers["content-type"] == "image/svg+xml"
        assert b"<svg" in icon.content
        assert 'rel="icon"' in client.get("/").text
    app.state.runs.shutdown()


def hint(page: str) -> str:
    """The page's line on what scripts can do."""
    found = re.search(r"Scripts do the same(.*?)</li>", page, re.S)
    assert found is not None
    return found.group(1)


def test_the_page_names_routes_that_work_in_its_mode(live):
    shared = create_app(live)
    with TestClient(shared) as client:
        page = client.get("/").text
        assert "PUT /api/params" in hint(page) and "/api/sessions" not in hint(page)
        assert "set-cookie" not in client.get("/").headers  # no seat in shared mode
    shared.state.runs.shutdown()
    taught = create_app(SessionRegistry.around(live), instructor=Instructor("t" * 24))
    with TestClient(taught) as client:
        student = hint(client.get("/").text)
        assert "GET /api/state" in student and "PUT /api/params" not in student
        r = client.put("/api/params", json={"walk": {"step_length": 0.25}})
        assert r.status_code == 401 and "POST /api/sessions" not in r.json()["detail"]
        assert "watch" in r.json()["detail"]
        teacher = hint(client.get(f"/?token={'t' * 24}").text)
        assert "PUT /api/params" in teacher and "Authorization: Bearer" in teacher
    taught.state.runs.shutdown()


def test_lesson_two_says_where_to_lift_off_stops_and_what_the_camera_does():
    lesson = LESSONS[1]
    assert "with both feet down" in lesson.watch and "Step: to landing" in lesson.watch
    assert "first instant" in lesson.watch and "SSP" in lesson.watch


def test_the_plots_label_their_time_axes_and_keep_titles_short():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        inspector = HorizonInspector(server.gui)
        for handle in (inspector.com, inspector.zmp, inspector.theta):
            assert handle.axes[0]["label"] == "t from now [s]"
    finally:
        server.stop()
    # a title wider than the panel runs under the plot's expand button
    assert all(len(title) <= 48 for _col, title, _span in PLOTS), [t for _c, t, _s in PLOTS]
