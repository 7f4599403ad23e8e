"""``GET /api/strategies``: the pelvis strategies this server knows, the paper's three and the
ones it loaded at start (``serve --strategy FILE.py``). Code is never loaded over HTTP: a
strategy is named here, and ``POST /api/runs`` or the live controls run it by that name."""

from __future__ import annotations

import os
from typing import Any

from fastapi import APIRouter

from app.web.api.edges import router
from controller import strategy


def describe(name: str) -> dict[str, Any]:
    """One strategy as the API shows it (the file by its name only: no server paths)."""
    i = strategy.info(name)
    r, g, b = i.color
    return {
        "name": i.name,
        "label": i.label,
        "description": i.description,
        "color": f"#{r:02x}{g:02x}{b:02x}",
        "builtin": i.builtin,
        "file": os.path.basename(i.file) if i.file else None,
        "class": i.cls.__name__,
    }


def strategies_router() -> APIRouter:
    r = router("/api", "strategies")

    @r.get("/strategies")
    def get_strategies() -> dict[str, Any]:
        """Every pelvis strategy a robot can run here: ``name`` (the robot's key: the
        ``methods`` of ``PUT /api/params``, ``method`` of ``POST /api/runs``), ``label``,
        ``description``, ``color``, ``builtin`` and, for a user's, its ``file``."""
        return {"strategies": [describe(n) for n in strategy.names()]}

    return r
