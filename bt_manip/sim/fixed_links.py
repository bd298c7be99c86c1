"""Fixed links folded into their parents, so that PyBullet simulates fewer links.

A composed robot has many links that cannot move relative to their parent: an IMU frame, a top
plate, bumpers, an arm's mounting flange, the tool flange, the gripper's body, the grasp frame.
Each one is a link of PyBullet's multibody all the same, and the cost of a physics step grows
with the number of links (every contact row's Jacobian and every forward-dynamics pass walks
them all). :func:`merge_fixed_links` rewrites a URDF tree so that each child of a ``fixed``
joint becomes part of its parent:

- the child's mass joins the parent's: one inertial with the total mass at the common centre of
  mass and the combined inertia tensor (parallel-axis theorem), written in its principal axes;
- the child's collision shapes move to the parent, placed where they were;
- joints that hung below the child hang below the parent, at the same place;
- the fixed joint and the child link are removed (with its ``<contact>``, which only its own
  collision shapes used), and the child's frame is recorded as a
  :class:`MergedFrame`: which remaining link carries it, and where it sits in that link's frame.

The body is the same rigid assembly (same masses, inertia about every axis, collision shapes and
joints); only its bookkeeping differs. A link missing an ``<inertial>`` counts as PyBullet counts
it (1 kg, unit inertia). A child is left as it is when its ``<contact>`` parameters differ from
its parent's (merged shapes take the parent's friction), and when the combined inertia would not
be one PyBullet accepts (principal moments must obey the triangle inequality).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from bt_manip.geometry import pose_matrix, quat_from_matrix, rpy_matrix

PYBULLET_DEFAULT_MASS = 1.0
"""PyBullet's mass for a link without ``<inertial>`` (with URDF_USE_INERTIA_FROM_FILE; its
inertia is then the unit matrix)."""


@dataclass(frozen=True)
class MergedFrame:
    """Where a merged link's frame now lives: ``carrier`` is the link that holds it, and
    ``position`` / ``quat`` (x, y, z, w) place the merged link's URDF frame in the carrier's
    URDF frame."""

    carrier: str
    position: tuple[float, float, float]
    quat: tuple[float, float, float, float]

    def matrix(self) -> np.ndarray:
        """The offset as a 4x4 transform."""
        return pose_matrix(self.position, self.quat)


@dataclass
class _Inertial:
    mass: float
    com: np.ndarray  # (3,) in the link frame
    tensor: np.ndarray  # (3, 3) about the centre of mass, link-frame axes


def merge_fixed_links(root: ET.Element) -> dict[str, MergedFrame]:
    """Fold every mergeable child of a fixed joint into its parent, in place (see the module
    docstring); the merged links' frames by name."""
    frames: dict[str, tuple[str, np.ndarray]] = {}
    while True:
        links = {el.get("name", ""): el for el in root.findall("link")}
        joint = next((j for j in root.findall("joint") if _mergeable(j, links)), None)
        if joint is None:
            break
        parent_name = _child_or_parent(joint, "parent")
        child_name = _child_or_parent(joint, "child")
        parent, child = links[parent_name], links[child_name]
        offset = _origin(joint)
        _fold(parent, child, offset)
        for other in root.findall("joint"):
            if _child_or_parent(other, "parent") == child_name:
                _set_origin(other, offset @ _origin(other))
                other.find("parent").set("link", parent_name)  # type: ignore[union-attr]
        root.remove(joint)
        root.remove(child)
        for name, (carrier, t) in list(frames.items()):
            if carrier == child_name:
                frames[name] = (parent_name, offset @ t)
        frames[child_name] = (parent_name, offset)
    return {
        name: MergedFrame(
            carrier,
            (float(t[0, 3]), float(t[1, 3]), float(t[2, 3])),
            tuple(float(v) for v in quat_from_matrix(t[:3, :3])),  # type: ignore[arg-type]
        )
        for name, (carrier, t) in frames.items()
    }


def _mergeable(joint: ET.Element, links: dict[str, ET.Element]) -> bool:
    if joint.get("type") != "fixed":
        return False
    parent = links.get(_child_or_parent(joint, "parent"))
    child = links.get(_child_or_parent(joint, "child"))
    if parent is None or child is None:
        return False
    if _contact_text(parent) != _contact_text(child) and child.find("collision") is not None:
        return False
    combined = _combine(_inertial(parent), _inertial(child), _origin(joint))
    return combined.mass == 0.0 or _valid_tensor(combined.tensor)


def _child_or_parent(joint: ET.Element, tag: str) -> str:
    el = joint.find(tag)
    return el.get("link", "") if el is not None else ""


def _contact_text(link: ET.Element) -> str:
    contact = link.find("contact")
    return "" if contact is None else ET.tostring(contact, encoding="unicode").strip()


