"""A small client of the Chrome DevTools Protocol (CDP) for headless Chromium, over a pipe.
Longer than the usual 400 lines because it owns the browser's whole life, each step with its
deadline and its error: launching, talking, a browser that dies, and the clean-up.

The viewer's browser tests and the viewer benchmark (``tools/bench/viewer.py``) drive Debian's
``chromium`` with it; nothing is installed for it (no Playwright, no websocket library). Chromium
started with ``--remote-debugging-pipe`` reads CDP messages, JSON each ended by a NUL byte, on its
file descriptor 3 and writes its answers and events the same way on descriptor 4::

    with Browser.launch() as browser:
        page = browser.new_page("http://127.0.0.1:8000/viewer/index.html?file=...")
        page.evaluate("window.tkcViewer.ready")           # awaits a promise
        positions = page.typed_array("window.tkcViewer.drawnPositions()")
        png = page.screenshot()                            # png.decode_png(png)
        assert not page.problems()                         # console errors, exceptions

Every wait has a deadline (:class:`BrowserTimeout`), a browser that dies or closes its pipe
raises :class:`BrowserDied` with the end of its stderr, and closing (also on any error, the
``with`` block's exit) kills the browser's whole process group and removes its profile folder.
:func:`tests.support.png.decode_png` reads a screenshot into a numpy array.
"""

from __future__ import annotations

import base64
import contextlib
import fcntl
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

#: Where a chromium is looked for: Debian's path first, then these names on PATH.
CANDIDATES = ("/usr/bin/chromium", "chromium", "chromium-browser", "google-chrome")

#: The flags every launch gets. Headless, no first-run or background work: the closed network
#: here refuses the connections Chromium makes on its own (updates, sync, QUIC probes). WebGL
#: runs on SwiftShader (ANGLE's CPU Vulkan), the one GL a machine without a GPU has.
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-default-apps",
    "--disable-extensions",
    "--no-first-run",
    "--no-default-browser-check",
    "--disable-quic",
    "--disable-dev-shm-usage",
    "--mute-audio",
    "--disable-crash-reporter",
    # a page measured for its frame rate must not be slowed down as a "background" page
    "--disable-background-timer-throttling",
    "--disable-renderer-backgrounding",
    "--disable-backgrounding-occluded-windows",
    "--hide-scrollbars",
)

#: Seconds any single wait may take unless the caller says otherwise.
DEFAULT_TIMEOUT = 30.0


class BrowserError(RuntimeError):
    """The browser could not be driven: it failed to start, refused a call, or a script threw."""


class BrowserTimeout(BrowserError):
    """A call or a wait did not finish within its deadline."""


class BrowserDied(BrowserError):
    """The browser exited or closed its end of the pipe."""


def find_chromium() -> str | None:
    """The path of a Chromium to run (see :data:`CANDIDATES`), or None."""
    for name in CANDIDATES:
        path = name if os.path.isabs(name) and os.access(name, os.X_OK) else shutil.which(name)
        if path:
            return path
    return None


@dataclass(frozen=True)
class ConsoleEntry:
    """One message the page produced: ``source`` is ``console`` (console.log and friends),
    ``exception`` (an uncaught exception or rejection) or ``log`` (the browser's own log:
    network failures, security violations...); ``level`` is e.g. ``log``, ``warning``,
    ``error``."""

    source: str
    level: str
    text: str

    @property
    def is_error(self) -> bool:
        """An error or an exception (warnings and logs are not)."""
        return self.source == "exception" or self.level in ("error", "assert")


