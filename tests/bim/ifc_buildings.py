"""Small IFC buildings generated with ``ifcopenshell.api`` for the bim tests.

:func:`three_rooms` builds, in millimetres, a 10 m x 6 m single-storey building of three rooms:

```
 y=6 +-------------------+-----------+
     |                   |  store    |   wall at x=5: door 1.6 m wide at y=1.5 (workshop-office)
     |   workshop        D 0.9       |                door 0.9 m wide at y=4.5 (workshop-store)
     |   (0..5 x 0..6)   +-----------+ y=3
     |                   |  office   |
     |                   D 1.6       |
 y=0 +-------------------+---W-------+   window 1.2 m wide at x=7.5 in the south wall, sill 0.9 m
    x=0                 x=5         x=10
```

Walls are 0.2 m thick and 2.5 m high, centred on the lines drawn. A slab lies under the whole
building (top at z = 0), a table (a mesh, turned 30 deg) stands in the store,
and six panels (IfcPlate, 1.2 x 0.02 x 0.3 m of a 400 kg/m3 material: 2.88 kg, within
the UR3's 3 kg payload) are to be installed standing on the floor before the inner faces of the
workshop's west wall and the office's east and south walls, each by its own task.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ifcopenshell = pytest.importorskip("ifcopenshell")
api = pytest.importorskip("ifcopenshell.api").run

WALL_T = 0.2
WALL_H = 2.5
PANEL = (1.2, 0.02, 0.3)

# name, from, to, openings: (kind, centre distance from `from`, width, sill, height)
Opening = tuple[str, float, float, float, float]
WALLS: list[tuple[str, tuple[float, float], tuple[float, float], list[Opening]]] = [
    ("South", (0.0, 0.0), (10.0, 0.0), [("window", 7.5, 1.2, 0.9, 1.2)]),
    ("North", (0.0, 6.0), (10.0, 6.0), []),
    ("West", (0.0, 0.0), (0.0, 6.0), []),
    ("East", (10.0, 0.0), (10.0, 6.0), []),
    ("Partition", (5.0, 0.0), (5.0, 6.0),
     [("door", 1.5, 1.6, 0.0, 2.1), ("door", 4.5, 0.9, 0.0, 2.1)]),
    ("Store", (5.0, 3.0), (10.0, 3.0), []),
]
SPACES = [("Workshop", (0.0, 0.0), (5.0, 6.0)), ("Office", (5.0, 0.0), (10.0, 3.0)),
          ("Store", (5.0, 3.0), (10.0, 6.0))]


@dataclass
class Panel:
    """A panel to install: its name, centre (x, y, z) in metres, yaw, and task start (a working
    day: ifcopenshell.api moves a start to 09:00 of the next working day)."""

    name: str
    centre: tuple[float, float, float]
    yaw: float
    start: str


# The default panels stand on the floor before the walls (z = 0..0.3 m), 8 cm off the wall's
# face: three before the workshop's west wall (facing +x), two before the office's east wall
# (facing -x) and one before the office's south wall (facing +y). They suit the robot: a UR3
# on a Husky with its gripper pointing down reaches a top edge up to about 0.9 m above the
# floor, and its gripper, closing across a panel's thickness from above, is 15 cm wide, so
# the wall must leave it 7.5 cm on the panel's far side.
PANELS = [
    Panel("Panel W1", (0.19, 1.4, 0.15), math.pi / 2, "2026-03-02"),
    Panel("Panel W2", (0.19, 2.75, 0.15), math.pi / 2, "2026-03-03"),
    Panel("Panel W3", (0.19, 4.1, 0.15), math.pi / 2, "2026-03-04"),
    Panel("Panel E1", (9.81, 0.8, 0.15), -math.pi / 2, "2026-03-05"),
    Panel("Panel E2", (9.81, 2.2, 0.15), -math.pi / 2, "2026-03-06"),
    Panel("Panel S1", (7.0, 0.19, 0.15), 0.0, "2026-03-09"),
]


@dataclass
class Building:
    """A generated model and the handles tests need."""

    file: Any
    walls: dict[str, Any] = field(default_factory=dict)
    panels: list[Any] = field(default_factory=list)
    tasks: list[Any] = field(default_factory=list)
    storey: Any = None
    body: Any = None

    def write(self, path: Path) -> Path:
        self.file.write(str(path))
        return path


def _matrix(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    m = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    m[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    m[:3, 3] = [x, y, z]
    return m


def _box(f: Any, body: Any, cls: str, name: str, size: tuple[float, float, float],
         matrix: np.ndarray) -> Any:
    """An element whose body is a box extruded from its placement (x along size[0])."""
    el = api("root.create_entity", f, ifc_class=cls, name=name)
    rep = api("geometry.add_wall_representation", f, context=body, length=size[0],
              height=size[2], thickness=size[1])
    api("geometry.assign_representation", f, product=el, representation=rep)
    api("geometry.edit_object_placement", f, product=el, matrix=matrix)
    return el


def three_rooms(*, schema: str = "IFC4", panels: list[Panel] | None = None,
                sequence: list[int] | None = None, with_tasks: bool = True,
                with_storey: bool = True, mm: bool = True, link: str = "product",
                element_class: str = "IfcPlate") -> Building:
    """The building of the module docstring.

    ``sequence`` lists panel indices: each IfcRelSequence links one to the next (by default
    none: the order comes from the tasks' start times). ``with_tasks=False`` leaves the panels
    without tasks (a CSV schedule is then needed); IFC2X3 files never get tasks. ``link`` is
    how a panel is tied to its task: ``product`` (the task's output, IfcRelAssignsToProduct)
    or ``process`` (IfcRelAssignsToProcess); ``element_class`` is the panels' IFC class.
    """
    f = ifcopenshell.file(schema=schema)
    if schema == "IFC2X3":  # every IFC2X3 entity names its owner: an author and a tool
        org = f.createIfcOrganization(None, "bt-manip tests")
        f.createIfcPersonAndOrganization(f.createIfcPerson(), org)
        f.createIfcApplication(org, "1", "bt-manip tests", "bt-manip-tests")
    project = api("root.create_entity", f, ifc_class="IfcProject", name="Three rooms")
    if mm:
        length = api("unit.add_si_unit", f, unit_type="LENGTHUNIT", prefix="MILLI")
        api("unit.assign_unit", f, units=[length])
    else:
        api("unit.assign_unit", f)
    model = api("context.add_context", f, context_type="Model")
    body = api("context.add_context", f, context_type="Model", context_identifier="Body",
               target_view="MODEL_VIEW", parent=model)
    site = api("root.create_entity", f, ifc_class="IfcSite", name="Site")
    building = api("root.create_entity", f, ifc_class="IfcBuilding", name="Building")
    api("aggregate.assign_object", f, products=[site], relating_object=project)
    api("aggregate.assign_object", f, products=[building], relating_object=site)
    out = Building(f, body=body)
    if with_storey:
        storey = api("root.create_entity", f, ifc_class="IfcBuildingStorey", name="Ground floor")
        api("aggregate.assign_object", f, products=[storey], relating_object=building)
        out.storey = storey
    container = out.storey if with_storey else building
    wall_cls = "IfcWallStandardCase" if schema == "IFC2X3" else "IfcWall"
    for name, a, b, openings in WALLS:
        yaw = math.atan2(b[1] - a[1], b[0] - a[0])
        length = math.dist(a, b)
        # the axis runs along the centre line: the box starts half a thickness to the right
        nx, ny = -math.sin(yaw), math.cos(yaw)
        m = _matrix(a[0] - nx * WALL_T / 2, a[1] - ny * WALL_T / 2, 0.0, yaw)
        wall = _box(f, body, wall_cls, name, (length, WALL_T, WALL_H), m)
        api("spatial.assign_container", f, products=[wall], relating_structure=container)
        out.walls[name] = wall
        for i, (kind, at, width, sill, height) in enumerate(openings):
            local = _matrix(at - width / 2, -0.05, sill, 0.0)
            opening = _box(f, body, "IfcOpeningElement", f"{name} opening {i}",
                           (width, WALL_T + 0.1, height), m @ local)
            api("feature.add_feature", f, feature=opening, element=wall)
            filling = api("root.create_entity", f,
                          ifc_class="IfcDoor" if kind == "door" else "IfcWindow",
                          name=f"{name} {kind} {i}")
            api("geometry.edit_object_placement", f, product=filling, matrix=m @ local)
            api("feature.add_filling", f, opening=opening, element=filling)
            api("spatial.assign_container", f, products=[filling], relating_structure=container)
    # add_wall_representation extrudes x along `length`, y along `thickness`
    slab = _box(f, body, "IfcSlab", "Ground slab", (10.2, 6.2, 0.2), _matrix(-0.1, -0.1, -0.2, 0.0))
    api("spatial.assign_container", f, products=[slab], relating_structure=container)
    for name, lo, hi in SPACES:
        space = _box(f, body, "IfcSpace", name, (hi[0] - lo[0] - WALL_T, hi[1] - lo[1] - WALL_T,
                     WALL_H), _matrix(lo[0] + WALL_T / 2, lo[1] + WALL_T / 2, 0.0, 0.0))
        if with_storey:
            api("aggregate.assign_object", f, products=[space], relating_object=out.storey)
    # a 1.2 x 0.8 x 0.75 m table turned by 30 deg, centred at (8.0, 5.0), as a mesh
    hx, hy, hz = 0.6, 0.4, 0.75
    verts = [(x, y, z) for z in (0.0, hz) for x, y in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))]
    faces = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    table = api("root.create_entity", f,
                ifc_class="IfcFurnishingElement" if schema == "IFC2X3" else "IfcFurniture",
                name="Table")
    rep = api("geometry.add_mesh_representation", f, context=body, vertices=[verts], faces=[faces])
    api("geometry.assign_representation", f, product=table, representation=rep)
    api("geometry.edit_object_placement", f, product=table,
        matrix=_matrix(8.0, 5.0, 0.0, math.radians(30)))
    api("spatial.assign_container", f, products=[table], relating_structure=container)
    material = api("material.add_material", f, name="Gypsum fibre board")
    pset = api("pset.add_pset", f, product=material, name="Pset_MaterialCommon")
    api("pset.edit_pset", f, pset=pset, properties={"MassDensity": 400.0})
    schedule = None
    if with_tasks and schema != "IFC2X3":
        schedule = api("sequence.add_work_schedule", f, name="Panel installation")
    for p in panels if panels is not None else PANELS:
        cx, cy, cz = p.centre
        # the panel box starts at its placement: move back by half its length, thickness, height
        c, s = math.cos(p.yaw), math.sin(p.yaw)
        x0 = cx - c * PANEL[0] / 2 + s * PANEL[1] / 2
        y0 = cy - s * PANEL[0] / 2 - c * PANEL[1] / 2
        panel = _box(f, body, element_class, p.name, PANEL,
                     _matrix(x0, y0, cz - PANEL[2] / 2, p.yaw))
        api("spatial.assign_container", f, products=[panel], relating_structure=container)
        api("material.assign_material", f, products=[panel], material=material)
        out.panels.append(panel)
        if schedule is not None:
            task = api("sequence.add_task", f, work_schedule=schedule, name=f"Install {p.name}")
            time = api("sequence.add_task_time", f, task=task)
            api("sequence.edit_task_time", f, task_time=time,
                attributes={"ScheduleStart": p.start})
            if link == "product":
                api("sequence.assign_product", f, relating_product=panel, related_object=task)
            else:
                api("sequence.assign_process", f, relating_process=task, related_object=panel)
            out.tasks.append(task)
    for a, b in zip(sequence or [], (sequence or [])[1:], strict=False):
        api("sequence.assign_sequence", f, relating_process=out.tasks[a],
            related_process=out.tasks[b])
    return out


def _mesh_element(f: Any, body: Any, cls: str, name: str,
                  boxes: list[tuple[tuple[float, float, float], tuple[float, float, float]]],
                  container: Any) -> Any:
    """An element whose body is a mesh of closed boxes, each (low corner, high corner) in
    metres (the api converts them to the file's units), placed at the origin."""
    el = api("root.create_entity", f, ifc_class=cls, name=name)
    verts: list[tuple[float, float, float]] = []
    faces: list[list[int]] = []
    for lo, hi in boxes:
        k = len(verts)
        verts += [(x, y, z) for z in (lo[2], hi[2])
                  for x, y in ((lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1]))]
        faces += [[k + i for i in face] for face in
                  ([0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6],
                   [3, 0, 4, 7])]
    rep = api("geometry.add_mesh_representation", f, context=body, vertices=[verts],
              faces=[faces])
    api("geometry.assign_representation", f, product=el, representation=rep)
    api("geometry.edit_object_placement", f, product=el, matrix=np.eye(4))
    if container is not None:
        api("spatial.assign_container", f, products=[el], relating_structure=container)
    return el


HOLE = (7.0, 8.2, 2.1)
"""The doorway cut into the body of the office-store wall: from x, to x, height (m)."""


def real_features(b: Building) -> Building:
    """The three rooms (in millimetres) with what real exports hold: the office-store wall's
    body with a doorway cut into it (:data:`HOLE`, no IfcOpeningElement), a curtain wall of two
    plates and three members outside the north wall, a gable piece 3.0-4.8 m above the west
    wall and a wall with no body."""
    f = b.file
    store = b.walls["Store"]
    for rep in list(store.Representation.Representations):
        api("geometry.unassign_representation", f, product=store, representation=rep)
    half = WALL_T / 2
    x0, x1, top = HOLE
    b.walls["Store"] = _mesh_element(
        f, b.body, "IfcWall", "Store", [
            ((5.0, 3.0 - half, 0.0), (x0, 3.0 + half, WALL_H)),
            ((x1, 3.0 - half, 0.0), (10.0, 3.0 + half, WALL_H)),
            ((x0, 3.0 - half, top), (x1, 3.0 + half, WALL_H)),
        ], b.storey)
    api("root.remove_product", f, product=store)
    curtain = api("root.create_entity", f, ifc_class="IfcCurtainWall", name="Glazing")
    api("spatial.assign_container", f, products=[curtain], relating_structure=b.storey)
    parts = [
        _mesh_element(f, b.body, "IfcPlate", f"Glass {i}",
                      [((1.0 + 1.5 * i, 6.55, 0.1), (2.5 + 1.5 * i, 6.57, 2.4))], None)
        for i in range(2)
    ] + [
        _mesh_element(f, b.body, "IfcMember", f"Mullion {i}",
                      [((0.95 + 1.5 * i, 6.5, 0.0), (1.05 + 1.5 * i, 6.62, 2.5))], None)
        for i in range(3)
    ]
    api("aggregate.assign_object", f, products=parts, relating_object=curtain)
    b.walls["Gable"] = _mesh_element(f, b.body, "IfcWall", "Gable",
                                     [((-0.1, 0.0, 3.0), (0.1, 6.0, 4.8))], b.storey)
    bodiless = api("root.create_entity", f, ifc_class="IfcWall", name="Sketch")
    api("spatial.assign_container", f, products=[bodiless], relating_structure=b.storey)
    b.walls["Sketch"] = bodiless
    return b


WINDOW = (7.0, 8.2, 0.9, 2.1)
"""The window cut into the body of :func:`stepped_top`'s office-store wall: from x, to x, from
z, to z (m)."""


def stepped_top(b: Building) -> Building:
    """The three rooms with the office-store wall's body a mesh with a window cut into it
    (:data:`WINDOW`, no IfcOpeningElement) and a top that steps down from 2.5 m to 2.4 m west
    of the window's east jamb, as a wall runs under a sloping roof."""
    f = b.file
    store = b.walls["Store"]
    half = WALL_T / 2
    x0, x1, z0, z1 = WINDOW
    b.walls["Store"] = _mesh_element(
        f, b.body, "IfcWall", "Store", [
            ((5.0, 3.0 - half, 0.0), (10.0, 3.0 + half, z0)),
            ((5.0, 3.0 - half, z0), (x0, 3.0 + half, 2.4)),
            ((x0, 3.0 - half, z1), (x1, 3.0 + half, 2.4)),
            ((x1, 3.0 - half, z0), (10.0, 3.0 + half, WALL_H)),
        ], b.storey)
    api("root.remove_product", f, product=store)
    return b


def empty_storey(schema: str = "IFC4") -> tuple[Any, Any, Any]:
    """A project in millimetres with a site, a building 'Hall' and an empty storey 'Ground':
    the file, its Body context and the storey."""
    f = ifcopenshell.file(schema=schema)
    project = api("root.create_entity", f, ifc_class="IfcProject", name="Hall")
    api("unit.assign_unit", f, units=[api("unit.add_si_unit", f, unit_type="LENGTHUNIT",
                                          prefix="MILLI")])
    model = api("context.add_context", f, context_type="Model")
    body = api("context.add_context", f, context_type="Model", context_identifier="Body",
               target_view="MODEL_VIEW", parent=model)
    site = api("root.create_entity", f, ifc_class="IfcSite", name="Site")
    building = api("root.create_entity", f, ifc_class="IfcBuilding", name="Hall")
    storey = api("root.create_entity", f, ifc_class="IfcBuildingStorey", name="Ground")
    api("aggregate.assign_object", f, products=[site], relating_object=project)
    api("aggregate.assign_object", f, products=[building], relating_object=site)
    api("aggregate.assign_object", f, products=[storey], relating_object=building)
    return f, body, storey


def add_wall(f: Any, body: Any, storey: Any, name: str, length: float, thickness: float,
             matrix: np.ndarray) -> Any:
    """A 2.5 m high wall of ``length`` and ``thickness`` (m) from its placement ``matrix``
    along its x axis, on ``storey``."""
    wall = api("root.create_entity", f, ifc_class="IfcWall", name=name)
    rep = api("geometry.add_wall_representation", f, context=body, length=length, height=2.5,
              thickness=thickness)
    api("geometry.assign_representation", f, product=wall, representation=rep)
    api("geometry.edit_object_placement", f, product=wall, matrix=matrix)
    api("spatial.assign_container", f, products=[wall], relating_structure=storey)
    return wall


def bim_cli(capsys: Any, *argv: str) -> tuple[int, str, str]:
    """``bt-manip bim ARGV``: its exit code, standard output and error (never a traceback)."""
    from bt_manip.cli import main

    code = main(["bim", *argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err
