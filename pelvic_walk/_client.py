"""A client for a served tool (``pelvic-walk serve``): the HTTP API of docs/REFERENCE.md from
Python, its error answers raised as exceptions that carry the API's own message."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from typing import Any
from urllib.parse import quote

import httpx

from pelvic_walk import _params

SESSION_HEADER = "X-Pelvic-Session"  # app/web/api/sessions.py


class ApiError(Exception):
    """The served tool refused a request: ``str(error)`` is its message (the answer's
    ``detail``), ``status`` the HTTP status, ``body`` the whole answer (dict)."""

    def __init__(self, status: int, detail: str, body: Any = None):
        self.status, self.detail, self.body = status, detail, body
        super().__init__(detail)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.status}, {self.detail!r})"


class InvalidRequest(ApiError, ValueError):
    """415 / 422: a value out of range, an unknown method or field, a bad body."""


class NotAllowed(ApiError, PermissionError):
    """401 / 403: the instructor drives this session (send their token), or a wrong token."""


class NotFound(ApiError, LookupError):
    """404: no such session or run (or no shared session on this server)."""


class Conflict(ApiError):
    """409: not now (seek while running, a recording already being made, ...)."""


class Busy(ApiError):
    """429 / 503: too many headless runs, the workers are full, or no frame yet."""


_ERRORS: dict[int, type[ApiError]] = {
    401: NotAllowed,
    403: NotAllowed,
    404: NotFound,
    409: Conflict,
    415: InvalidRequest,
    422: InvalidRequest,
    429: Busy,
    503: Busy,
}


def _raise_for(response: httpx.Response) -> None:
    if response.is_success:
        return
    try:
        body = response.json()
    except ValueError:
        body = None
    detail = body.get("detail") if isinstance(body, dict) else None
    if not isinstance(detail, str):
        detail = f"HTTP {response.status_code}: {response.text[:200] or response.reason_phrase}"
    raise _ERRORS.get(response.status_code, ApiError)(response.status_code, detail, body)


def _groups(params: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Keywords as the API's groups: the paper's names are checked here; another dotted name
    (a strategy's own ``gain.k``, ``mpc.alpha``) goes as it is, for the server to check
    (its strategies are not loaded here)."""
    body: dict[str, dict[str, Any]] = {}
    for key, value in params.items():
        try:
            group, name, _ = _params._field_of(key)
        except ValueError:
            group, dot, name = key.partition(".")
            if not (dot and group and name):
                raise
        body.setdefault(group, {})[name] = _params._plain(value)
    return body


