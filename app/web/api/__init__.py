"""The HTTP API (FastAPI): thin routes that write intent and read published frames.

Routes (docs/REFERENCE.md, "HTTP API"): ``GET /api/health``; ``GET``/``PUT /api/params``;
``POST /api/sim/pause|resume|reset|step|seek|push`` (and ``PUT /api/sim/speed``);
``GET /api/state``; ``GET /api/horizon``; ``POST /api/runs`` and ``GET /api/runs/{id}``;
``GET /api/recording`` (the last seconds as a file that plays back without the server);
``GET /api/sessions`` (and ``/api/sessions/{sid}/...`` for each session-scoped route);
``GET /`` (the page framing the viser scene), ``/report``, ``/docs``.

Modules: ``models`` (request and response models, generated from controller/params.py),
``edges`` (JSON-only bodies, 422 and 415 answers), ``live`` (session-scoped routes),
``recording`` (recordings), ``sessions``, ``runs`` (headless runs), ``pages``, ``app``
(:func:`create_app`).
"""

from app.web.api.app import create_app
from app.web.api.headless import RunManager

__all__ = ["RunManager", "create_app"]
