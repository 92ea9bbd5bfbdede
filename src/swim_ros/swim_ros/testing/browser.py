"""A real browser in a test.

A folder served over HTTP on loopback, headless Chromium opening a page of it, and the text of the page's elements read
through the Chrome DevTools Protocol (CDP).

- ``serve_folder(folder)``: an HTTP server of one folder on 127.0.0.1 at a free port, in a thread; its base URL.
- ``HeadlessChromium()``: Debian's chromium, headless, started through ``swim_ros.processes.start_child`` (it dies
  with its starter) with a user profile of its own, ended with everything it started when the block ends.
  ``open_page(url)`` gives a ``Page`` whose ``evaluate(expression)`` runs JavaScript in it and ``element_text(id)``
  reads an element; ``wait_for_element_json(id, accept, timeout_s)`` waits until an element holds JSON that
  ``accept`` takes.
- ``LatestMessagePage`` and ``latest_page_value(page_dir, ws_url, topic)``: the swim_viz test page
  (src/swim_viz/test/browser: the Foxglove WebSocket protocol's JavaScript client, subscribed to one topic) and the
  latest message it shows, as a dict.
- ``browser_unavailable(page_dir)``: why such a test cannot run here (no chromium, no bundled page, no
  websockets library), or None; a test skips with that reason.
Nothing here knows ROS: the page reads any foxglove.websocket.v1 server whose channel carries CDR with a ros2msg
schema.
"""
from __future__ import annotations

import contextlib
import functools
import http.server
import itertools
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import threading
import time
import urllib.parse
from collections import deque
from pathlib import Path
from typing import Any, Callable, Iterator, Optional

from swim_ros.processes import start_child

#: the browser's executables, in the order they are looked for: Debian's package installs /usr/bin/chromium
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")
#: what Chromium prints on stderr once its DevTools endpoint listens (with --remote-debugging-port)
DEVTOOLS_LINE = re.compile(r"DevTools listening on (ws://\S+)")
#: Chromium's start to its DevTools line: about a second here; 30 s covers a cold start on a loaded 2-core host
BROWSER_START_TIMEOUT_S = 30.0
#: a CDP command's reply (open a page, evaluate an expression): milliseconds; 20 s covers a loaded host
CDP_REPLY_TIMEOUT_S = 20.0
#: how long the browser has to end after SIGTERM (it closes its renderers and profile) before its process group is
#: killed: a second or less; 5 s margin
BROWSER_STOP_GRACE_S = 5.0
#: how often a wait for a page's element looks again: 50 ms, a few CDP round trips a period at most
PAGE_POLL_PERIOD_S = 0.05
#: how many of the browser's last stderr lines are kept to explain a failure
STDERR_LINES_KEPT = 40
#: the name of serve_folder's thread (in a stack dump of a hung test)
HTTP_THREAD_NAME = "serve_folder"
#: the page's element that holds the latest message (JSON) and the one that says what it is doing
LATEST_ELEMENT_ID = "latest"
STATUS_ELEMENT_ID = "status"
#: the page's script, bundled by scripts/setup.sh (npm ci, esbuild) beside index.html
PAGE_BUNDLE = Path("dist") / "page.js"
#: the first message through a fresh browser, page, connection and subscription: about a second here; 30 s covers
#: a loaded host
LATEST_VALUE_TIMEOUT_S = 30.0


class BrowserError(RuntimeError):
    """The browser did not start, a CDP command failed, or a page did not show what was waited for.

    The message says what the page's status element said.
    """


def find_chromium() -> Optional[str]:
    """The path of a Chromium executable on PATH, or None."""
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path is not None:
            return path
    return None


