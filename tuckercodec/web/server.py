"""A small web server for the viewer's folder (:mod:`tuckercodec.web.site`), on this machine only.

It listens on 127.0.0.1 and nowhere else, and serves exactly the files the folder was built
with, by their exact paths: anything else is 404, so there is no directory listing and no way
out of the folder (``..``, encoded or not, names no file of the list). ``/`` is the folder's
index.html. Every response says ``Cache-Control: no-store`` (a page reopened after the file
changed must not run stale scripts or show a stale file) and ``X-Content-Type-Options:
nosniff`` with the right type for each file: browsers refuse to run an ES module served as
anything but JavaScript. It also carries the page's Content-Security-Policy as an HTTP header,
with ``frame-ancestors 'none'`` (which a meta tag cannot say) and ``X-Frame-Options: DENY``, so
no other page can frame the viewer, and ``Referrer-Policy: no-referrer``.

Each connection has a read and idle timeout (:data:`CONNECTION_TIMEOUT`): a client that stops
sending, mid-request or between requests, is disconnected, so half-sent requests cannot hold
threads. A request's line and headers must also arrive whole within :data:`REQUEST_DEADLINE`
of when the server starts waiting for them: a client that sends a byte every few seconds,
never idle for long, is disconnected there too (otherwise 64 kB of request line and a hundred
headers at a byte every 4 s would hold a thread for weeks).

A connection holds no place until it has shown the token: until its first request's line and
headers have arrived it is *waiting*, and at most :data:`MAX_WAITING` connections wait at once;
one more makes room by closing the one that has waited longest. A browser sends a request's
headers at once, so it waits for milliseconds, while a client that connects and trickles (or
sends nothing) is the oldest soon: connections without the token cannot crowd out the page's
requests. A connection whose request carries the token is *admitted* and may stay open for the
next (keep-alive), at most :data:`MAX_CONNECTIONS` at once (503 beyond); a connection whose
request is refused, or is no GET or HEAD, is closed after its response.

Each run has a random token (as Jupyter does), in the URL to open (:meth:`ViewerServer.address`,
``...&token=...``) and required on every request: other users of the machine can reach
127.0.0.1 too. The first request that carries it in its query gets it back as a cookie (named
with the port, since cookies do not tell ports apart), which the page's module, script and file
requests then carry; a request with neither is refused (403). The Cookie header is split by
hand (``;`` between cookies, the first ``=`` in each), not with ``http.cookies``, which gives
up on the whole header at one cookie it cannot parse: another local app's cookie for
127.0.0.1 must not hide this one. A request whose ``Host`` is not
this server's address is refused (403) too, which stops a web page elsewhere from reaching it
through a name that resolves to 127.0.0.1 (DNS rebinding).

Use it as a context manager: the server answers in a background thread from ``__enter__`` until
``__exit__`` shuts it down.
"""

from __future__ import annotations

import io
import secrets
import shutil
import socket
import sys
import threading
import time
from collections import OrderedDict
from contextlib import suppress
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path, PurePosixPath
from types import TracebackType
from typing import Any
from urllib.parse import parse_qs, quote, unquote, urlsplit

from .site import page_policy

#: The only address the server listens on.
HOST = "127.0.0.1"

#: How often the serving thread looks for a shutdown request: what stopping can take.
POLL_SECONDS = 0.05

#: Seconds a connection may wait for the client's next bytes (mid-request or between requests).
CONNECTION_TIMEOUT = 5.0

#: Seconds a request's line and headers may take to arrive, all of them together, from when the
#: server starts waiting for the request.
REQUEST_DEADLINE = 15.0

#: Admitted connections (whose request carried the token) open at once; a browser opens about
#: six. Another is answered 503 and closed.
MAX_CONNECTIONS = 64

#: Connections waiting for their first request's headers at once; one more closes the oldest.
MAX_WAITING = 64

#: What every response adds to the page's own policy: no page may frame this one.
FRAME_POLICY = "frame-ancestors 'none'"

#: Content-Type by suffix; a file without a suffix (LICENSE) is plain text.
CONTENT_TYPES = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".bin": "application/octet-stream",
    ".tkc": "application/octet-stream",
    ".md": "text/markdown; charset=utf-8",
    "": "text/plain; charset=utf-8",
}


def content_type(name: str) -> str:
    """The Content-Type of a file of the folder, by its suffix."""
    return CONTENT_TYPES.get(PurePosixPath(name).suffix.lower(), "application/octet-stream")


