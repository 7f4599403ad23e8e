"""Who is who: the instructor (``serve --instructor-token T``), and the holders of private
sessions (their seat cookie or session token).

With an instructor only the instructor changes the shared demo; students watch it (and, with
private sessions, drive their own robots).

Who is the instructor:

- through the HTTP API, a request carrying ``Authorization: Bearer T``; a request that would
  change the shared session without it gets 401, with a wrong token 403, each with a line
  saying what to do (``app.web.api.live``);
- in the browser, the page opened once as ``/?token=T``: the token is exchanged for the
  *instructor cookie* (:data:`INSTRUCTOR_COOKIE`: a fresh random credential, HttpOnly,
  SameSite=Strict, for this browser's session) and the browser is sent on to ``/`` (303), so
  the token is in no frame's address, no page, no later request and no history entry. The
  cookie goes with the scene's websocket too (cookies know no ports): the display reads it
  when the browser connects (:func:`client_instructor`), and the API accepts it as it accepts
  the bearer token.

The token is compared in constant time (:func:`hmac.compare_digest`) and never logged: the
web server's access log is off, and :class:`RedactTokens` blanks ``token=...`` in any record
of the loggers that could print a URL. The cookies the instructor's browsers were given are
kept in memory only (a restarted server asks for the token again).

A private session's holder (``app.live.registry``): a browser is known by its *seat cookie*
(:data:`SEAT_COOKIE`, HttpOnly, set by the page ``/`` in private mode). Cookies belong to a
host, not a port, so the browser sends it with the scene's websocket too
(:func:`client_seat`), and its session follows the browser through a reload, a reconnect or a
second tab, and answers its API calls. A script is known by the token ``POST /api/sessions``
gave it, sent as ``Authorization: Bearer <token>``.
"""

from __future__ import annotations

import hmac
import logging
import re
import secrets
import threading
from http.cookies import CookieError, SimpleCookie
from typing import Any

from fastapi.security import HTTPBearer

TOKEN_PARAM = "token"
SEAT_COOKIE = "pelvic_walk_seat"  # a browser's credential for its private session
INSTRUCTOR_COOKIE = "pelvic_walk_instructor"  # the instructor's browser, once it gave the token
MAX_INSTRUCTOR_COOKIES = 32  # browsers the instructor opened the page in (the oldest forgotten)
_TOKEN_IN_TEXT = re.compile(r"(token=)[^&\s\"']+", re.IGNORECASE)
_BEARER_IN_TEXT = re.compile(r"(bearer\s+)\S+", re.IGNORECASE)
URL_LOGGERS = (  # a logger's filters see only its own records, not its children's
    "uvicorn",
    "uvicorn.access",
    "uvicorn.error",
    "websockets",
    "websockets.server",
    "viser",
)


# The API's bearer credential: the instructor's token (with an instructor, changing the shared
# session needs it; it reaches every private session too), or a private session's token (given
# once, by POST /api/sessions). Reading the shared session needs nothing.
BEARER = HTTPBearer(
    auto_error=False,
    description="The instructor's token (serve --instructor-token: changing the shared "
    "session needs it, and it reaches every private session), or a private session's token "
    "(POST /api/sessions answers with it once). A browser's page sends its seat cookie "
    "instead. Reading the shared session needs nothing.",
)


def new_credential() -> str:
    """A fresh secret for a seat cookie or a session token (256 bits)."""
    return secrets.token_urlsafe(32)


