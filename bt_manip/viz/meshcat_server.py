"""The meshcat server that ``--viz`` starts, bound to one address and tied to its run.

``python -m bt_manip.viz.meshcat_server --host 127.0.0.1`` runs meshcat's own server (its
ZeroMQ socket and its web server on free ports from 6000 and 7000) with two differences:

- both listen on ``--host`` only (meshcat's own command binds its web server to every
  interface): :class:`BoundBridge` passes the address to the web application's ``listen``;
- it exits when the process that started it is gone (checked twice a second), so a run that
  is killed leaves no server behind.

Like meshcat's command it prints ``zmq_url=...`` and ``web_url=...`` on its first two lines.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import threading
import time
import warnings
from typing import Any

PARENT_CHECK_S = 0.5


def _bridge_class() -> Any:
    with warnings.catch_warnings():  # meshcat imports a deprecated pyzmq module
        warnings.simplefilter("ignore", DeprecationWarning)
        from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class BoundBridge(ZMQWebSocketBridge):  # type: ignore[misc]
        """meshcat's bridge whose web server listens on ``host`` only."""

        def make_app(self) -> Any:
            app = super().make_app()
            listen = app.listen
            host = self.host

            def bound_listen(port: int, address: str = "", **kwargs: Any) -> Any:
                return listen(port, address=host, **kwargs)

            app.listen = bound_listen
            return app

    return BoundBridge


def _exit_with_parent(parent: int) -> None:
    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_CHECK_S)
        os._exit(0)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1")
    args = parser.parse_args(argv)
    _exit_with_parent(os.getppid())
    bridge = _bridge_class()(host=args.host)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    with contextlib.suppress(KeyboardInterrupt):
        bridge.run()
    sys.exit(0)


if __name__ == "__main__":
    main()
