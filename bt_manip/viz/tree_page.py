"""The live page: the 3D view beside the behaviour tree, served on localhost.

:class:`TreePageServer` serves, from a background thread:

``/``            the page (3D view from the meshcat server's websocket, the tree with statuses)
``/tree.json``   the tree's nodes (name, node ID, depth, parent)
``/state.json``  sim time, tick count, every node's status and reason, the run's result
``/static/...``  the page's own scripts and style

The server listens on 127.0.0.1 unless told another address (``--bind``), and reuses its
address (SO_REUSEADDR), so a second run soon after the first can serve on the same port while
the old connections wait out TIME_WAIT. The 3D view is the meshcat server's own page in a frame
(its websocket only accepts pages it served). The page polls ``/state.json`` a few times a
second; the run thread only swaps in a new snapshot after each tick
(:meth:`PageState.publish`), so serving never slows the run down.
"""

from __future__ import annotations

import errno
import json
import socket
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

STATIC_DIR = Path(__file__).resolve().parent / "static"
DEFAULT_PORT = 7080


def meshcat_bundle() -> Path:
    """The viewer bundle (three.js + meshcat) shipped with the meshcat package."""
    import importlib.util

    spec = importlib.util.find_spec("meshcat")  # located, not imported (it pulls in IPython)
    if spec is None or spec.origin is None:
        raise FileNotFoundError("the meshcat package is not installed")
    return Path(spec.origin).resolve().parent / "viewer" / "dist" / "main.min.js"


def render_page(title: str, config: dict[str, Any], scripts: str, view: str, timeline: str = "",
                follow: bool = False, css: str | None = None) -> str:
    """Fill the page template (shared by the live and the replay page).

    ``view`` is the 3D view's element, ``timeline`` the replay's controls, ``follow`` adds the
    follow-the-robot switch.
    """
    template = (STATIC_DIR / "page.html").read_text()
    css_text = css if css is not None else (STATIC_DIR / "page.css").read_text()
    config_text = json.dumps(config).replace("</", "<\\/")
    import html

    out = template.replace("@@CSS@@", css_text)
    out = out.replace("@@CONFIG@@", config_text)
    out = out.replace("@@TIMELINE@@", timeline)
    out = out.replace("@@VIEW@@", view)
    out = out.replace(
        "@@FOLLOW@@",
        '<label style="margin-left:auto"><input type="checkbox" id="follow"> follow robot</label>'
        if follow
        else "",
    )
    out = out.replace("@@TITLE@@", html.escape(title))
    return out.replace("@@SCRIPTS@@", scripts)


@dataclass
class PageState:
    """What the page shows; written by the run thread, read by the server threads."""

    title: str = "bt-manip"
    nodes: list[dict[str, Any]] = field(default_factory=list)
    config: dict[str, Any] = field(default_factory=dict)
    _state: bytes = b"{}"
    _lock: threading.Lock = field(default_factory=threading.Lock)
    version: int = 0

    def publish(self, time: float, ticks: int, statuses: list[int], reasons: list[str],
                result: str = "", failures: Sequence[tuple[float, int, str]] = ()) -> None:
        """Swap in the statuses after a tick (``failures``: recent (time, node, reason))."""
        self.version += 1
        data = json.dumps(
            {
                "version": self.version,
                "time": round(time, 4),
                "ticks": ticks,
                "statuses": statuses,
                "reasons": reasons,
                "result": result,
                "failures": [list(f) for f in failures],
            }
        ).encode()
        with self._lock:
            self._state = data

    def state_bytes(self) -> bytes:
        with self._lock:
            return self._state


class _Handler(BaseHTTPRequestHandler):
    server: _Server

    def log_message(self, format: str, *args: Any) -> None:  # quiet
        pass

    def _send(self, body: bytes, content_type: str, status: int = 200) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def do_GET(self) -> None:
        state = self.server.state
        route = self.path.split("?", 1)[0]
        try:
            if route in ("/", "/index.html"):
                host = (self.headers.get("Host") or "").rsplit(":", 1)[0]
                self._send(self.server.page(host), "text/html; charset=utf-8")
            elif route == "/state.json":
                self._send(state.state_bytes(), "application/json")
            elif route == "/tree.json":
                body = json.dumps({"title": state.title, "nodes": state.nodes}).encode()
                self._send(body, "application/json")
            elif route.startswith("/static/"):
                name = route[len("/static/") :]
                target = (STATIC_DIR / name).resolve()
                if target.parent != STATIC_DIR or not target.is_file():
                    self._send(b"not found", "text/plain", 404)
                    return
                kind = "text/javascript" if name.endswith(".js") else "text/css"
                self._send(target.read_bytes(), kind)
            else:
                self._send(b"not found", "text/plain", 404)
        except (BrokenPipeError, ConnectionResetError):
            pass


