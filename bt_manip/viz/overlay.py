"""Drawing overlay items (:mod:`bt_manip.overlay`: planned paths, target frames, point sets
such as a laser's returns and a filter's particles) as three.js objects, for the live viewer
and the replay recorder."""

from __future__ import annotations

import uuid
from typing import Any

import numpy as np

from bt_manip.overlay import FrameItem, PathItem, PointsItem
from bt_manip.viz.scene import colour_int, column_major


def item_json(item: PathItem | FrameItem | PointsItem) -> dict[str, Any]:
    """A three.js object JSON (plain lists, no binary) drawing an overlay item."""
    geom_id, mat_id = str(uuid.uuid4()), str(uuid.uuid4())
    attributes: dict[str, Any]
    if isinstance(item, PointsItem):
        positions = item.points.astype(np.float32).flatten().tolist()
        attributes = {
            "position": {"itemSize": 3, "type": "Float32Array", "array": positions,
                         "normalized": False}
        }
        material = {"uuid": mat_id, "type": "PointsMaterial", "color": colour_int(item.rgba),
                    "size": item.size, "sizeAttenuation": True, "vertexColors": 0}
        kind, matrix = "Points", np.eye(4)
    elif isinstance(item, PathItem):
        positions = item.points.astype(np.float32).flatten().tolist()
        attributes = {
            "position": {"itemSize": 3, "type": "Float32Array", "array": positions,
                         "normalized": False}
        }
        material = {"uuid": mat_id, "type": "LineBasicMaterial", "color": colour_int(item.rgba),
                    "linewidth": 3, "vertexColors": 0}
        kind, matrix = "Line", np.eye(4)
    else:
        s = item.size
        positions = [0, 0, 0, s, 0, 0, 0, 0, 0, 0, s, 0, 0, 0, 0, 0, 0, s]
        colours = [1, 0, 0, 1, 0, 0, 0, 0.8, 0, 0, 0.8, 0, 0, 0, 1, 0, 0, 1]
        attributes = {
            "position": {"itemSize": 3, "type": "Float32Array", "array": positions,
                         "normalized": False},
            "color": {"itemSize": 3, "type": "Float32Array", "array": colours,
                      "normalized": False},
        }
        material = {"uuid": mat_id, "type": "LineBasicMaterial", "color": 0xFFFFFF,
                    "linewidth": 3, "vertexColors": 2}
        kind, matrix = "LineSegments", item.matrix
    return {
        "metadata": {"version": 4.5, "type": "Object"},
        "geometries": [{"uuid": geom_id, "type": "BufferGeometry",
                        "data": {"attributes": attributes}}],
        "materials": [material],
        "object": {"uuid": str(uuid.uuid4()), "type": kind, "geometry": geom_id,
                   "material": mat_id, "matrix": column_major(matrix)},
    }