def browser_unavailable(page_dir: Optional[Path] = None) -> Optional[str]:
    """Why a browser test cannot run on this machine (for pytest.skip), or None.

    No Chromium on PATH, the websockets library missing, or page_dir's bundled script not built.
    """
    if find_chromium() is None:
        return ("no chromium on PATH: scripts/setup.sh installs Debian's chromium when run as root with apt "
                "(apt-get install chromium)")
    try:
        import websockets.sync.client  # noqa: F401
    except ImportError:
        return "the websockets library is not installed (pip install websockets): the DevTools client needs it"
    if page_dir is not None and not (page_dir / PAGE_BUNDLE).is_file():
        return (f"the page's bundle {page_dir / PAGE_BUNDLE} is not built: scripts/setup.sh builds it with npm "
                "(is npm installed?)")
    return None


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    """A static file handler that logs nothing (a test's output stays its own) and lets no page be cached."""

    def log_message(self, format: str, *args: Any) -> None:
        pass

    def end_headers(self) -> None:
        self.send_header("Cache-Control", "no-store")
        super().end_headers()


@contextlib.contextmanager
def serve_folder(folder: Path) -> Iterator[str]:
    """The folder served over HTTP on 127.0.0.1 at a free port by a thread of this process, while the block runs.

    Its base URL (http://127.0.0.1:PORT/). The server is shut down and its socket closed when the block ends.
    """
    handler = functools.partial(_QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, name=HTTP_THREAD_NAME, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


class Page:
    """One page (a CDP target) of a HeadlessChromium, driven over the browser's DevTools connection."""

    def __init__(self, browser: HeadlessChromium, target_id: str, session_id: str) -> None:
        self._browser = browser
        self.target_id = target_id
        self.session_id = session_id

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page (JSON-able values; None for undefined and null).

        BrowserError if it throws.
        """
        reply = self._browser.command("Runtime.evaluate", {"expression": expression, "returnByValue": True},
                                      session_id=self.session_id)
        if "exceptionDetails" in reply:
            details = reply["exceptionDetails"]
            raise BrowserError(f"{expression!r} threw: {details.get('exception', {}).get('description', details)}")
        return reply.get("result", {}).get("value")

    def element_text(self, element_id: str) -> Optional[str]:
        """The text of the page's element of that id, or None where there is none (yet)."""
        return self.evaluate(f"document.getElementById({json.dumps(element_id)})?.textContent ?? null")

    def wait_for_element_json(self, element_id: str, accept: Callable[[Any], bool], timeout_s: float,
                              status_element_id: Optional[str] = None) -> Any:
        """The JSON value of the element's text as soon as accept(value) is true, looking every PAGE_POLL_PERIOD_S.

        BrowserError after timeout_s, with the last text seen and the status element's text if one is named.
        """
        deadline = time.monotonic() + timeout_s
        text: Optional[str] = None
        while True:
            text = self.element_text(element_id)
            if text:
                try:
                    value = json.loads(text)
                except ValueError:
                    value = None
                if value is not None and accept(value):
                    return value
            if time.monotonic() >= deadline:
                status = self.element_text(status_element_id) if status_element_id else None
                raise BrowserError(f"#{element_id} did not hold an accepted value within {timeout_s} s "
                                   f"(last: {text!r}; status: {status!r})")
            time.sleep(PAGE_POLL_PERIOD_S)


class HeadlessChromium:
    """Headless Chromium with a profile of its own in a temporary folder, driven over its DevTools WebSocket.

    It talks to the browser endpoint, and to pages through Target.attachToTarget's flat sessions. Use as a context
    manager: everything it started, and the profile, is gone when the block ends, however it ends.
    """

    def __init__(self, executable: Optional[str] = None) -> None:
        self.executable = executable or find_chromium()
        if self.executable is None:
            raise BrowserError(browser_unavailable() or "no chromium")
        self._process: Optional[subprocess.Popen[bytes]] = None
        self._profile: Optional[tempfile.TemporaryDirectory[str]] = None
        self._connection: Any = None
        self._stderr_lines: deque[str] = deque(maxlen=STDERR_LINES_KEPT)
        self._devtools_url: Optional[str] = None
        self._devtools_ready = threading.Event()
        self._stderr_thread: Optional[threading.Thread] = None
        self._command_ids = itertools.count(1)

    def __enter__(self) -> HeadlessChromium:
        """Start the browser; on a failure, end what was started and re-raise."""
        try:
            self._start()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc_info: Any) -> None:
        """End the browser and remove its profile (close)."""
        self.close()

    def _start(self) -> None:
        from websockets.sync.client import connect

        self._profile = tempfile.TemporaryDirectory(prefix="swim-chromium-")
        assert self.executable is not None   # __init__ refused a machine without one
        command = [self.executable, "--headless=new", "--no-sandbox", "--remote-debugging-port=0",
                   f"--user-data-dir={self._profile.name}", "--no-first-run", "--no-default-browser-check",
                   "--disable-extensions", "--disable-background-networking", "--disable-component-update",
                   "--disable-sync", "--disable-gpu", "--mute-audio", "about:blank"]
        # its own process group: the renderers and helpers it starts end with it (close kills the group)
        self._process = start_child(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                    stderr=subprocess.PIPE, start_new_session=True)
        self._stderr_thread = threading.Thread(target=self._read_stderr, name="chromium-stderr", daemon=True)
        self._stderr_thread.start()
        if not self._devtools_ready.wait(BROWSER_START_TIMEOUT_S) or self._devtools_url is None:
            raise BrowserError(f"chromium printed no DevTools endpoint within {BROWSER_START_TIMEOUT_S} s "
                               f"(exit status {self._process.poll()}); its stderr:\n{self.stderr_tail()}")
        self._connection = connect(self._devtools_url, max_size=None, open_timeout=CDP_REPLY_TIMEOUT_S,
                                   close_timeout=BROWSER_STOP_GRACE_S)

    def _read_stderr(self) -> None:
        """Reads the browser's stderr to its end (so the pipe never fills).

        The DevTools endpoint, and the last lines for a failure's message.
        """
        assert self._process is not None and self._process.stderr is not None
        for raw in self._process.stderr:
            line = raw.decode(errors="replace").rstrip()
            self._stderr_lines.append(line)
            match = DEVTOOLS_LINE.search(line)
            if match and self._devtools_url is None:
                self._devtools_url = match.group(1)
                self._devtools_ready.set()
        self._devtools_ready.set()   # ended without one: the start's wait returns now

    def stderr_tail(self) -> str:
        """The last lines the browser wrote to stderr, for a failure's message."""
        return "\n".join(self._stderr_lines)

    def command(self, method: str, params: Optional[dict[str, Any]] = None, session_id: Optional[str] = None,
                timeout_s: float = CDP_REPLY_TIMEOUT_S) -> dict[str, Any]:
        """A CDP command's result (to the browser, or to a page's session), skipping the events that come between.

        BrowserError for an error reply or none within timeout_s.
        """
        if self._connection is None:
            raise BrowserError("the browser is not running")
        command_id = next(self._command_ids)
        message: dict[str, Any] = {"id": command_id, "method": method, "params": params or {}}
        if session_id is not None:
            message["sessionId"] = session_id
        self._connection.send(json.dumps(message))
        deadline = time.monotonic() + timeout_s
        while True:
            remaining_s = deadline - time.monotonic()
            if remaining_s <= 0:
                raise BrowserError(f"no reply to {method} within {timeout_s} s")
            try:
                reply = json.loads(self._connection.recv(timeout=remaining_s))
            except TimeoutError:
                continue
            if reply.get("id") != command_id:
                continue   # an event, or the reply to an earlier command given up on
            if "error" in reply:
                raise BrowserError(f"{method} failed: {reply['error']}")
            return reply.get("result", {})

    def open_page(self, url: str) -> Page:
        """A new page (tab) loading url, attached for commands."""
        target_id = self.command("Target.createTarget", {"url": url})["targetId"]
        session_id = self.command("Target.attachToTarget", {"targetId": target_id, "flatten": True})["sessionId"]
        return Page(self, target_id, session_id)

    def close(self) -> None:
        """Ends the DevTools connection and the browser, and removes its profile.

        The browser gets SIGTERM, then SIGKILL to its whole process group after BROWSER_STOP_GRACE_S. Safe to call more
        than once.
        """
        if self._connection is not None:
            with contextlib.suppress(Exception):
                self._connection.close()
            self._connection = None
        if self._process is not None:
            process, self._process = self._process, None
            with contextlib.suppress(ProcessLookupError):
                process.terminate()
            try:
                process.wait(BROWSER_STOP_GRACE_S)
            except subprocess.TimeoutExpired:
                pass
            # whatever of its group is left (renderers, zygotes; the browser itself if it did not stop)
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            if self._stderr_thread is not None:
                self._stderr_thread.join(BROWSER_STOP_GRACE_S)
            if process.stderr is not None:
                process.stderr.close()
        if self._profile is not None:
            self._profile.cleanup()
            self._profile = None


