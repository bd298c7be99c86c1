"""Serving like a good citizen: loopback by default, ports reused and checked, nothing left
running after SIGTERM, the view kept up on request."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from bt_manip.cli import main
from bt_manip.viz.live import LiveOptions, LiveViewer
from bt_manip.viz.tree_page import PageState, TreePageServer

REPO = Path(__file__).resolve().parents[2]
DEMO = str(REPO / "trees" / "builtins_demo.xml")


def _listening(port: int) -> set[str]:
    """Addresses listening on TCP ``port`` (from /proc/net/tcp): '127.0.0.1', '0.0.0.0'..."""
    out = set()
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        addr, hex_port = local.split(":")
        if state == "0A" and int(hex_port, 16) == port:  # 0A: LISTEN
            out.add(socket.inet_ntoa(bytes.fromhex(addr)[::-1]))
    return out


def _port_of(url: str) -> int:
    match = re.search(r":(\d+)", url.split("//", 1)[-1])
    assert match, url
    return int(match.group(1))


def _free(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) != 0


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (from /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _all_gone(pids: list[int], timeout: float = 10.0) -> bool:
    """Whether every process has exited, waiting up to ``timeout`` s on a busy machine."""
    deadline = time.monotonic() + timeout
    while not all(_gone(pid) for pid in pids):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def _gone(pid: int) -> bool:
    """The process has exited (and is not a zombie waiting to be reaped)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return True
    return state == "Z"


def test_a_second_server_serves_at_once_on_a_port_in_time_wait() -> None:
    first = TreePageServer(PageState(), port=0)
    port = first.port
    with urllib.request.urlopen(first.url + "state.json", timeout=5) as res:
        assert res.status == 200  # the server closes this connection first: TIME_WAIT
    first.close()
    second = TreePageServer(PageState(), port=port)
    try:
        with urllib.request.urlopen(second.url + "state.json", timeout=5) as res:
            assert json.loads(res.read()) == {}
    finally:
        second.close()


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux /proc/net/tcp")
@pytest.mark.parametrize("bind", ["127.0.0.1", "0.0.0.0"])
def test_every_server_listens_on_the_bind_address_only(bind: str) -> None:
    live = LiveViewer(None, _Tiny(), LiveOptions(port=0, bind=bind), say=lambda s: None)
    assert live.start()
    try:
        assert live.page is not None and live.link is not None
        web = _port_of(live.link.web_url)
        zmq = _port_of(live.link.zmq_url)
        assert _listening(live.page.port) == {bind}
        assert _listening(web) == {bind}  # meshcat's own command would listen on 0.0.0.0
        assert _listening(zmq) == {bind}
        assert live.page.url == f"http://127.0.0.1:{live.page.port}/"
        with urllib.request.urlopen(live.page.url, timeout=5) as res:
            page = res.read().decode()
        # the 3D view's frame points where the browser can reach it, never at 0.0.0.0
        assert f'src="http://127.0.0.1:{web}/static/"' in page
        server = live.link.server
    finally:
        live.close()
    assert server is not None and server.poll() is not None  # stopped and reaped


class _Tiny:
    """A one-node tree for the page."""

    def __init__(self) -> None:
        import py_trees

        self.root = py_trees.behaviours.Success("done")


@pytest.mark.parametrize(
    ("flag", "value", "message"),
    [
        ("--port", "99999", "argument --port: 99999 is not a port; use 1..65535, or 0 for any "
                            "free port"),
        ("--port", "-1", "argument --port: -1 is not a port"),
        ("--port", "http", "argument --port: expected a port number, got 'http'"),
        ("--bind", "999.1.1.1", "argument --bind: '999.1.1.1' is not an IP address"),
        ("--bind", "::1", "argument --bind: '::1': the meshcat server listens on IPv4 only"),
    ],
)
def test_bad_port_and_bind_values_are_bad_input(
    flag: str, value: str, message: str, capsys: pytest.CaptureFixture
) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["run", DEMO, "--viz", flag, value])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_taken_port_and_foreign_address_exit_2_naming_the_flag(
    capsys: pytest.CaptureFixture,
) -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        assert main(["run", DEMO, "--viz", "--port", str(port)]) == 2
    err = capsys.readouterr().err
    assert f"--port: port {port} is in use on 127.0.0.1" in err
    # 192.0.2.0/24 is reserved for documentation: never an address of this machine
    assert main(["run", DEMO, "--viz", "--port", "0", "--bind", "192.0.2.7"]) == 2
    err = capsys.readouterr().err
    assert "--bind: cannot listen on 192.0.2.7: not an address of this machine" in err
    assert "Traceback" not in err


