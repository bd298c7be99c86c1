"""The visual elements of a URDF: what each link looks like, in that link's frame.

The viewer draws robots (and URDF furniture) from their URDF ``<visual>`` elements: a mesh
(``.dae``, ``.stl``, ``.obj``) or a primitive (box, cylinder, sphere), placed by the visual's
``<origin>`` in its link frame, coloured by its ``<material>`` (inline or named at the top of the
file). A visual without a material keeps the colours of its mesh file, if it has any.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import defusedxml.ElementTree as SafeET
import numpy as np

from bt_manip.geometry import rpy_matrix
from bt_manip.sim.assets import resolve_uri

Rgba = tuple[float, float, float, float]


@dataclass(frozen=True)
class Visual:
    """One ``<visual>`` of a link.

    ``kind`` is ``mesh``, ``box``, ``cylinder`` or ``sphere``; ``size`` holds the box extents,
    (radius, length) of a cylinder or (radius,) of a sphere; ``mesh`` and ``scale`` describe a
    mesh file. ``rgba`` is None when the URDF gives no colour.
    """

    link: str
    origin: np.ndarray = field(compare=False)
    kind: str
    size: tuple[float, ...] = ()
    mesh: Path | None = None
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    rgba: Rgba | None = None


def _floats(text: str | None, n: int, default: float) -> tuple[float, ...]:
    if not text:
        return (default,) * n
    values = [float(v) for v in text.split()]
    if len(values) == 1 and n > 1:
        values = values * n
    return tuple(values[:n])


def origin_matrix(xyz: tuple[float, ...], rpy: tuple[float, ...]) -> np.ndarray:
    """A 4x4 transform from a URDF ``<origin xyz rpy>``."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(*rpy)
    out[:3, 3] = xyz
    return out


def _colour(material: object, named: dict[str, Rgba]) -> Rgba | None:
    if material is None:
        return None
    colour = material.find("color")  # type: ignore[attr-defined]
    if colour is not None and colour.get("rgba"):
        return _floats(colour.get("rgba"), 4, 1.0)  # type: ignore[return-value]
    return named.get(material.get("name", ""))  # type: ignore[attr-defined]


def read_visuals(urdf: str | Path) -> list[Visual]:
    """Every visual of every link of a URDF file, in file order.

    Mesh file names are resolved like the simulator does (``package://``, ``pybullet_data://``,
    relative to the URDF); a mesh that does not exist is skipped (nothing to draw).
    """
    path = Path(urdf)
    root = SafeET.parse(str(path)).getroot()
    named: dict[str, Rgba] = {}
    for material in root.iter("material"):
        colour = material.find("color")
        if material.get("name") and colour is not None and colour.get("rgba"):
            named.setdefault(material.get("name"), _floats(colour.get("rgba"), 4, 1.0))  # type: ignore[arg-type]
    out: list[Visual] = []
    for link in root.findall("link"):
        name = link.get("name", "")
        for visual in link.findall("visual"):
            element = visual.find("origin")
            xyz = _floats(element.get("xyz") if element is not None else None, 3, 0.0)
            rpy = _floats(element.get("rpy") if element is not None else None, 3, 0.0)
            origin = origin_matrix(xyz, rpy)
            rgba = _colour(visual.find("material"), named)
            geometry = visual.find("geometry")
            if geometry is None or len(geometry) == 0:
                continue
            shape = geometry[0]
            if shape.tag == "mesh":
                mesh = resolve_uri(shape.get("filename", ""), path.parent)
                if not mesh.is_file():
                    continue
                scale = _floats(shape.get("scale"), 3, 1.0)
                out.append(Visual(name, origin, "mesh", (), mesh, scale, rgba))  # type: ignore[arg-type]
            elif shape.tag == "box":
                size = _floats(shape.get("size"), 3, 0.0)
                out.append(Visual(name, origin, "box", size, rgba=rgba))
            elif shape.tag == "cylinder":
                size = (float(shape.get("radius", 0)), float(shape.get("length", 0)))
                out.append(Visual(name, origin, "cylinder", size, rgba=rgba))
            elif shape.tag == "sphere":
                size = (float(shape.get("radius", 0)),)
                out.append(Visual(name, origin, "sphere", size, rgba=rgba))
    return out