class Instructor:
    """The instructor's token (None: no instructor, everyone may change the shared demo)."""

    def __init__(self, token: str | None):
        if token is not None and not token.strip():
            raise ValueError("the instructor token is empty")
        self._token = token.encode("utf-8") if token is not None else None
        self._cookies: list[bytes] = []  # given to the instructor's browsers, newest last
        self._lock = threading.Lock()

    @property
    def enabled(self) -> bool:
        return self._token is not None

    def is_token(self, candidate: str | None) -> bool:
        """True if ``candidate`` is the token (constant time: no timing tells how much of a
        guess was right)."""
        if self._token is None or candidate is None:
            return False
        return hmac.compare_digest(candidate.encode("utf-8"), self._token)

    def issue_cookie(self) -> str:
        """A fresh instructor cookie's value, for a browser that has just given the token."""
        value = new_credential()
        with self._lock:
            self._cookies = [*self._cookies, value.encode("utf-8")][-MAX_INSTRUCTOR_COOKIES:]
        return value

    def is_cookie(self, candidate: str | None) -> bool:
        """True if ``candidate`` is an instructor cookie this server gave (constant time)."""
        if self._token is None or not candidate:
            return False
        given = candidate.encode("utf-8")
        with self._lock:
            cookies = list(self._cookies)
        found = False
        for c in cookies:  # every one compared: the time tells nothing about which
            found |= hmac.compare_digest(given, c)
        return found

    def __repr__(self) -> str:  # never the token itself
        return f"Instructor(enabled={self.enabled})"


def _connection(server: Any, client: Any) -> Any:
    """The websocket connection (the websockets library's ``ServerConnection``) a viser client
    came in on, or None. viser keeps it only in a private table, so this reads it defensively:
    any change there reads as "nothing known" (a student without a seat), never as an error."""
    try:
        return server._websock_server._live_connections[client.client_id]
    except (AttributeError, KeyError, TypeError):
        return None


def seat_of(cookie_header: str | None, name: str = SEAT_COOKIE) -> str | None:
    """The seat cookie's (or cookie ``name``'s) value in a ``Cookie`` header, or None (none,
    or malformed)."""
    if not cookie_header:
        return None
    try:
        jar: SimpleCookie = SimpleCookie()
        jar.load(cookie_header)
    except CookieError:
        return None
    morsel = jar.get(name)
    return morsel.value if morsel is not None and morsel.value else None


def client_instructor(server: Any, client: Any) -> str | None:
    """The instructor cookie the browser of a viser client sent with its websocket, or None."""
    try:
        headers = _connection(server, client).request.headers
        return seat_of(headers.get("Cookie"), INSTRUCTOR_COOKIE)
    except AttributeError:
        return None


def client_seat(server: Any, client: Any) -> str | None:
    """The seat cookie the browser of a viser client sent with its websocket, or None."""
    try:
        headers = _connection(server, client).request.headers
        return seat_of(headers.get("Cookie"))
    except AttributeError:
        return None


def client_headers(server: Any, client: Any) -> Any:
    """The HTTP headers of a viser client's websocket request, or None."""
    try:
        return _connection(server, client).request.headers
    except AttributeError:
        return None


def client_address(server: Any, client: Any) -> str | None:
    """The network address a viser client's socket connected from (the peer: behind a
    proxy, the proxy's; :class:`app.web.addresses.ClientAddresses` reads the client's), or
    None."""
    try:
        return str(_connection(server, client).remote_address[0])
    except (AttributeError, IndexError, TypeError):
        return None


def redact(text: str) -> str:
    """``text`` with any ``token=...`` value and bearer credential blanked."""
    return _BEARER_IN_TEXT.sub(r"\1***", _TOKEN_IN_TEXT.sub(r"\1***", text))


class RedactTokens(logging.Filter):
    """Blanks tokens in a record's message and arguments (added to :data:`URL_LOGGERS`)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if isinstance(record.msg, str):
            record.msg = redact(record.msg)
        if isinstance(record.args, tuple):
            record.args = tuple(redact(a) if isinstance(a, str) else a for a in record.args)
        elif isinstance(record.args, dict):
            record.args = {
                k: redact(v) if isinstance(v, str) else v for k, v in record.args.items()
            }
        return True


def redact_logs() -> RedactTokens:
    """Install :class:`RedactTokens` on the loggers that could print a URL (idempotent)."""
    f = RedactTokens()
    for name in URL_LOGGERS:
        logger = logging.getLogger(name)
        if not any(isinstance(x, RedactTokens) for x in logger.filters):
            logger.addFilter(f)
    return f