class LatestMessagePage:
    """The swim_viz test page of page_dir (index.html and its bundle) in headless Chromium.

    Connected to the foxglove.websocket.v1 server at ws_url and subscribed to topic; field picks the value it shows (a
    dotted path; by default the message's first float64 scalar). Use as a context manager; ``latest(...)`` reads what it
    shows as often as wanted.
    """

    def __init__(self, page_dir: Path, ws_url: str, topic: str, field: Optional[str] = None) -> None:
        self.page_dir = Path(page_dir)
        self.query = {"url": ws_url, "topic": topic} | ({"field": field} if field else {})
        self._stack = contextlib.ExitStack()
        self.page: Optional[Page] = None

    def __enter__(self) -> LatestMessagePage:
        """Serve page_dir, start the browser and open the page; on a failure, end what was started."""
        try:
            base_url = self._stack.enter_context(serve_folder(self.page_dir))
            browser = self._stack.enter_context(HeadlessChromium())
            self.page = browser.open_page(f"{base_url}index.html?{urllib.parse.urlencode(self.query)}")
        except BaseException:
            self._stack.close()
            raise
        return self

    def __exit__(self, *exc_info: Any) -> None:
        """End the browser and the page's server."""
        self._stack.close()

    def status(self) -> Optional[str]:
        """What the page says it is doing ("subscribed to ...", "error: ...")."""
        assert self.page is not None, "LatestMessagePage used outside its with block"
        return self.page.element_text(STATUS_ELEMENT_ID)

    def latest(self, timeout_s: float = LATEST_VALUE_TIMEOUT_S,
               accept: Callable[[dict[str, Any]], bool] = lambda shown: True) -> dict[str, Any]:
        """The latest message the page shows, once it has shown one that accept takes.

        A dict {"topic", "field", "sec", "nanosec", "value", "count"} (sec and nanosec: its header.stamp, None without a
        header). BrowserError after timeout_s, with the page's status.
        """
        assert self.page is not None, "LatestMessagePage used outside its with block"
        return self.page.wait_for_element_json(
            LATEST_ELEMENT_ID, lambda shown: isinstance(shown, dict) and shown.get("count", 0) > 0 and accept(shown),
            timeout_s, status_element_id=STATUS_ELEMENT_ID)


def latest_page_value(page_dir: Path, ws_url: str, topic: str, timeout_s: float = LATEST_VALUE_TIMEOUT_S,
                      field: Optional[str] = None) -> dict[str, Any]:
    """The first message of topic that the test page of page_dir shows in a real browser connected to ws_url.

    See LatestMessagePage.latest. The browser and the page's server are gone when it returns.
    """
    with LatestMessagePage(page_dir, ws_url, topic, field) as page:
        return page.latest(timeout_s)
