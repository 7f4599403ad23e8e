"""One address source for every seat: which client a request or a scene connection comes from.

The per-address limits (private sessions, ``--sessions-per-address``; headless runs,
:class:`app.web.api.headless.RunManager`) count clients by address. The page and the HTTP API
(uvicorn's requests) and the 3-D scene (viser's websocket connections) all ask
:meth:`ClientAddresses.resolve` with the connection's peer address and its headers, so one
browser is one address everywhere.

Behind a reverse proxy every connection's peer is the proxy. The proxy's address is *trusted*
(``serve --trusted-proxy ADDR`` or ``PELVIC_WALK_TRUSTED_PROXIES``, addresses or networks,
comma separated): from it, and only from it, the ``X-Forwarded-For`` header names the client
(read from the right: the nearest address that is not itself a trusted proxy). A forwarded
header from anyone else is ignored (a client could write any address there). uvicorn's own
reading of forwarded headers is off (``proxy_headers=False``): it read them from 127.0.0.1
for the API only, never for the scene, which made two sources for one seat.
"""

from __future__ import annotations

import ipaddress
import logging
from collections.abc import Iterable, Mapping
from typing import Any

log = logging.getLogger(__name__)
FORWARDED_FOR = "x-forwarded-for"
Network = ipaddress.IPv4Network | ipaddress.IPv6Network


def _ip(text: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    text = text.strip()
    if text.startswith("[") and "]" in text:  # [v6]:port
        text = text[1 : text.index("]")]
    elif text.count(":") == 1:  # v4:port
        text = text.split(":")[0]
    try:
        ip = ipaddress.ip_address(text)
    except ValueError:
        return None
    mapped = getattr(ip, "ipv4_mapped", None)
    return mapped or ip


def parse_trusted(spec: str | Iterable[str] | None) -> tuple[Network, ...]:
    """``"127.0.0.1, 10.0.0.0/8"`` (or a list) -> networks; ValueError on a bad entry."""
    if spec is None:
        return ()
    items = spec.split(",") if isinstance(spec, str) else list(spec)
    out = []
    for item in (i.strip() for i in items):
        if not item:
            continue
        try:
            out.append(ipaddress.ip_network(item, strict=False))
        except ValueError:
            raise ValueError(f"not an IP address or network: {item!r}") from None
    return tuple(out)


class ClientAddresses:
    """The client address of a connection, the same way for the page, the API and the scene."""

    def __init__(self, trusted: str | Iterable[str] | None = None):
        self.trusted = parse_trusted(trusted)
        self._warned = False

    def _is_trusted(self, ip: Any) -> bool:
        return ip is not None and any(ip in net for net in self.trusted)

    def resolve(self, peer: str | None, headers: Mapping[str, str] | None) -> str | None:
        """The client's address: ``peer`` (the socket's), or, when ``peer`` is a trusted proxy,
        the nearest untrusted address its ``X-Forwarded-For`` names (the proxy's own when it
        names none)."""
        if peer is None:
            return None
        forwarded = _header(headers, FORWARDED_FOR)
        peer_ip = _ip(peer)
        if not self._is_trusted(peer_ip):
            if forwarded and not self._warned and peer_ip is not None and peer_ip.is_loopback:
                self._warned = True  # once: a proxy on this machine that nobody trusted
                log.warning(
                    "a connection from %s came with X-Forwarded-For, but that address is not "
                    "a trusted proxy: every client behind it counts as one address. Behind a "
                    "reverse proxy, start with --trusted-proxy %s (docs/TEACHING.md)",
                    peer,
                    peer_ip,
                )
            return str(peer_ip) if peer_ip is not None else peer
        client = str(peer_ip)
        if forwarded:
            for hop in reversed(forwarded.split(",")):
                ip = _ip(hop)
                if ip is None:  # not an address: stop at the last one known good
                    break
                client = str(ip)
                if not self._is_trusted(ip):
                    break
        return client

    def of_request(self, request: Any) -> str | None:
        """A FastAPI request's client address."""
        peer = request.client.host if request.client is not None else None
        return self.resolve(peer, request.headers)


def _header(headers: Mapping[str, str] | None, name: str) -> str | None:
    """A header's value (every ``X-Forwarded-For`` line joined), case-insensitively."""
    if headers is None:
        return None
    get_all = getattr(headers, "get_all", None) or getattr(headers, "getlist", None)
    if get_all is not None:
        values = list(get_all(name))
        return ", ".join(values) if values else None
    for key, value in headers.items():
        if key.lower() == name:
            return value
    return None
