"""Who may call the service: the Host check, the Origin check and the token.

``AccessGuard`` is one plain ASGI middleware (not Starlette's ``BaseHTTPMiddleware``,
which hides a client's disconnect from the route: ``/predict`` must see it) that checks,
in this order:

1. **Host**: the request's ``Host`` must name this server (``hosts``: the names it is
   bound to, or that a reverse proxy passes on; ``"*"`` turns the check off).  A page on
   a foreign name that resolves to 127.0.0.1 (DNS rebinding) is refused (421).
2. **Origin**: a state-changing request (POST, DELETE, ...) sent by a browser must come
   from this server's own page (``Origin`` equal to ``Host``) or an origin the server
   allows (``cors``); otherwise 403.  So a web page a user visits cannot queue jobs with
   a plain form post, token or not.  Requests without ``Origin`` (curl, scripts) pass.
3. **Token** (only when one is set): ``Authorization: Bearer TOKEN`` (the scheme in any
   case) or, for the page, the session cookie that ``POST /session`` (sent with that
   header) sets: HttpOnly, SameSite=Strict, holding a random session id made for that
   login (kept by the server, at most :data:`MAX_SESSIONS`), not the token; ``DELETE
   /session`` ends it, so a copied cookie is worth nothing after "log out" (sessions
   live in the server's memory: a restart ends them all).
   A token is never read from the URL: URLs end up in logs, histories and shared links.

Every answer also says it may not be framed by another site and that its type is the
one given (``X-Frame-Options``, ``Content-Security-Policy: frame-ancestors``,
``X-Content-Type-Options``).

``RedactTokens`` is a logging filter that blanks any ``token=...`` in a log line (the
access log prints query strings), whatever a client sent.
"""

from __future__ import annotations

import hashlib
import hmac
import logging
import re
import secrets
from http.cookies import SimpleCookie
from urllib.parse import urlsplit

from starlette.datastructures import Headers
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

__all__ = [
    "LOOPBACK_HOSTS",
    "MAX_SESSIONS",
    "SECURITY_HEADERS",
    "SESSION_COOKIE",
    "SESSION_PATH",
    "AccessGuard",
    "RedactTokens",
    "bearer_token",
    "host_name",
]

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
SESSION_COOKIE = "treesketch_session"
SESSION_PATH = "/session"
SAFE_METHODS = ("GET", "HEAD", "OPTIONS")
MAX_SESSIONS = 256  # page logins kept at once; the oldest ends first
# on every answer: no other site may frame the page (clickjacking), and no answer is
# sniffed into another type than the one it says
SECURITY_HEADERS = (
    (b"x-frame-options", b"DENY"),
    (b"content-security-policy", b"frame-ancestors 'none'"),
    (b"x-content-type-options", b"nosniff"),
)
_DEFAULT_PORTS = {"http": "80", "https": "443"}


def host_name(value: str) -> str:
    """The name part of a ``Host`` value (no port, no IPv6 brackets, lower case)."""
    value = value.strip().lower()
    if value.startswith("["):
        return value[1:].partition("]")[0]
    if value.count(":") == 1:
        value = value.partition(":")[0]
    return value.rstrip(".")


def bearer_token(authorization: str) -> str:
    """The token of an ``Authorization`` header ('' if it is not a Bearer one); the
    scheme is case-insensitive (RFC 9110, 11.1)."""
    scheme, _, value = authorization.strip().partition(" ")
    return value.strip() if scheme.lower() == "bearer" else ""


def _origin_netloc(origin: str) -> str | None:
    """``host[:port]`` of an Origin, the default port dropped; None when it is not one."""
    parts = urlsplit(origin.strip().lower())
    if parts.scheme not in _DEFAULT_PORTS or not parts.hostname:
        return None
    host = f"[{parts.hostname}]" if ":" in parts.hostname else parts.hostname
    try:
        port = parts.port
    except ValueError:
        return None
    if port is None or str(port) == _DEFAULT_PORTS[parts.scheme]:
        return host
    return f"{host}:{port}"


def _host_netloc(host: str) -> str:
    host = host.strip().lower()
    for port in _DEFAULT_PORTS.values():
        host = host.removesuffix(f":{port}")
    return host


