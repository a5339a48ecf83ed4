"""The lock on the console's door: who may load the page and talk to its socket.

The console commands a mission (and, live, the operator's team member, which holds the
operator's key), so binding 127.0.0.1 is not enough: another local user, or a web page
in the operator's own browser (DNS rebinding, a cross-site socket), can reach the
port. Every request — the page, its assets, the socket.io connection, HTTP and
WebSocket alike — passes :class:`ConsoleGuard` first:

* the ``Host`` header must name this server (``127.0.0.1:PORT`` or ``localhost:PORT``):
  a rebinding page's requests carry its own name and are refused;
* an ``Origin`` header, when sent (browsers send it on every socket and cross-site
  request), must be this server's;
* a per-run secret must come with it: the ``token`` query parameter of the URL printed
  at start (the page's response then sets it as an HttpOnly, SameSite=Strict cookie,
  which the page's own requests carry from then on), or that cookie;
* every HTTP response forbids framing (``Content-Security-Policy: frame-ancestors
  'none'``, ``X-Frame-Options: DENY``) and sniffing, and sends no referrer (the URL
  holds the secret).

At most :data:`MAX_SOCKETS` page sockets are open at once (each holds a page's state
in this process); more are refused (``too many clients``). Refusals are answered 403
(HTTP) or a closed socket, and counted by cause.
"""

from __future__ import annotations

import secrets
import threading
from collections import Counter
from collections.abc import Awaitable, Callable, MutableMapping
from http.cookies import SimpleCookie
from typing import Any
from urllib.parse import parse_qs

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]

COOKIE = "mrcomm_console"
#: Page sockets open at once (an operator and a few observers).
MAX_SOCKETS = 8
#: Headers of every HTTP response.
SECURITY_HEADERS: tuple[tuple[bytes, bytes], ...] = (
    (b"content-security-policy", b"frame-ancestors 'none'"),
    (b"x-frame-options", b"DENY"),
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"no-referrer"),
)


class ConsoleGuard:
    """The console server's secret, the names it answers to, and what it refused."""

    def __init__(self, port: int, token: str | None = None) -> None:
        self.port = port
        self.token = token or secrets.token_urlsafe(24)
        self.hosts = frozenset({f"127.0.0.1:{port}", f"localhost:{port}"})
        self.origins = frozenset(f"http://{host}" for host in self.hosts)
        self.refused: Counter[str] = Counter()
        self._lock = threading.Lock()
        self._sockets = 0

    @property
    def url(self) -> str:
        """The page's address with the secret (what the command prints)."""
        return f"http://127.0.0.1:{self.port}/?token={self.token}"

    def refusal(self, scope: Scope) -> tuple[str, bool]:
        """Why the request of ``scope`` is refused ("" when it is not), and whether it
        came with the secret in its query (its response then sets the cookie)."""
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}
        if headers.get("host", "") not in self.hosts:
            return "foreign host", False
        origin = headers.get("origin")
        if origin is not None and origin not in self.origins:
            return "foreign origin", False
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        given = query.get("token", [""])[0]
        if given and secrets.compare_digest(given, self.token):
            return "", True
        cookie = SimpleCookie()
        try:
            cookie.load(headers.get("cookie", ""))
        except Exception:  # a malformed cookie header is no secret
            return "missing token", False
        held = cookie.get(COOKIE)
        if held is not None and secrets.compare_digest(held.value, self.token):
            return "", False
        return "missing token", False

    def _open_socket(self) -> bool:
        """Take one of the :data:`MAX_SOCKETS` (False: none left)."""
        with self._lock:
            if self._sockets >= MAX_SOCKETS:
                return False
            self._sockets += 1
            return True

    def count(self, cause: str) -> None:
        with self._lock:
            self.refused[cause] += 1

    def middleware(self, app: App) -> App:
        """``app`` behind this guard (an ASGI middleware)."""

        async def guarded(scope: Scope, receive: Receive, send: Send) -> None:
            if scope["type"] not in ("http", "websocket"):
                await app(scope, receive, send)
                return
            cause, with_token = self.refusal(scope)
            if cause:
                self.count(cause)
                await _refuse(scope, receive, send, cause)
                return
            if scope["type"] == "websocket":
                if not self._open_socket():
                    self.count("too many clients")
                    await _refuse(scope, receive, send, "too many clients")
                    return
                try:
                    await app(scope, receive, send)
                finally:
                    with self._lock:
                        self._sockets -= 1
                return

            async def send_with_headers(message: Message) -> None:
                if message["type"] == "http.response.start":
                    headers = list(message.get("headers", []))
                    headers += SECURITY_HEADERS
                    if with_token:
                        value = f"{COOKIE}={self.token}; HttpOnly; SameSite=Strict; Path=/"
                        headers.append((b"set-cookie", value.encode("latin-1")))
                    message["headers"] = headers
                await send(message)

            await app(scope, receive, send_with_headers)

        return guarded


async def _refuse(scope: Scope, receive: Receive, send: Send, cause: str) -> None:
    if scope["type"] == "websocket":
        await receive()  # the connect message
        await send({"type": "websocket.close", "code": 1008})
        return
    body = f"refused: {cause}\n".encode()
    await send(
        {
            "type": "http.response.start",
            "status": 403,
            "headers": [
                (b"content-type", b"text/plain; charset=utf-8"),
                (b"content-length", str(len(body)).encode()),
                *SECURITY_HEADERS,
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})