WILDCARDS = {"//0.0.0.0:": "127.0.0.1", "//[::]:": "[::1]"}


def reachable(url: str, host: str = "") -> str:
    """``url`` of a server listening on every interface (0.0.0.0, ::) as a browser reaches
    it: at ``host`` (the name the browser used for the page), else at the loopback address."""
    for wildcard, loopback in WILDCARDS.items():
        if wildcard in url:
            return url.replace(wildcard, f"//{host or loopback}:")
    return url


class PortUnavailable(OSError):
    """The page cannot listen where asked (port taken, or an address not on this machine).

    ``strerror`` says why and what to do; ``flag`` is the option to change (``--port`` or
    ``--bind``); ``in_use`` tells a taken port from the other reasons.
    """

    @property
    def in_use(self) -> bool:
        return self.errno == errno.EADDRINUSE

    @property
    def flag(self) -> str:
        bad_address = self.errno in (errno.EADDRNOTAVAIL, errno.EAFNOSUPPORT, None) or (
            self.errno is not None and self.errno < 0  # getaddrinfo failed
        )
        return "--bind" if bad_address else "--port"


def bind_problem(host: str, port: int, exc: OSError) -> str:
    """Why ``host:port`` cannot be listened on, and what to do, in one line."""
    if exc.errno == errno.EADDRINUSE:
        return (f"port {port} is in use on {host} (another bt-manip --viz?); choose another "
                "port, or 0 for any free one")
    if isinstance(exc, socket.gaierror) or exc.errno in (errno.EADDRNOTAVAIL, errno.EAFNOSUPPORT):
        return f"cannot listen on {host}: not an address of this machine ({exc.strerror or exc})"
    if exc.errno == errno.EACCES:
        return f"no permission to listen on port {port} (ports below 1024 need root)"
    return f"cannot listen on {host}:{port}: {exc.strerror or exc}"


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True  # SO_REUSEADDR: a port in TIME_WAIT can serve again at once

    def __init__(self, address: tuple[str, int], state: PageState) -> None:
        if ":" in address[0]:
            self.address_family = socket.AF_INET6
        super().__init__(address, _Handler)
        self.state = state

    def page(self, request_host: str = "") -> bytes:
        """The live page; a meshcat server listening on every address (0.0.0.0, ::) is
        reached at the host name the browser asked for."""
        import html

        scripts = (
            '<script src="static/common.js"></script>\n<script src="static/live.js"></script>'
        )
        url = reachable(str(self.state.config.get("meshcat_url", "")), request_host)
        src = html.escape(url, quote=True)
        view = f'<iframe id="meshcat-frame" src="{src}" title="3D view"></iframe>'
        return render_page(self.state.title, self.state.config, scripts, view).encode()


class TreePageServer:
    """Serve the live page on ``host:port`` (port 0 picks a free one) until :meth:`close`.

    Raises :class:`PortUnavailable` (with the reason) when it cannot listen there.
    """

    def __init__(self, state: PageState, port: int = DEFAULT_PORT, host: str = "127.0.0.1") -> None:
        self.state = state
        try:
            self._server = _Server((host, port), state)
        except OSError as exc:
            raise PortUnavailable(exc.errno, bind_problem(host, port, exc)) from None
        self.host = host
        self.port = int(self._server.server_address[1])
        self._thread = threading.Thread(
            target=self._server.serve_forever, kwargs={"poll_interval": 0.2},
            name="bt-manip-page", daemon=True,
        )
        self._thread.start()

    @property
    def url(self) -> str:
        """Where to open the page on this machine (loopback when serving every interface)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return reachable(f"http://{host}:{self.port}/")

    def close(self) -> None:
        self._server.shutdown()
        self._server.server_close()
        self._thread.join(timeout=5)