def test_keep_serving_needs_a_live_view(capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["run", DEMO, "--keep-serving"])
    assert exc.value.code == 2
    assert "--keep-serving: only with --viz" in capsys.readouterr().err


def _start(args: list[str], tmp_path: Path) -> tuple[subprocess.Popen[str], dict[str, int]]:
    """Start ``bt-manip run`` with a live view; wait for its URLs; return the ports."""
    env = dict(os.environ, PYTHONPATH=str(REPO))
    process = subprocess.Popen(
        [sys.executable, "-m", "bt_manip.cli", "run", *args, "--viz", "--port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=tmp_path,
    )
    ports: dict[str, int] = {}
    assert process.stdout is not None
    deadline = time.monotonic() + 60
    while len(ports) < 2 and time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            break
        for key in ("meshcat view", "tree page"):
            if line.startswith(key + ":"):
                ports[key] = _port_of(line.split(": ", 1)[1])
    assert len(ports) == 2, f"the run did not report its servers (exit {process.poll()})"
    return process, ports


def _wait_line(process: subprocess.Popen[str], text: str, timeout: float = 30) -> str:
    assert process.stdout is not None
    seen = ""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            break
        seen += line
        if text in line:
            return seen
    raise AssertionError(f"no '{text}' in the output:\n{seen}")


def _get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=5) as res:
        return json.loads(res.read())


def _long_tree(tmp_path: Path) -> Path:
    """``long.xml``: a tree that sleeps for two minutes in node ``long_wait``."""
    tree = tmp_path / "long.xml"
    tree.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="M">'
        '<Sleep name="long_wait" msec="120000"/></BehaviorTree></root>'
    )
    return tree


def test_sigterm_stops_the_run_and_every_server(tmp_path: Path) -> None:
    tree = _long_tree(tmp_path)
    process, ports = _start([str(tree)], tmp_path)
    try:
        page = f"http://127.0.0.1:{ports['tree page']}/"
        assert _get(page + "tree.json")["nodes"][0]["name"] == "long_wait"
        servers = _children(process.pid)  # the meshcat server
        assert servers
        process.send_signal(signal.SIGTERM)
        out, _ = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 130, out
    assert "result: INTERRUPTED" in out and "Traceback" not in out
    assert _all_gone(servers)  # no meshcat server left behind
    assert _free(ports["tree page"])


def test_keep_serving_keeps_the_page_after_the_run_until_sigterm(tmp_path: Path) -> None:
    process, ports = _start([DEMO, "--keep-serving"], tmp_path)
    try:
        _wait_line(process, "serving the live view until Ctrl-C")
        state = _get(f"http://127.0.0.1:{ports['tree page']}/state.json")
        assert state["result"] == "SUCCESS"
        servers = _children(process.pid)
        assert servers and not any(_gone(pid) for pid in servers)  # still serving
        process.send_signal(signal.SIGTERM)
        out, _ = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0, out  # the run's own result
    assert _all_gone(servers)
    assert _free(ports["tree page"])


def test_a_taken_default_port_falls_back_to_a_free_one(monkeypatch: pytest.MonkeyPatch) -> None:
    from types import SimpleNamespace

    import bt_manip.viz.hooks as hooks

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        taken = s.getsockname()[1]
        monkeypatch.setattr(hooks, "DEFAULT_PORT", taken)
        said: list[str] = []
        args = SimpleNamespace(viz=True, port=None, bind=None, zmq_url=None, record=None)
        viz = hooks.setup_viz(args, None, _Tiny(), say=said.append)
        try:
            assert viz.viewing and viz.viewer.page is not None
            assert viz.viewer.page.port != taken
            assert f"port {taken} is in use; serving the tree page on a free port instead" in said
        finally:
            viz.close()
    assert viz.viewer.page is None and not viz.viewer.active


def test_a_killed_run_leaves_no_meshcat_server(tmp_path: Path) -> None:
    tree = _long_tree(tmp_path)
    process, _ = _start([str(tree)], tmp_path)
    servers = _children(process.pid)
    assert servers
    process.kill()  # SIGKILL: no clean-up runs in the run itself
    process.communicate(timeout=30)
    assert _all_gone(servers)  # the server noticed its run was gone and exited
