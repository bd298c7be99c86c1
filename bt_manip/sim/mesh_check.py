"""Checking that a mesh file named by a URDF is a mesh PyBullet can read.

PyBullet refuses a URDF whose mesh has an extension it does not know (``pybullet.error``, with
no word of which mesh), and silently loads a body without geometry when an ``.stl``, ``.obj``
or ``.dae`` file holds something else. :func:`mesh_problem` finds both (and meshes larger than
:data:`MAX_MESH_BYTES`) before PyBullet sees the file, so the message can name the URDF and the
mesh.
"""

from __future__ import annotations

import struct
from pathlib import Path

from bt_manip.input_files import size_text

MESH_EXTENSIONS = (".stl", ".obj", ".dae")
MAX_MESH_BYTES = 64 * 1024 * 1024
"""Largest mesh file accepted (PyBullet and the viewer read meshes whole)."""
_CHUNK = 1024 * 1024


def mesh_problem(path: Path, uri: str) -> str | None:
    """Why the mesh at ``path`` (written ``uri`` in the URDF) cannot be loaded, or None."""
    suffix = path.suffix.lower()
    if suffix not in MESH_EXTENSIONS:
        return (f"mesh '{uri}' is not a mesh PyBullet reads; use an .stl, .obj or .dae file")
    if not path.is_file():
        return f"mesh not found: {uri} (at {path})"
    try:
        with open(path, "rb") as f:
            head = f.read(4096)
            size = path.stat().st_size
            if size > MAX_MESH_BYTES:
                return f"mesh '{uri}' is larger than the limit of {size_text(MAX_MESH_BYTES)}"
            ok = {".stl": _is_stl, ".obj": _is_obj, ".dae": _is_collada}[suffix](f, head, size)
    except OSError as exc:
        return f"mesh '{uri}' cannot be read: {exc.strerror}"
    if not ok:
        kind = {".stl": "an STL", ".obj": "a Wavefront OBJ", ".dae": "a COLLADA"}[suffix]
        return f"mesh '{uri}' is not {kind} mesh (no triangles found in {path.name})"
    return None


def _is_stl(f: object, head: bytes, size: int) -> bool:
    if len(head) >= 84:
        (count,) = struct.unpack_from("<I", head, 80)
        if count > 0 and size == 84 + 50 * count:
            return True
    return head.lstrip().startswith(b"solid") and b"facet" in head


def _is_obj(f: object, head: bytes, size: int) -> bool:
    """True when the file has a face line (``f ...``); scans it in chunks."""
    data = b"\n" + head
    while True:
        if b"\nf " in data or b"\nf\t" in data:
            return True
        chunk = f.read(_CHUNK)  # type: ignore[attr-defined]
        if not chunk:
            return False
        data = data[-2:] + chunk


def _is_collada(f: object, head: bytes, size: int) -> bool:
    return b"<COLLADA" in head