class ViewerServer(ThreadingHTTPServer):
    """Serve ``files`` (POSIX paths relative to ``folder``) on 127.0.0.1:``port`` (0: a free
    port, chosen by the system); :attr:`url` is its address.

    Raises:
        OSError: the port cannot be had (in use, or a privileged port).
    """

    daemon_threads = True  # a browser's open connection must not hold up the shutdown
    request_queue_size = MAX_WAITING  # accepted at once, then the oldest waiting one closed

    def __init__(
        self,
        folder: str | Path,
        files: list[str] | tuple[str, ...],
        port: int = 0,
        *,
        connection_timeout: float = CONNECTION_TIMEOUT,
        request_deadline: float = REQUEST_DEADLINE,
        max_connections: int = MAX_CONNECTIONS,
        max_waiting: int = MAX_WAITING,
        token: str | None = None,
    ):
        root = Path(folder)
        self.routes: dict[str, Path] = {"/" + name: root / name for name in files}
        if "/index.html" in self.routes:
            self.routes["/"] = self.routes["/index.html"]
        self.connection_timeout = connection_timeout
        self.request_deadline = request_deadline
        self.token = token if token is not None else secrets.token_urlsafe(32)
        self.policy = f"{page_policy()}; {FRAME_POLICY}"
        self._slots = threading.BoundedSemaphore(max_connections)
        self._max_waiting = max_waiting
        self._waiting: OrderedDict[int, socket.socket] = OrderedDict()  # oldest first
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        super().__init__((HOST, port), _Handler)

    def process_request(self, request: Any, client_address: Any) -> None:
        """Answer in a thread of its own, the connection waiting for its request's headers;
        if more than the cap wait, the one that has waited longest is closed."""
        with self._lock:
            self._waiting[id(request)] = request
            while len(self._waiting) > self._max_waiting:
                _, oldest = self._waiting.popitem(last=False)
                with suppress(OSError):  # its thread sees the end of its input and stops
                    oldest.shutdown(socket.SHUT_RDWR)
        try:
            super().process_request(request, client_address)
        except BaseException:
            self.arrived(request)
            raise

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self.arrived(request)  # one that never sent a request waits no more

    def arrived(self, request: Any) -> None:
        """``request``'s headers have arrived (or it ended): it no longer waits."""
        with self._lock:
            self._waiting.pop(id(request), None)

    def admit(self) -> bool:
        """Take a place for a connection whose request carried the token; False if none is
        free (the handler gives it back with :meth:`leave`)."""
        return self._slots.acquire(blocking=False)

    def leave(self) -> None:
        self._slots.release()

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return int(self.server_address[1])

    @property
    def url(self) -> str:
        """``http://127.0.0.1:PORT/``."""
        return f"http://{HOST}:{self.port}/"

    def address(self, entry: str = "") -> str:
        """The URL to open: ``entry`` (a path relative to the folder, with or without a query)
        on this server, with the run's token in its query."""
        separator = "&" if "?" in entry else "?"
        return f"{self.url}{entry}{separator}token={quote(self.token)}"

    @property
    def cookie(self) -> str:
        """The name of the cookie that carries the token (one per port)."""
        return f"tuckercodec-view-{self.port}"

    def authorised(self, query: str, cookies: str) -> tuple[bool, bool]:
        """Whether a request with this query and Cookie header carries the token, and whether
        it did so in its query (then it gets the cookie)."""
        given = parse_qs(query).get("token", [])
        if any(self._is_token(value) for value in given):
            return True, True
        return any(self._is_token(value) for value in cookie_values(cookies, self.cookie)), False

    def _is_token(self, value: str) -> bool:
        # as bytes: compare_digest refuses a str with characters beyond ASCII
        expected = self.token.encode()
        return secrets.compare_digest(value.encode("utf-8", "surrogateescape"), expected)

    def allowed_hosts(self) -> set[str]:
        """The ``Host`` headers this server answers: its own address, by number or name."""
        return {f"{HOST}:{self.port}", f"localhost:{self.port}"}

    def __enter__(self) -> ViewerServer:
        self._thread = threading.Thread(
            target=self.serve_forever,
            args=(POLL_SECONDS,),
            name="tuckercodec-view",
            daemon=True,
        )
        self._thread.start()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._thread is not None:
            self.shutdown()  # stops serve_forever and waits for it
            self._thread.join()
            self._thread = None
        self.server_close()

    def handle_error(self, request: object, client_address: object) -> None:
        """A browser that goes away mid-response is no error; anything else is reported."""
        if isinstance(sys.exception(), ConnectionError):
            return
        super().handle_error(request, client_address)  # type: ignore[arg-type]


