"""The replay page: one HTML file that plays a recorded run offline.

The page holds everything it needs: the meshcat viewer bundle (three.js included) from the
installed ``meshcat`` package, the page's scripts and style, and the recording as one
gzip-compressed, base64-encoded container:

``BTRP`` (4 bytes), header length (uint32, little-endian), header (JSON), binary blobs.

The header lists the scene objects (three.js JSON; a mesh file is stored once and referred to
as ``{"$mesh": k}``), the static placements, the bodies with the sim times at which they
appeared and disappeared (models spawned and deleted by the tree), the moving frames and where
their samples are, the tree's nodes and status changes, the overlay items and the highlights,
each with its sim time. A moving frame has samples from its body's first frame on (``first``,
``count``), stored as float32, component by component (x of every sample, then y, ...), which
compresses well; a frame that never moves keeps a single sample.
The browser unpacks it with ``DecompressionStream`` and plays it on a timeline.
"""

from __future__ import annotations

import base64
import copy
import gzip
import json
import struct
from pathlib import Path
from typing import Any

import numpy as np

from bt_manip.outputs import write_text
from bt_manip.viz.recording import Recording
from bt_manip.viz.scene import ROOT, column_major, mesh_files
from bt_manip.viz.tree_page import STATIC_DIR, meshcat_bundle, render_page

MAGIC = b"BTRP"
STILL = 1e-6
"""A frame whose samples all stay this close to the first (m, quaternion units) is stored once."""
FORMAT_VERSION = 2


class _Blobs:
    def __init__(self) -> None:
        self.parts: list[bytes] = []
        self.size = 0

    def add(self, data: bytes) -> dict[str, int]:
        ref = {"offset": self.size, "length": len(data)}
        self.parts.append(data)
        self.size += len(data)
        return ref


def build_container(rec: Recording, title: str = "") -> bytes:
    """The uncompressed container of a recording (see the module docstring)."""
    blobs = _Blobs()
    duration = float(rec.times[-1]) if rec.times else 0.0
    header: dict[str, Any] = {
        "format": FORMAT_VERSION,
        "title": title,
        "info": {k: v for k, v in rec.info.items() if k != "camera"},
        "result": rec.result,
        "duration": duration,
        "root": ROOT,
    }
    objects: list[dict[str, Any]] = []
    meshes: list[dict[str, Any]] = []
    static: list[list[Any]] = []
    tracks: list[dict[str, Any]] = []
    bodies: list[dict[str, Any]] = []
    body_objects: dict[str, list[list[Any]]] = {}
    mesh_index: dict[Path, int] = {}
    all_objects = rec.objects
    for path in mesh_files(all_objects):
        fmt = next(o.mesh_format for o in all_objects if o.mesh == path)
        mesh_index[path] = len(meshes)
        meshes.append({"format": fmt, "name": path.name, **blobs.add(path.read_bytes())})
    for body in rec.bodies:
        drawing = body.drawing
        if drawing.tracks and not body.samples:
            continue  # came and went between two frames: never seen
        for obj in drawing.objects:
            json_obj = copy.deepcopy(obj.json)
            if obj.mesh is not None:
                ref = {"$mesh": mesh_index[obj.mesh]}
                if json_obj["object"]["type"] == "_meshfile_object":
                    json_obj["object"]["data"] = ref
                else:
                    json_obj["geometries"][0]["data"] = ref
            objects.append({"path": obj.path, "json": json_obj})
        static += [[path, column_major(m)] for path, m in drawing.static]
        body_objects[body.key] = [[o.path, list(o.rgba)] for o in drawing.objects
                                  if o.rgba is not None]
        bodies.append({"name": body.key, "path": drawing.path, "appear": float(body.appear),
                       "disappear": None if body.disappear is None else float(body.disappear)})
        if not body.samples:
            continue
        samples = np.stack(body.samples).astype(np.float32)  # (samples, tracks, 7)
        for k, track_path in enumerate(drawing.tracks):
            series = samples[:, k, :]
            constant = bool(np.abs(series - series[0]).max() < STILL)
            data = series[0] if constant else series.T  # component-major
            tracks.append({"path": track_path, "const": constant, "first": body.first_frame,
                           "count": len(series),
                           **blobs.add(np.ascontiguousarray(data).tobytes())})
    times = np.asarray(rec.times, dtype=np.float32)
    camera = rec.info.get("camera") or {"target": [0.0, 0.0, 0.0],
                                        "offset": [-2.4, -2.0, 1.9], "follow": ""}
    header["scene"] = {
        "objects": objects,
        "meshes": meshes,
        "static": static,
        "bodies": bodies,
        "tracks": tracks,
        "body_objects": body_objects,
        "camera": camera,
    }
    header["frames"] = {"count": len(rec.times), "times": blobs.add(times.tobytes())}
    reasons: dict[str, int] = {"": 0}
    events = []
    for t, index, code, reason in rec.status_events:
        r = reasons.setdefault(reason, len(reasons))
        events.append([float(t), index, code, r])
    header["tree"] = {"nodes": rec.nodes, "events": events, "reasons": list(reasons)}
    if rec.counts is not None:
        header["tree"]["counts"] = rec.counts
    header["overlay"] = [[float(t), name, obj, m] for t, name, obj, m in
                         rec.overlay_events]
    header["highlights"] = [[float(t), name, on] for t, name, on in
                            rec.highlight_events]
    head = json.dumps(header, separators=(",", ":")).encode()
    return MAGIC + struct.pack("<I", len(head)) + head + b"".join(blobs.parts)