def _origin(el: ET.Element) -> np.ndarray:
    """The 4x4 transform of an element's ``<origin>`` (identity when absent)."""
    origin = el.find("origin")
    out = np.eye(4)
    if origin is None:
        return out
    xyz = [float(v) for v in origin.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in origin.get("rpy", "0 0 0").split()]
    out[:3, :3] = rpy_matrix(*rpy)
    out[:3, 3] = xyz
    return out


def _set_origin(el: ET.Element, t: np.ndarray) -> None:
    origin = el.find("origin")
    if origin is None:
        origin = ET.Element("origin")
        el.insert(0, origin)
    origin.set("xyz", " ".join(repr(float(v)) for v in t[:3, 3]))
    origin.set("rpy", " ".join(repr(float(v)) for v in rpy_of(t[:3, :3])))


def rpy_of(r: np.ndarray) -> tuple[float, float, float]:
    """URDF roll, pitch, yaw of a rotation matrix (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    pitch = float(np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0])))
    if np.hypot(r[0, 0], r[1, 0]) < 1e-12:  # gimbal lock: put the whole turn in roll
        return float(np.arctan2(-r[1, 2], r[1, 1])), pitch, 0.0
    return float(np.arctan2(r[2, 1], r[2, 2])), pitch, float(np.arctan2(r[1, 0], r[0, 0]))


def _inertial(link: ET.Element) -> _Inertial:
    el = link.find("inertial")
    if el is None:
        return _Inertial(PYBULLET_DEFAULT_MASS, np.zeros(3), np.eye(3))
    mass_el = el.find("mass")
    mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
    frame = _origin(el)
    inertia = el.find("inertia")
    local = np.zeros((3, 3))
    if inertia is not None:
        get = lambda key: float(inertia.get(key, "0"))  # noqa: E731
        local = np.array(
            [
                [get("ixx"), get("ixy"), get("ixz")],
                [get("ixy"), get("iyy"), get("iyz")],
                [get("ixz"), get("iyz"), get("izz")],
            ]
        )
    rot = frame[:3, :3]
    return _Inertial(mass, frame[:3, 3].copy(), rot @ local @ rot.T)


def _combine(parent: _Inertial, child: _Inertial, offset: np.ndarray) -> _Inertial:
    """The two bodies as one, in the parent's frame; ``offset`` places the child's frame."""
    rot = offset[:3, :3]
    child_com = offset[:3, :3] @ child.com + offset[:3, 3]
    child_tensor = rot @ child.tensor @ rot.T
    mass = parent.mass + child.mass
    if mass == 0.0:
        return _Inertial(0.0, np.zeros(3), np.zeros((3, 3)))
    com = (parent.mass * parent.com + child.mass * child_com) / mass
    tensor = np.zeros((3, 3))
    parts = ((parent.mass, parent.com, parent.tensor), (child.mass, child_com, child_tensor))
    for m, c, t in parts:
        if m == 0.0:
            continue
        d = c - com
        tensor += t + m * (float(d @ d) * np.eye(3) - np.outer(d, d))
    return _Inertial(mass, com, tensor)


def _valid_tensor(tensor: np.ndarray) -> bool:
    """Principal moments that PyBullet accepts: positive and each below the sum of the others
    (strictly, with a small margin)."""
    moments = np.linalg.eigvalsh(0.5 * (tensor + tensor.T))
    if moments.min() <= 0.0:
        return False
    a, b, c = sorted(moments)
    return bool(c < (a + b) * (1.0 - 1e-9))


def _fold(parent: ET.Element, child: ET.Element, offset: np.ndarray) -> None:
    combined = _combine(_inertial(parent), _inertial(child), offset)
    old = parent.find("inertial")
    index = list(parent).index(old) if old is not None else 0
    if old is not None:
        parent.remove(old)
    parent.insert(index, _inertial_element(combined))
    for collision in child.findall("collision"):
        _set_origin(collision, offset @ _origin(collision))
        parent.append(collision)


def _inertial_element(inertial: _Inertial) -> ET.Element:
    """An ``<inertial>`` in principal axes (PyBullet would diagonalise a full tensor itself)."""
    el = ET.Element("inertial")
    frame = np.eye(4)
    frame[:3, 3] = inertial.com
    moments = np.zeros(3)
    if inertial.mass > 0.0:
        moments, axes = np.linalg.eigh(0.5 * (inertial.tensor + inertial.tensor.T))
        if np.linalg.det(axes) < 0:
            axes[:, 2] = -axes[:, 2]
        frame[:3, :3] = axes
    _set_origin(el, frame)
    ET.SubElement(el, "mass", value=repr(float(inertial.mass)))
    ET.SubElement(
        el,
        "inertia",
        ixx=repr(float(moments[0])), ixy="0", ixz="0",
        iyy=repr(float(moments[1])), iyz="0", izz=repr(float(moments[2])),
    )
    return el
