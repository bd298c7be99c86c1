"""The live page: the 3D view beside the behaviour tree, served on localhost.

:class:`TreePageServer` serves, from a background thread:

``/``            the page (3D view from the meshcat server's websocket, the tree with statuses)
``/tree.json``   the tree's nodes (name, node ID, depth, parent)
``/state.json``  sim time, tick count, every node's status and reason, the run's result
``/static/...``  the page's own scripts and style

The 3D view is the meshcat server's own page in a frame (its websocket only accepts pages it
served). The page polls ``/state.json`` a few times a second; the run thread only swaps in a new
snapshot after each tick (:meth:`PageState.publish`), so serving never slows the run down.
"""

from __future__ import annotations

import json
import threading
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
                result: str = "", failures: list[tuple[float, int, str]] = ()) -> None:
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
                self._send(self.server.page(), "text/html; charset=utf-8")
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


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = False

    def __init__(self, address: tuple[str, int], state: PageState) -> None:
        super().__init__(address, _Handler)
        self.state = state

    def page(self) -> bytes:
        import html

        scripts = (
            '<script src="static/common.js"></script>\n<script src="static/live.js"></script>'
        )
        src = html.escape(str(self.state.config.get("meshcat_url", "")), quote=True)
        view = f'<iframe id="meshcat-frame" src="{src}" title="3D view"></iframe>'
        return render_page(self.state.title, self.state.config, scripts, view).encode()


class TreePageServer:
    """Serve the live page on ``host:port`` (port 0 picks a free one) until :meth:`close`.

    Raises OSError when the port is taken.
    """

    def __init__(self, state: PageState, port: int = DEFAULT_PORT, host: str = "127.0.0.1") -> None:
        self.state = state
        self._server = _Server((host, port), state)
        self.host = host
        self.port = int(self._server.server_address[1])
        self._thread = threading.Thread(
            target=self._server.serve_forever, kwargs={"poll_interval": 0.2},
            name="bt-manip-page", daemon=True,
        )
        self._thread.start()

    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}/"

    def close(self) -> None:
        self._server.shutdown()
        self._server.server_close()
        self._thread.join(timeout=5)
