"""How large a URDF bt-manip loads: links and joints counted on the parsed file.

A URDF of 8 MB (:data:`~bt_manip.sim.compose.MAX_URDF_BYTES`) holds tens of thousands of
links; Pinocchio's URDF reader recurses once per link of a chain and overflows the stack past
a few thousand (a segmentation fault, not an error), and every check of a link costs a pass
over it. A robot has tens of links, a building's furniture fewer: a file with more than
:data:`MAX_URDF_LINKS` links or :data:`MAX_URDF_JOINTS` joints is refused at the first one past
the limit, before any library reads it.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from bt_manip.errors import InputError

MAX_URDF_LINKS = 1000
"""Links of one URDF: at most this many."""
MAX_URDF_JOINTS = 1000
"""Joints of one URDF: at most this many."""


def check_urdf_size(path: Path, root: ET.Element, data: bytes) -> None:
    """Refuse ``root`` (the parsed ``data`` of ``path``) when it holds more links or joints
    than the limits, naming the line of the first one past the limit."""
    for tag, limit in (("link", MAX_URDF_LINKS), ("joint", MAX_URDF_JOINTS)):
        count = len(root.findall(tag))
        if count > limit:
            raise InputError.single(
                str(path), _line_of_nth(data, tag, limit),
                f"the URDF has {count:,} <{tag}> elements, more than the limit of {limit:,}")


def _line_of_nth(data: bytes, tag: str, n: int) -> int | None:
    """Line of the ``n``-th (0-based) ``<tag`` element in ``data``, or None."""
    pattern = re.compile(rb"<" + tag.encode() + rb"[\s/>]")
    for i, match in enumerate(pattern.finditer(data)):
        if i == n:
            return data.count(b"\n", 0, match.start()) + 1
    return None