class AccessGuard:
    """The Host, Origin and token checks (see the module text), in front of the app."""

    def __init__(
        self,
        app: ASGIApp,
        hosts: tuple[str, ...],
        cors: tuple[str, ...] = (),
        token: str | None = None,
        open_paths: tuple[str, ...] = (),
        open_prefixes: tuple[str, ...] = (),
    ) -> None:
        self.app = app
        self.any_host = "*" in hosts
        self.hosts = frozenset(host_name(h) for h in hosts if h != "*")
        self.cors = frozenset(o.strip().lower().rstrip("/") for o in cors)
        self.token = token.encode() if token else None
        # a random id per login, kept here as its hash (insertion order: the oldest first):
        # a copied cookie is not the token, and it ends with its session
        self.sessions: dict[str, None] = {}
        self.open_paths, self.open_prefixes = open_paths, open_prefixes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_secured(message: Message) -> None:
            if message["type"] == "http.response.start":
                have = {name.lower() for name, _ in message.get("headers", [])}
                extra = [(n, v) for n, v in SECURITY_HEADERS if n not in have]
                message = {**message, "headers": [*message.get("headers", []), *extra]}
            await send(message)

        await self._guarded(scope, receive, send_secured)

    async def _guarded(self, scope: Scope, receive: Receive, send: Send) -> None:
        headers = Headers(scope=scope)
        refusal = self._host(headers) or self._origin(scope, headers)
        if refusal is None and scope.get("path") == SESSION_PATH:
            response: Response = self._session(scope, headers)
        elif refusal is None and (refusal := self._token(scope, headers)) is None:
            await self.app(scope, receive, send)
            return
        else:
            response = refusal
        await response(scope, receive, send)

    # -- the checks: None when the request passes, else the answer -----------------------
    def _host(self, headers: Headers) -> Response | None:
        host = headers.get("host")
        if self.any_host or host is None or host_name(host) in self.hosts:
            return None
        return _refuse(
            421,
            f"this server does not answer to the name {host_name(host)!r}; it answers to "
            f"{', '.join(sorted(self.hosts))} (add names with --allow-host)",
        )

    def _origin(self, scope: Scope, headers: Headers) -> Response | None:
        if scope["method"] in SAFE_METHODS:
            return None
        origin = headers.get("origin")
        if origin is None:
            # an old browser may leave Origin out; its fetch metadata still tells
            if headers.get("sec-fetch-site", "") == "cross-site":
                return _refuse(403, "a cross-site request may not change anything here")
            return None
        if origin.strip().lower().rstrip("/") in self.cors:
            return None
        netloc = _origin_netloc(origin)
        if netloc is not None and netloc == _host_netloc(headers.get("host", "")):
            return None
        return _refuse(
            403,
            f"a request from the page at {origin!r} may not change anything on this server "
            "(only its own page, or an origin allowed with --cors)",
        )

    def _token(self, scope: Scope, headers: Headers) -> Response | None:
        if self.token is None:
            return None
        path = scope.get("path", "")
        if path in self.open_paths or path.startswith(self.open_prefixes):
            return None
        given = bearer_token(headers.get("authorization", ""))
        if given and hmac.compare_digest(given.encode(), self.token):
            return None
        if self._has_session(headers):
            return None
        return _refuse(
            401,
            "a token is needed: send 'Authorization: Bearer TOKEN' (the page: open it as "
            "/#token=TOKEN); a token in the URL is never read",
        )

    @staticmethod
    def _session_key(headers: Headers) -> str | None:
        """The hash of the request's session cookie, or None."""
        cookies = SimpleCookie()
        try:
            cookies.load(headers.get("cookie", ""))
        except Exception:  # noqa: BLE001 - a malformed cookie header is no session
            return None
        morsel = cookies.get(SESSION_COOKIE)
        if morsel is None or not morsel.value:
            return None
        # looked up by its hash: the lookup's time says nothing of a live id
        return hashlib.sha256(morsel.value.encode()).hexdigest()

    def _has_session(self, headers: Headers) -> bool:
        key = self._session_key(headers)
        return key is not None and key in self.sessions

    def _new_session(self) -> str:
        session = secrets.token_urlsafe(32)
        self.sessions[hashlib.sha256(session.encode()).hexdigest()] = None
        while len(self.sessions) > MAX_SESSIONS:
            del self.sessions[next(iter(self.sessions))]
        return session

    def _session(self, scope: Scope, headers: Headers) -> Response:
        """``POST /session`` with the token in the header: the page's cookie;
        ``DELETE /session``: the cookie cleared."""
        if self.token is None:
            return Response(status_code=204)  # nothing to log in to
        if scope["method"] == "DELETE":
            key = self._session_key(headers)
            if key is not None:
                self.sessions.pop(key, None)  # the cookie is worth nothing from now on
            response = Response(status_code=204)
            response.delete_cookie(SESSION_COOKIE, path="/", httponly=True, samesite="strict")
            return response
        if scope["method"] != "POST":
            return _refuse(405, "POST /session with 'Authorization: Bearer TOKEN', or DELETE")
        given = bearer_token(headers.get("authorization", ""))
        if not (given and hmac.compare_digest(given.encode(), self.token)):
            return _refuse(401, "a token is needed: send 'Authorization: Bearer TOKEN'")
        response = Response(status_code=204)
        response.set_cookie(
            SESSION_COOKIE,
            self._new_session(),
            path="/",
            httponly=True,
            samesite="strict",
            secure=scope.get("scheme") == "https",
        )
        return response


def _refuse(status: int, message: str) -> Response:
    return JSONResponse({"detail": message}, status_code=status)


class RedactTokens(logging.Filter):
    """Blank every ``token=VALUE`` (and ``access_token=``) in a record's message and
    arguments; keep the record."""

    PATTERN = re.compile(r"((?:access_)?token=)[^&\s\"']*", re.IGNORECASE)

    def filter(self, record: logging.LogRecord) -> bool:
        if isinstance(record.msg, str):
            record.msg = self.PATTERN.sub(r"\1[redacted]", record.msg)
        if isinstance(record.args, tuple):
            record.args = tuple(
                self.PATTERN.sub(r"\1[redacted]", a) if isinstance(a, str) else a
                for a in record.args
            )
        return True