@dataclass
class Page:
    """A tab, attached by a flattened CDP session; made by :meth:`Browser.new_page`."""

    browser: Browser
    target_id: str
    session_id: str
    console: list[ConsoleEntry] = field(default_factory=list)

    def call(self, method: str, params: dict[str, Any] | None = None, **kw: Any) -> Any:
        """A CDP command in this page's session (see :meth:`Browser.call`)."""
        return self.browser.call(method, params, session_id=self.session_id, **kw)

    def goto(self, url: str, timeout: float = DEFAULT_TIMEOUT) -> None:
        """Navigate to ``url`` and wait for its load event (module scripts have run by then)."""
        self.browser.pop_events(self.session_id, "Page.loadEventFired")
        answer = self.call("Page.navigate", {"url": url}, timeout=timeout)
        if answer.get("errorText"):
            raise BrowserError(f"could not open {url}: {answer['errorText']}")
        self.browser.wait_event(self.session_id, "Page.loadEventFired", timeout)

    def evaluate(self, expression: str, timeout: float = DEFAULT_TIMEOUT) -> Any:
        """The value of a JavaScript expression (a promise is awaited), as JSON gives it.

        Raises:
            BrowserError: the expression threw or its promise rejected (the message says what).
        """
        answer = self.call(
            "Runtime.evaluate",
            {
                "expression": expression,
                "awaitPromise": True,
                "returnByValue": True,
                "userGesture": True,
                "timeout": int(timeout * 1000),
            },
            timeout=timeout + 2.0,  # the browser's own deadline first
        )
        details = answer.get("exceptionDetails")
        if details is not None:
            thrown = details.get("exception", {})
            message = thrown.get("description") or thrown.get("value") or details.get("text")
            raise BrowserError(f"{expression[:200]!r} threw: {message}")
        return answer["result"].get("value")

    def typed_array(self, expression: str, timeout: float = DEFAULT_TIMEOUT) -> np.ndarray:
        """A typed array the expression gives (or its promise), exactly: its bytes travel as
        base64 (a JSON number would round a float, and a typed array by value is an object of
        index keys)."""
        script = (
            "(async () => { const a = await (" + expression + ");"
            " const b = new Uint8Array(a.buffer, a.byteOffset, a.byteLength); let s = '';"
            " for (let i = 0; i < b.length; i += 0x8000)"
            " s += String.fromCharCode.apply(null, b.subarray(i, i + 0x8000));"
            " return {type: a.constructor.name, data: btoa(s)}; })()"
        )
        got = self.evaluate(script, timeout)
        dtype = _TYPED_ARRAYS.get(got["type"])
        if dtype is None:
            raise BrowserError(f"{expression!r} gave a {got['type']}, not a typed array")
        return np.frombuffer(base64.b64decode(got["data"]), dtype=dtype)

    def wait_for(self, expression: str, timeout: float = DEFAULT_TIMEOUT) -> Any:
        """Poll until the expression is truthy; its value."""
        deadline = time.monotonic() + timeout
        while True:
            value = self.evaluate(expression, timeout)
            if value:
                return value
            if time.monotonic() > deadline:
                raise BrowserTimeout(f"{expression!r} still false after {timeout} s")
            time.sleep(0.05)

    def screenshot(
        self,
        clip: tuple[float, float, float, float] | None = None,
        timeout: float = DEFAULT_TIMEOUT,
    ) -> bytes:
        """The page's viewport, or the ``clip`` rectangle of it (x, y, width, height in CSS
        pixels), as PNG bytes."""
        params: dict[str, Any] = {"format": "png"}
        if clip is not None:
            x, y, width, height = clip
            params["clip"] = {"x": x, "y": y, "width": width, "height": height, "scale": 1}
        answer = self.call("Page.captureScreenshot", params, timeout=timeout)
        return base64.b64decode(answer["data"])

    def problems(self) -> list[ConsoleEntry]:
        """The errors and exceptions seen so far (after draining pending events)."""
        self.browser.pump(0.0)
        return [entry for entry in self.console if entry.is_error]

    def close(self) -> None:
        """Close the tab."""
        self.browser.call("Target.closeTarget", {"targetId": self.target_id})


_TYPED_ARRAYS = {
    "Float32Array": "<f4",
    "Float64Array": "<f8",
    "Int8Array": "i1",
    "Uint8Array": "u1",
    "Uint8ClampedArray": "u1",
    "Int16Array": "<i2",
    "Uint16Array": "<u2",
    "Int32Array": "<i4",
    "Uint32Array": "<u4",
}