def cookie_values(header: str, name: str) -> list[str]:
    """The values of the cookies called ``name`` in a Cookie header, found by splitting it on
    ``;`` and each part at its first ``=``: a part that is no cookie is skipped, not the
    header (``http.cookies`` gives up on the whole header at one cookie it cannot parse)."""
    values = []
    for part in header.split(";"):
        key, equals, value = part.partition("=")
        if equals and key.strip() == name:
            value = value.strip()
            if len(value) >= 2 and value[0] == value[-1] == '"':
                value = value[1:-1]
            values.append(value)
    return values


class _DeadlineReader(io.RawIOBase):
    """A handler's connection read raw, each read within what is left of its deadline."""

    def __init__(self, handler: _Handler):
        self.handler = handler

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        self.handler.before_read()
        return self.handler.connection.recv_into(buffer)


class _Handler(BaseHTTPRequestHandler):
    server: ViewerServer
    server_version = "tuckercodec-view"
    sys_version = ""

    #: When the request being read must have arrived (``time.monotonic``); None once it has.
    _deadline: float | None = None
    #: Whether the connection holds one of the server's places (a request carried the token).
    _admitted = False

    def setup(self) -> None:
        super().setup()
        # for every read and write: a client that stops sending is disconnected
        self.connection.settimeout(self.server.connection_timeout)
        # every read of the request checks what is left of its deadline first
        plain, self.rfile = self.rfile, io.BufferedReader(_DeadlineReader(self))
        plain.close()  # else it holds the socket open after the server closes it

    def handle_one_request(self) -> None:
        self._deadline = time.monotonic() + self.server.request_deadline
        super().handle_one_request()  # a TimeoutError while reading ends the connection
        if not self._admitted:  # refused, or no GET: it may not wait for another request
            self.close_connection = True

    def parse_request(self) -> bool:
        parsed = super().parse_request()  # the request line and the headers
        self._deadline = None  # arrived: the response has the plain timeout
        self.connection.settimeout(self.server.connection_timeout)
        self.server.arrived(self.request)
        return parsed

    def finish(self) -> None:
        try:
            super().finish()
        finally:
            if self._admitted:
                self._admitted = False
                self.server.leave()

    def before_read(self) -> None:
        """Cut the socket's timeout to what is left of the request's deadline, or end the
        connection (TimeoutError) if nothing is."""
        if self._deadline is None:
            return
        left = self._deadline - time.monotonic()
        if left <= 0:
            deadline = self.server.request_deadline
            raise TimeoutError(f"the request did not arrive within {deadline} s")
        self.connection.settimeout(min(self.server.connection_timeout, left))

    def do_GET(self) -> None:
        self._respond(body=True)

    def do_HEAD(self) -> None:
        self._respond(body=False)

    def _respond(self, body: bool) -> None:
        self._grant = False
        if self.headers.get("Host", "") not in self.server.allowed_hosts():
            self.send_error(HTTPStatus.FORBIDDEN, "unknown host")
            return
        parts = urlsplit(self.path)
        allowed, self._grant = self.server.authorised(parts.query, self.headers.get("Cookie", ""))
        if not allowed:
            self.send_error(HTTPStatus.FORBIDDEN, "open the URL tuckercodec view printed")
            return
        if not self._admitted:
            if not self.server.admit():
                self.send_error(HTTPStatus.SERVICE_UNAVAILABLE, "too many connections")
                return
            self._admitted = True
        path = self.server.routes.get(unquote(parts.path))
        if path is None:
            self.send_error(HTTPStatus.NOT_FOUND)
            return
        try:
            handle = path.open("rb")
        except OSError:
            self.send_error(HTTPStatus.NOT_FOUND)
            return
        with handle:
            size = path.stat().st_size
            self.send_response(HTTPStatus.OK)
            self.send_header("Content-Type", content_type(path.name))
            self.send_header("Content-Length", str(size))
            self.end_headers()
            if body:
                shutil.copyfileobj(handle, self.wfile, 1 << 20)

    def end_headers(self) -> None:
        # on every response, errors included
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Cross-Origin-Resource-Policy", "same-origin")
        self.send_header("Content-Security-Policy", self.server.policy)
        self.send_header("X-Frame-Options", "DENY")
        self.send_header("Referrer-Policy", "no-referrer")
        if getattr(self, "_grant", False):
            cookie = f"{self.server.cookie}={self.server.token}; Path=/; HttpOnly; SameSite=Strict"
            self.send_header("Set-Cookie", cookie)
        super().end_headers()

    def log_message(self, format: str, *args: object) -> None:
        """Quiet: the terminal shows the URL and the stop message, not every request."""
