"""What every route shares at the edge: JSON-only bodies, readable 422s, JSON-safe values.

Bad input -- NaN or infinity (as numbers or strings), out of range, wrong type, unknown fields
or methods -- gets a 422 whose ``detail`` is one readable line (the full list is under
``errors``); the live simulation never sees it. A body that is not JSON gets a 415 (every
route that takes a body: :class:`JsonBodyRoute`), bytes that do not parse as JSON a 422.
"""

from __future__ import annotations

import email.message
import json
import math
from collections.abc import Callable, Coroutine
from enum import Enum
from pathlib import Path
from typing import Any

from fastapi import APIRouter, HTTPException, Request, Response
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from fastapi.routing import APIRoute


def finite(x: Any) -> Any:
    """JSON-safe: non-finite floats -> None, numpy scalars -> Python numbers, recursively."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite(v) for v in x]
    if isinstance(x, bytes):
        return x.decode("utf-8", "replace")
    if hasattr(x, "tolist") and not isinstance(x, str):  # numpy array or scalar
        return finite(x.tolist())
    return x


def unprocessable(message: str) -> HTTPException:
    return HTTPException(status_code=422, detail=message)


def conflict(message: str) -> HTTPException:
    """The request is fine but the session's state forbids it now (e.g. seek while running)."""
    return HTTPException(status_code=409, detail=message)


def _error_line(err: dict[str, Any]) -> str:
    loc = ".".join(str(p) for p in err.get("loc", ()) if p != "body")
    msg = err.get("msg", "invalid")
    given = err.get("input")
    tail = f" (got {given!r})" if given is not None and not isinstance(given, dict) else ""
    return f"{loc}: {msg}{tail}" if loc else f"{msg}{tail}"


async def validation_handler(_request: Request, exc: RequestValidationError) -> JSONResponse:
    """422 with one readable line in ``detail`` and the full list under ``errors``."""
    errors = exc.errors()
    detail = "; ".join(_error_line(e) for e in errors[:3]) or "invalid request"
    safe = [{k: finite(v) if k != "ctx" else str(v) for k, v in e.items()} for e in errors]
    safe = json.loads(json.dumps(safe, default=str))  # anything else pydantic put there
    return JSONResponse(status_code=422, content={"detail": detail, "errors": safe})


def _is_json(content_type: str | None) -> bool:
    """``application/json`` or ``application/*+json`` (parameters such as charset allowed)."""
    if not content_type:
        return False
    message = email.message.Message()
    message["content-type"] = content_type
    subtype = message.get_content_subtype()
    return message.get_content_maintype() == "application" and (
        subtype == "json" or subtype.endswith("+json")
    )


def _invalid_json(reason: str) -> RequestValidationError:
    return RequestValidationError(
        [
            {
                "type": "json_invalid",
                "loc": ("body",),
                "msg": f"body is not valid JSON: {reason}",
                "input": None,
            }
        ]
    )


class JsonBodyRoute(APIRoute):
    """A route whose body, when it takes one, must be JSON.

    Checked before FastAPI reads the body: another media type (or none) gets 415, bytes that
    do not parse get 422 through the validation handler (FastAPI alone would pass the raw
    bytes on, or answer 400).
    """

    def get_route_handler(self) -> Callable[[Request], Coroutine[Any, Any, Response]]:
        handler = super().get_route_handler()
        if self.body_field is None:
            return handler

        async def checked(request: Request) -> Response:
            body = await request.body()  # cached: the handler reads the same bytes
            if body:
                content_type = request.headers.get("content-type")
                if not _is_json(content_type):
                    given = f"{content_type!r}" if content_type else "no Content-Type"
                    raise HTTPException(
                        415,
                        detail=f"unsupported media type ({given}): send the body as JSON "
                        "with Content-Type: application/json",
                    )
                try:
                    json.loads(body)
                except json.JSONDecodeError as exc:
                    raise _invalid_json(
                        f"{exc.msg} at line {exc.lineno} column {exc.colno}"
                    ) from None
                except UnicodeDecodeError:
                    raise _invalid_json("not UTF-8 text") from None
                except RecursionError:
                    raise _invalid_json("nested too deeply") from None
            return await handler(request)

        return checked


def router(prefix: str = "", tag: str | None = "pages", **kw: Any) -> APIRouter:
    """A router whose routes take JSON bodies only. ``tag``: its routes' heading in /docs
    (None: each route names its own; /docs lists an operation under every tag it has)."""
    tags: list[str | Enum] = [tag] if tag is not None else []
    return APIRouter(prefix=prefix, tags=tags, route_class=JsonBodyRoute, **kw)


def file_under(base: Path, path: str) -> Path:
    """``base / path`` if that is a file inside ``base``, else 404 (``..``, a symlink out, a
    NUL byte, a name too long; package markers such as ``__init__.py`` are not content)."""
    try:
        root = base.resolve()
        target = (root / path).resolve()
        found = (
            root in target.parents
            and target.is_file()
            and not any(p.startswith("__") for p in target.relative_to(root).parts)
        )
    except (OSError, ValueError):
        found = False
    if not found:
        raise HTTPException(404, detail="not found")
    return target