class Browser:
    """A running headless Chromium; make one with :meth:`launch` and use it as a context
    manager (or call :meth:`close`, which is idempotent)."""

    def __init__(self, process: subprocess.Popen[bytes], writer: int, reader: int, home: Path):
        self.process = process
        #: The temporary folder of the profile and the browser's stderr, removed by close().
        self.home = home
        self._writer = writer
        self._reader = reader
        self._buffer = b""
        self._next_id = 0
        self._answers: dict[int, dict[str, Any]] = {}
        self._events: list[dict[str, Any]] = []
        self._pages: dict[str, Page] = {}
        self._closed = False

    # -- life ------------------------------------------------------------------------------

    @classmethod
    def launch(
        cls,
        executable: str | None = None,
        *,
        width: int = 1024,
        height: int = 768,
        extra_flags: tuple[str, ...] = (),
        timeout: float = DEFAULT_TIMEOUT,
    ) -> Browser:
        """Start Chromium (``executable``, else :func:`find_chromium`) with a fresh profile in a
        temporary folder and a ``width`` x ``height`` window, and wait until it answers.

        Raises:
            BrowserError: no chromium, or it did not start (its stderr is in the message).
        """
        executable = executable or find_chromium()
        if executable is None:
            raise BrowserError(f"no chromium found (looked for {', '.join(CANDIDATES)})")
        if shutil.which(executable) is None:
            raise BrowserError(f"{executable}: no such executable")
        home = Path(tempfile.mkdtemp(prefix="tuckercodec-chromium-"))
        ours: list[int] = []
        try:
            # at 10 or above, so that placing one at 3 or 4 cannot overwrite the other
            to_browser = [_high(fd, ours) for fd in os.pipe()]
            from_browser = [_high(fd, ours) for fd in os.pipe()]
            flags = [
                *FLAGS,
                "--remote-debugging-pipe",
                f"--user-data-dir={home / 'profile'}",
                f"--window-size={width},{height}",
                *extra_flags,
                "about:blank",
            ]
            # subprocess cannot place a descriptor at a given number (and dash's redirections
            # take one digit only): a tiny Python moves them to 3 and 4, then becomes the browser
            with open(home / "stderr.txt", "wb") as stderr:
                process = subprocess.Popen(
                    [
                        sys.executable,
                        "-I",
                        "-S",
                        "-c",
                        _TRAMPOLINE,
                        str(to_browser[0]),
                        str(from_browser[1]),
                        executable,
                        *flags,
                    ],
                    stdin=subprocess.DEVNULL,
                    stdout=stderr,
                    stderr=stderr,
                    pass_fds=(to_browser[0], from_browser[1]),
                    start_new_session=True,  # its own process group: close() kills them all
                )
        except BaseException:
            for fd in ours:
                os.close(fd)
            shutil.rmtree(home, ignore_errors=True)
            raise
        os.close(to_browser[0])
        os.close(from_browser[1])
        browser = cls(process, to_browser[1], from_browser[0], home)
        try:
            browser.call("Browser.getVersion", timeout=timeout)
        except BaseException:
            browser.close()
            raise
        return browser

    def close(self) -> None:
        """Stop the browser (politely, then by killing its process group) and remove its
        profile. Safe to call twice and on a browser that already died."""
        if self._closed:
            return
        self._closed = True
        if self.process.poll() is None:
            with contextlib.suppress(BrowserError, OSError):
                self._send(self._next_id + 1, "Browser.close", {}, None)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout=5)
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, signal.SIGKILL)  # renderers and helpers too
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.process.wait(timeout=10)
        for fd in (self._writer, self._reader):
            with contextlib.suppress(OSError):
                os.close(fd)
        shutil.rmtree(self.home, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def stderr_tail(self, size: int = 3000) -> str:
        """The end of what the browser wrote on stderr (and stdout)."""
        try:
            data = (self.home / "stderr.txt").read_bytes()
        except OSError:
            return ""
        return data[-size:].decode("utf-8", "replace")

    # -- protocol --------------------------------------------------------------------------

    def call(
        self,
        method: str,
        params: dict[str, Any] | None = None,
        *,
        session_id: str | None = None,
        timeout: float = DEFAULT_TIMEOUT,
    ) -> Any:
        """Send a CDP command and return its result.

        Raises:
            BrowserError: the browser answered with an error.
            BrowserTimeout: no answer within ``timeout`` seconds.
            BrowserDied: the browser is gone.
        """
        if self._closed:
            raise BrowserError(f"{method}: the browser is closed")
        self._next_id += 1
        number = self._next_id
        self._send(number, method, params or {}, session_id)
        deadline = time.monotonic() + timeout
        while number not in self._answers:
            left = deadline - time.monotonic()
            if left <= 0:
                raise BrowserTimeout(f"{method}: no answer within {timeout} s")
            self.pump(left)
        answer = self._answers.pop(number)
        if "error" in answer:
            raise BrowserError(f"{method}: {answer['error'].get('message', answer['error'])}")
        return answer.get("result", {})

    def new_page(self, url: str | None = None, timeout: float = DEFAULT_TIMEOUT) -> Page:
        """A new tab, its console recorded from the start; at ``url`` when given (loaded)."""
        target = self.call("Target.createTarget", {"url": "about:blank"}, timeout=timeout)
        target_id = target["targetId"]
        attached = self.call(
            "Target.attachToTarget", {"targetId": target_id, "flatten": True}, timeout=timeout
        )
        page = Page(self, target_id, attached["sessionId"])
        self._pages[page.session_id] = page
        for domain in ("Page", "Runtime", "Log"):
            page.call(f"{domain}.enable", timeout=timeout)
        if url is not None:
            page.goto(url, timeout)
        return page

    def version(self) -> dict[str, Any]:
        """``Browser.getVersion``: product, revision, userAgent..."""
        return dict(self.call("Browser.getVersion"))

    def wait_event(self, session_id: str | None, method: str, timeout: float) -> dict[str, Any]:
        """The params of the next event ``method`` of the session (None: the browser's)."""
        deadline = time.monotonic() + timeout
        while True:
            for event in self.pop_events(session_id, method)[:1]:
                return dict(event.get("params", {}))
            left = deadline - time.monotonic()
            if left <= 0:
                raise BrowserTimeout(f"no {method} within {timeout} s")
            self.pump(min(left, 0.5))

    def pop_events(self, session_id: str | None, method: str) -> list[dict[str, Any]]:
        """Remove and return the events ``method`` of a session received so far."""
        taken = [
            e for e in self._events if e["method"] == method and e.get("sessionId") == session_id
        ]
        self._events = [e for e in self._events if not any(e is t for t in taken)]
        return taken

    def pump(self, timeout: float) -> None:
        """Read what the browser has written, waiting at most ``timeout`` s for something."""
        ready, _, _ = select.select([self._reader], [], [], max(timeout, 0.0))
        while ready:
            try:
                chunk = os.read(self._reader, 1 << 20)
            except OSError as error:
                raise self._died(f"reading its pipe failed: {error}") from error
            if not chunk:
                raise self._died("it closed its end of the pipe")
            self._buffer += chunk
            ready, _, _ = select.select([self._reader], [], [], 0)
        *messages, self._buffer = self._buffer.split(b"\0")
        for raw in messages:
            self._dispatch(json.loads(raw))

    def _dispatch(self, message: dict[str, Any]) -> None:
        if "id" in message:
            self._answers[message["id"]] = message
            return
        page = self._pages.get(message.get("sessionId", ""))
        entry = _console_entry(message) if page is not None else None
        if entry is not None and page is not None:
            page.console.append(entry)
        elif message.get("method") == "Page.loadEventFired" or page is None:
            self._events.append(message)
            del self._events[:-1000]  # nobody waits for old events; keep memory bounded

    def _send(
        self, number: int, method: str, params: dict[str, Any], session_id: str | None
    ) -> None:
        message: dict[str, Any] = {"id": number, "method": method, "params": params}
        if session_id is not None:
            message["sessionId"] = session_id
        data = json.dumps(message).encode() + b"\0"
        try:
            while data:
                _, writable, _ = select.select([], [self._writer], [], DEFAULT_TIMEOUT)
                if not writable:
                    raise BrowserTimeout(f"{method}: the browser does not read its pipe")
                data = data[os.write(self._writer, data) :]
        except (BrokenPipeError, OSError) as error:
            if isinstance(error, BrowserError):
                raise
            raise self._died(f"writing {method} failed: {error}") from error

    def _died(self, why: str) -> BrowserDied:
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.process.wait(timeout=2)
        code = self.process.poll()
        state = "is still running" if code is None else f"exited with status {code}"
        return BrowserDied(f"chromium {state}: {why}\n{self.stderr_tail()}")


#: Runs in the child: the pipe's ends to 3 and 4 (dup2 makes them inheritable), then exec.
_TRAMPOLINE = (
    "import os, sys; r, w = int(sys.argv[1]), int(sys.argv[2]); os.dup2(r, 3); os.dup2(w, 4); "
    "os.close(r); os.close(w); os.execv(sys.argv[3], sys.argv[3:])"
)


def _high(fd: int, ours: list[int]) -> int:
    """``fd`` moved to a descriptor numbered 10 or above (close-on-exec)."""
    ours.append(fd)
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10)
    ours.append(moved)
    os.close(fd)
    ours.remove(fd)
    return moved


def _console_entry(message: dict[str, Any]) -> ConsoleEntry | None:
    method, params = message.get("method"), message.get("params", {})
    if method == "Runtime.consoleAPICalled":
        text = " ".join(_remote_text(arg) for arg in params.get("args", []))
        return ConsoleEntry("console", str(params.get("type", "log")), text)
    if method == "Runtime.exceptionThrown":
        details = params.get("exceptionDetails", {})
        thrown = details.get("exception", {})
        text = thrown.get("description") or details.get("text", "exception")
        return ConsoleEntry("exception", "error", str(text))
    if method == "Log.entryAdded":
        entry = params.get("entry", {})
        text = f"{entry.get('text', '')} {entry.get('url', '')}".strip()
        return ConsoleEntry("log", str(entry.get("level", "info")), text)
    return None


def _remote_text(value: dict[str, Any]) -> str:
    if "value" in value:
        return str(value["value"])
    return str(value.get("description") or value.get("unserializableValue") or value.get("type"))
