"""Argument types of the command line: each turns one argument's text into its value, or
raises :class:`argparse.ArgumentTypeError` with the message argparse prints (exit code 2).

Also the defaults and shared flags that several verbs take (``--inject``).
"""

from __future__ import annotations

import argparse
import ipaddress
import math
from typing import Any

from bt_manip.bt.blackboard import bb_value
from bt_manip.errors import InputError
from bt_manip.run.faults import FaultSpec, parse_fault

DEFAULT_TICK_HZ = 20.0
"""Tree tick rate of ``run``, ``bench`` and ``demo`` (Hz)."""
DEFAULT_MAX_SIM_TIME = 600.0
"""Sim time budget of ``run``, ``bench`` and ``demo`` (s)."""
MAX_GRIPPER_JOINTS = 4
"""Finger joints ``robot init --gripper`` takes at most."""
MAX_PAYLOAD = 10000.0
"""Largest ``bim --payload`` (kg)."""
MAX_SEEDS = 1000
"""Seeds ``bim --seed-range`` checks at most."""


def positive(kind: type) -> Any:
    """An argparse type: a ``kind`` number greater than 0 (and finite)."""

    def convert(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got '{text}'") from None
        if not value > 0 or (isinstance(value, float) and not math.isfinite(value)):
            raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
        return value

    return convert


def within(kind: type, low: float, high: float) -> Any:
    """An argparse type: a ``kind`` number from ``low`` to ``high`` (both included)."""

    def convert(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got '{text}'") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be within {low:g}..{high:g}, got {text}")
        return value

    return convert


TICK_HZ = within(float, 0.1, 1000.0)
"""Tree tick rates accepted (Hz): slower would wait for ages, faster than any physics rate."""
REALTIME = within(float, 0.01, 1000.0)
"""Real-time factors accepted by --realtime."""


def _port_number(text: str) -> int:
    """``text`` as an integer, else the error of every port option."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got '{text}'") from None


def port(text: str) -> int:
    """A TCP port, 1..65535, or 0 for any free one."""
    value = _port_number(text)
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(
            f"{value} is not a port; use 1..65535, or 0 for any free port"
        )
    return value


def address(text: str) -> str:
    """An IPv4 address to listen on, or ``localhost``."""
    host = text.strip()
    if host == "localhost":
        return host
    try:
        parsed = ipaddress.ip_address(host)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"'{text}' is not an IP address; e.g. 127.0.0.1 (this machine only) or 0.0.0.0 "
            "(every interface)"
        ) from None
    if parsed.version != 4:
        raise argparse.ArgumentTypeError(
            f"'{text}': the meshcat server listens on IPv4 only; use an IPv4 address such as "
            "127.0.0.1 or 0.0.0.0"
        )
    return str(parsed)


def groot_port(text: str) -> int:
    """A Groot2 port: PORT serves requests, PORT+1 publishes, so at most 65534 (0: any)."""
    value = _port_number(text)
    if not 0 <= value <= 65534:
        raise argparse.ArgumentTypeError(
            f"must be a port from 1 to 65534 (PUB uses the next one), or 0 for any, got {text}")
    return value


def bb_pair(text: str) -> tuple[str, Any]:
    """``KEY=VALUE``; VALUE is read as a JSON scalar when it is one, else kept as text
    (:func:`~bt_manip.bt.blackboard.bb_value`)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected key=value, got '{text}'")
    return key.strip(), bb_value(value)


def fault(text: str) -> FaultSpec:
    """An ``--inject`` fault (:func:`~bt_manip.run.faults.parse_fault`)."""
    try:
        return parse_fault(text)
    except InputError as exc:
        raise argparse.ArgumentTypeError(exc.problems[0].message) from None


def add_localize(parser: argparse.ArgumentParser) -> None:
    """``--localize``, as ``run`` and ``bench`` take it."""
    parser.add_argument(
        "--localize",
        action="store_true",
        help="localise the robot with its laser, wheel odometry and a particle filter, and "
        "drive on the estimate (the world's localization: section, or the defaults); the run "
        "report adds the estimate's errors",
    )


def add_inject(parser: argparse.ArgumentParser) -> None:
    """``--inject FAULT`` (repeatable), as ``run`` and ``bench`` take it."""
    parser.add_argument(
        "--inject",
        action="append",
        type=fault,
        default=[],
        metavar="FAULT",
        help="inject faults, seeded: NAME:failure:P (node NAME fails with probability P), "
        "slip:P (a held object slips), block:P (an obstacle falls on the route), "
        "pose_noise:SIGMA_M[:SIGMA_DEG] (the robot sees each object off by an offset drawn once "
        "per episode: x, y with sigma SIGMA_M metres, yaw with sigma SIGMA_DEG, default 2 deg); "
        "with --localize: odom_noise:K[:K_ROT] (wheel odometry error), lidar_noise:SIGMA (range "
        "noise, m), lidar_dropout:P (each beam lost with probability P), kidnap:T (at sim time "
        "T the robot is carried 0.5-1.5 m away and its localisation is not told)",
    )


def joint_list(text: str) -> tuple[str, ...]:
    """``robot init --gripper``: 1..4 joint names separated by commas."""
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not 1 <= len(names) <= MAX_GRIPPER_JOINTS:
        raise argparse.ArgumentTypeError(
            f"expected 1..{MAX_GRIPPER_JOINTS} joint names separated by commas, got '{text}'"
        )
    return names


def stock_pose(text: str) -> tuple[float, float, float]:
    """``bim --stock``: ``X;Y;YAW`` (metres, radians)."""
    parts = text.split(";")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected X;Y;YAW (metres, radians), got '{text}'")
    return values  # type: ignore[return-value]


def payload(text: str) -> float:
    """``bim --payload``: a mass in kg, in (0, MAX_PAYLOAD]."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0.0 < value <= MAX_PAYLOAD):
        raise argparse.ArgumentTypeError(
            f"expected a mass in (0, {MAX_PAYLOAD:g}] kg, got '{text}'"
        )
    return value


def seed_range(text: str) -> range:
    """``bim --seed-range``: ``FIRST:END`` (END excluded) or one seed, 1..MAX_SEEDS seeds."""
    low, sep, high = text.partition(":")
    try:
        seeds = range(int(low), int(high)) if sep else range(int(low), int(low) + 1)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected FIRST:END (END excluded), got '{text}'"
        ) from None
    if not 0 < len(seeds) <= MAX_SEEDS:
        raise argparse.ArgumentTypeError(f"give 1..{MAX_SEEDS} seeds, got '{text}'")
    return seeds