class Client:
    """Drive a served tool (a lecture's script, a notebook beside the class's page).

    Args:
        url: the page's address, e.g. ``"http://127.0.0.1:8000"``.
        token: the instructor's token (``serve --instructor-token``), sent as
            ``Authorization: Bearer``: needed to change the shared session when an
            instructor drives it.
        session: a session id (``"shared"`` by default; :meth:`open_session` gives a private
            one).
        headers: more headers for every request (e.g. a session credential).
        timeout: [s] per request.

    Every method raises the API's refusals as :class:`ApiError` subclasses with the API's
    message (:class:`NotAllowed` for 401/403, :class:`InvalidRequest`, also a ValueError, for
    422, :class:`Conflict`, :class:`NotFound`, :class:`Busy`), and ``ConnectionError`` when
    nothing answers at ``url``. Cookies a server sets (e.g. a session's credential) are kept
    for the client's later requests and for the sessions it opens.
    """

    def __init__(
        self,
        url: str,
        token: str | None = None,
        session: str | None = None,
        headers: Mapping[str, str] | None = None,
        timeout: float = 30.0,
        _http: httpx.Client | None = None,
    ):
        self.url = url.rstrip("/")
        self.session = session
        extra = dict(headers or {})
        if token:
            extra["Authorization"] = f"Bearer {token}"
        self._http = _http or httpx.Client(base_url=self.url, timeout=timeout)
        self._headers = extra
        self._session_tokens: dict[str, str] = {}  # sessions this client opened -> their token
        self._parent: Client | None = None  # the client that opened this one's session
        self._owns_http = _http is None

    # -- plumbing ----------------------------------------------------------------------------
    def _request(self, verb: str, path: str, **kw: Any) -> httpx.Response:
        headers = {**self._headers, **kw.pop("headers", {})}
        try:
            response = self._http.request(verb, path, headers=headers, **kw)
        except httpx.TransportError as exc:
            raise ConnectionError(
                f"no pelvic-walk server answers at {self.url} ({type(exc).__name__}: {exc})"
            ) from None
        _raise_for(response)
        return response

    def _json(self, verb: str, path: str, **kw: Any) -> Any:
        return self._request(verb, path, **kw).json()

    def _live(self, route: str) -> str:
        """A session route: ``/api/<route>`` (shared) or ``/api/sessions/{id}/<route>``."""
        if self.session in (None, "shared"):
            return f"/api/{route}"
        return f"/api/sessions/{quote(str(self.session), safe='')}/{route}"

    def close(self) -> None:
        """Close the connections (a client made by :meth:`open_session` shares its parent's)."""
        if self._owns_http:
            self._http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<Client {self.url} session={self.session or 'shared'}>"

    # -- the server ----------------------------------------------------------------------------
    def health(self) -> dict[str, Any]:
        """``GET /api/health``."""
        return self._json("GET", "/api/health")

    def strategies(self) -> list[dict[str, Any]]:
        """The pelvis strategies the server can run (``GET /api/strategies``)."""
        return self._json("GET", "/api/strategies")["strategies"]

    def spec(self) -> dict[str, Any]:
        """Every parameter's range, unit and default (``GET /api/params/spec``)."""
        return self._json("GET", "/api/params/spec")

    # -- a live session -------------------------------------------------------------------
    def params(self) -> dict[str, Any]:
        """The parameters in force: groups ``walk``, ``com``, ``pelvis``, ``ik``, ``arms``,
        each strategy's own (a group named by it: ``"gain": {"k": 4.0}``), ``methods`` (the
        robots' labels) and ``robots`` (label, strategy, own settings, form of each)."""
        return self._json("GET", self._live("params"))

    def set_params(
        self,
        methods: Sequence[str] | None = None,
        robot: str | None = None,
        **params: Any,
    ) -> dict[str, Any]:
        """Change some parameters, by the names :func:`pelvic_walk.simulate` takes
        (``step_length=0.3``, ``pelvis_k_pel=0.3``, ``**{"pelvis.k_pel": 0.3}``, a strategy's
        own ``**{"gain.k": 12}``); ``robot``: a robot's label, whose own settings change (the
        others keep theirs; without it every robot's change); ``methods``: the robots to show,
        one per strategy (restarts them together). Gains act on the next tick, walking
        parameters from the next step. Returns the parameters in force."""
        body: dict[str, Any] = _groups(params)
        if methods is not None:
            body["methods"] = [methods] if isinstance(methods, str) else list(methods)
        if robot is not None:
            body["robot"] = robot
        if not body or list(body) == ["robot"]:
            raise ValueError("set_params() needs a parameter or methods=")
        return self._json("PUT", self._live("params"), json=body)

    def robots(self) -> list[dict[str, Any]]:
        """The robots shown: ``label``, ``strategy``, ``settings`` (its own values over the
        shared parameters) and ``text`` (its form ``NAME[,KEY=VALUE...][@LABEL]``)."""
        return self.params()["robots"]

    def set_robots(self, robots: Sequence[str | Mapping[str, Any]]) -> list[dict[str, Any]]:
        """Show these robots (all restart together): each a form such as
        ``"mpc,com.horizon=0.8@short"``, or ``{"strategy": "mpc", "settings": {...},
        "label": "short"}``. Returns them as :meth:`robots` does."""
        items = [robots] if isinstance(robots, str) else list(robots)
        body = {"robots": [r if isinstance(r, str) else dict(r) for r in items]}
        return self._json("PUT", self._live("params"), json=body)["robots"]

    def pause(self) -> dict[str, Any]:
        """Stop the clock (``POST /api/sim/pause``)."""
        return self._json("POST", self._live("sim/pause"))

    def resume(self) -> dict[str, Any]:
        """Run again from the present."""
        return self._json("POST", self._live("sim/resume"))

    def reset(self) -> dict[str, Any]:
        """Restart every robot from standing."""
        return self._json("POST", self._live("sim/reset"))

    def step(self, until: str = "tick") -> dict[str, Any]:
        """Pause and advance one 5 ms ``"tick"``, or to the next ``"liftoff"`` or
        ``"landing"``."""
        return self._json("POST", self._live("sim/step"), json={"until": until})

    def next_liftoff(self) -> dict[str, Any]:
        """Pause at the next lift-off (``step("liftoff")``)."""
        return self.step("liftoff")

    def speed(self, speed: float) -> dict[str, Any]:
        """Playback speed [x real time], 0.1 to 4."""
        return self._json("PUT", self._live("sim/speed"), json={"speed": speed})

    def seek(self, t: float) -> dict[str, Any]:
        """While paused, show the kept instant nearest to session clock ``t`` [s]; returns the
        state there (:meth:`state`). :class:`Conflict` while running."""
        return self._json("POST", self._live("sim/seek"), json={"t": t})

    def push(self, method: str, force: Sequence[float], duration: float = 0.1) -> dict[str, Any]:
        """Push the torso of the robot labelled ``method`` with ``force`` = (Fx, Fy) [N] for
        ``duration`` [s]."""
        body = {"method": method, "force": [float(f) for f in force], "duration": duration}
        return self._json("POST", self._live("sim/push"), json=body)

    def state(self) -> dict[str, Any]:
        """The clock, what is kept, and every robot's state (``GET /api/state``), each named
        by its ``label`` with its ``strategy`` and the ``settings`` it does not share."""
        return self._json("GET", self._live("state"))

    def horizon(self, method: str | None = None) -> dict[str, Any]:
        """One robot's plan over the horizon at the shown instant (``GET /api/horizon``);
        ``method``: its label (default: the first running the MPC)."""
        query = {"method": method} if method else None
        return self._json("GET", self._live("horizon"), params=query)

    def qp(self, method: str | None = None) -> dict[str, Any]:
        """What one robot's four optimisations did at the shown instant (``GET /api/qp``):
        cost terms, active constraints by name with their multipliers."""
        query = {"method": method} if method else None
        return self._json("GET", self._live("qp"), params=query)

    def recording(self, seconds: float = 10.0, format: str = "zip") -> bytes:
        """The last ``seconds`` as a file that plays back without the server: ``zip``,
        ``html`` (the scene), ``csv`` or ``png``."""
        query = {"seconds": seconds, "format": format}
        return self._request("GET", self._live("recording"), params=query).content

    # -- sessions --------------------------------------------------------------------------
    def sessions(self) -> dict[str, Any]:
        """``GET /api/sessions``."""
        return self._json("GET", "/api/sessions")

    def open_session(self) -> Client:
        """Open a private session (a server with ``--sessions private``) and return a client
        for it, sharing this one's connection, headers and cookies; it sends the session's own
        token (the server gives it once, in this answer) as its bearer credential. A second
        call returns the same session (one seat a client)."""
        # a session this client holds already: asked with its token, the server returns it
        held = next(reversed(self._session_tokens.values()), None)
        extra = {"Authorization": f"Bearer {held}"} if held else {}
        created = self._json("POST", "/api/sessions", headers=extra)
        child = Client(self.url, session=created["id"], _http=self._http)
        child._parent = self
        child._headers = dict(self._headers)
        if created.get("token"):  # the session's own credential, given only in this answer
            self._session_tokens[created["id"]] = created["token"]
        token = self._session_tokens.get(created["id"])
        if token:
            child._headers["Authorization"] = f"Bearer {token}"
        child.created = created  # type: ignore[attr-defined]
        return child

    def close_session(self) -> dict[str, Any]:
        """Close this client's private session."""
        if self.session in (None, "shared"):
            raise ValueError("this client drives the shared session, which cannot be closed")
        closed = self._json("DELETE", f"/api/sessions/{quote(str(self.session), safe='')}")
        if self._parent is not None:
            self._parent._session_tokens.pop(str(self.session), None)
        return closed

    # -- headless runs -------------------------------------------------------------------------
    def start_run(
        self, method: str = "mpc", seed: int | None = None, **params: Any
    ) -> dict[str, Any]:
        """Queue a headless run on the server (``POST /api/runs``): ``{"id", "status", ...}``."""
        body: dict[str, Any] = {"method": method, **_groups(params)}
        if seed is not None:
            body["seed"] = seed
        return self._json("POST", "/api/runs", json=body)

    def get_run(self, run_id: str) -> dict[str, Any]:
        """``GET /api/runs/{id}``: ``status`` and, when done, ``summary``."""
        return self._json("GET", f"/api/runs/{quote(run_id, safe='')}")

    def run(
        self,
        method: str = "mpc",
        seed: int | None = None,
        timeout: float = 600.0,
        poll: float = 0.5,
        **params: Any,
    ) -> dict[str, Any]:
        """A headless run on the server, waited for: its summary (the ``simulate --json``
        keys). RuntimeError if the run failed, TimeoutError after ``timeout`` [s]."""
        run_id = self.start_run(method, seed, **params)["id"]
        deadline = time.monotonic() + timeout
        while True:
            rec = self.get_run(run_id)
            if rec["status"] == "done":
                return rec["summary"]
            if rec["status"] == "error":
                raise RuntimeError(f"run {run_id} failed on the server: {rec['error']}")
            if time.monotonic() > deadline:
                raise TimeoutError(f"run {run_id} still {rec['status']} after {timeout:g} s")
            time.sleep(poll)