def read_container(data: bytes) -> tuple[dict[str, Any], bytes]:
    """Header and blob area of an uncompressed container."""
    if data[:4] != MAGIC:
        raise ValueError("not a bt-manip replay container")
    (length,) = struct.unpack("<I", data[4:8])
    return json.loads(data[8 : 8 + length]), data[8 + length :]


def read_replay(path: str | Path) -> tuple[dict[str, Any], bytes]:
    """Header and blobs of a replay page (what the page's script decodes)."""
    text = Path(path).read_text()
    start = text.index('<script type="application/octet-stream" id="bt-replay">')
    start = text.index(">", start) + 1
    end = text.index("</script>", start)
    return read_container(gzip.decompress(base64.b64decode(text[start:end].strip())))


def track_samples(header: dict[str, Any], blobs: bytes, path: str) -> np.ndarray:
    """The samples of one moving frame: rows (x, y, z, qx, qy, qz, qw), one per frame from
    the frame its body appeared in (``first`` of the track) on."""
    track = next(t for t in header["scene"]["tracks"] if t["path"] == path)
    n = track["count"]
    raw = np.frombuffer(blobs[track["offset"] : track["offset"] + track["length"]], np.float32)
    if track["const"]:
        return np.tile(raw, (n, 1))
    return raw.reshape(7, n).T


def write_replay(path: str | Path, rec: Recording, title: str = "") -> int:
    """Write the replay page of ``rec`` to ``path``; return its size in bytes."""
    title = title or rec.info.get("tree", "") or "bt-manip replay"
    payload = base64.b64encode(gzip.compress(build_container(rec, title), 6)).decode()
    bundle = meshcat_bundle().read_text().replace("</script", "<\\/script")
    common = (STATIC_DIR / "common.js").read_text()
    replay = (STATIC_DIR / "replay.js").read_text()
    scripts = (
        f'<script type="application/octet-stream" id="bt-replay">{payload}</script>\n'
        f"<script>{bundle}</script>\n<script>{common}</script>\n<script>{replay}</script>"
    )
    timeline = (STATIC_DIR / "timeline.html").read_text()
    view = '<div id="meshcat-pane"></div>'
    page = render_page(f"{title} (replay)", {"format": FORMAT_VERSION}, scripts, view,
                       timeline=timeline, follow=True)
    out = Path(path)
    write_text(out, page)
    return out.stat().st_size
