"""``bt-manip bim``: an IFC building and its schedule to ``world.yaml`` and ``schedule.json``.

The steps: read the file (:mod:`~bt_manip.bim.ifc_input`), find the elements to install and
their order (:mod:`~bt_manip.bim.schedule`), read the storey without them
(:mod:`~bt_manip.bim.building`), paint the floor grid, place the stock and the robot, check
that each element can be carried from the stock to its place through the doors
(:mod:`~bt_manip.bim.floor_grid`), and write the world and the schedule. Every problem of the
input is collected and reported as ``file:line: #id IfcClass 'Name': message``.

Last, the installation tree ``DIR/install.xml`` (:mod:`~bt_manip.bim.install_tree`: fetch each
element from its stand, carry it, place and fasten it at its target pose, in schedule order).

An element the robot cannot install is refused with its reason: not a box, on another storey,
heavier than the payload, a top edge out of the arm's reach where it is fetched or placed, too
thick for the gripper (:mod:`~bt_manip.bim.robot_fit`), or no route wide enough from the stock.
Refusals are problems (exit 2, nothing written) unless ``skip_uninstallable``: then the others
are installed and the refused ones listed in schedule.json's ``refused``. With nothing to install
(no schedule, or everything refused), only the world is written (the building, the robot and the
spaces as named poses), unless ``require_install``.
"""

from __future__ import annotations

import gc
import json
import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from bt_manip.bim import require_ifcopenshell
from bt_manip.bim.building import Building, Names, read_building
from bt_manip.bim.doorways import crossings, door_poses
from bt_manip.bim.floor_grid import MARGIN, FloorGrid, Rect
from bt_manip.bim.ifc_input import IfcSource, open_ifc
from bt_manip.bim.install_tree import install_tree
from bt_manip.bim.robot_fit import RobotFit, robot_fit
from bt_manip.bim.routes import CLEARANCE, check_routes, floor_grid, route_problems
from bt_manip.bim.schedule import (
    MAX_ELEMENTS,
    InstallElement,
    PlannedElement,
    schedule_from_csv,
    schedule_from_tasks,
)
from bt_manip.bim.shapes import ShapeReader, UnsupportedGeometry, footprint_box, is_box_like
from bt_manip.bim.stock import (
    Slot,
    StockPose,
    apron_pose,
    element_entry,
    footprint,
    slots,
    stand_entry,
    stand_rects,
    stock_group,
    stock_poses,
)
from bt_manip.bim.storeys import (
    StoreyChoice,
    choose_storey,
    one_level,
    storey_elevation,
    storey_of,
    storey_origin,
)
from bt_manip.bim.world_file import building_entries, r
from bt_manip.bim.world_yaml import world_yaml
from bt_manip.errors import InputError
from bt_manip.outputs import check_output_folder, make_folder
from bt_manip.sim.robot_description import RobotDescription, find_descriptor
from bt_manip.sim.world_reader import check_world

DEFAULT_DENSITY = 420.0
"""Mass density (kg/m3) of an element whose material gives none: a light board, like Scenario
A's panel (1.5 kg for 1.2 x 0.02 x 0.15 m)."""
START_JITTER = 0.2
"""The robot's start is moved by up to this much (m in x and y) per seed; 1.5x that in rad."""
SCHEMA_VERSION = 1
WORK_ZONES = (2.2, 2.0, 1.5, 0.0)
"""Depths (m) of floor kept free of the stock before each element's place, tried in turn: the
robot stands there to place it, and lines up behind."""
MAX_STOCK_TRIALS = 24
"""Stock poses whose routes are checked at most; when none leaves every place reachable, the
first is kept and its problems reported."""
PAYLOADS: dict[str, float] = {"husky_ur3": 3.0}
"""Rated payload (kg) of the arms of known robots: the UR3's is 3 kg (Universal Robots)."""
BAND_MARGIN = 0.1
"""Added (m) to the top of the robot's height band."""
ROUTE_ROUNDS = 4
"""Stock placements tried, refusing the elements without a route each time, at most."""


@dataclass(frozen=True)
class BimOptions:
    """What ``bt-manip bim`` was asked for (frozen: change a copy with
    :func:`dataclasses.replace`)."""

    ifc: Path
    out: Path
    schedule: Path | None = None
    robot: str = "husky_ur3"
    stock: tuple[float, float, float] | None = None
    start_space: str | None = None
    payload: float | None = None
    """Heaviest element (kg) the robot may carry; None: the robot's figure in PAYLOADS."""
    storey: str | None = None
    """Storey name or index (ascending elevation); None: the ground storey."""
    skip_uninstallable: bool = False
    require_install: bool = False


@dataclass
class Conversion:
    """The result: the building read, the elements in order, and the files written."""

    source: Path
    schema: str
    storey: str
    building: Building
    elements: list[InstallElement]
    stock: StockPose
    start: tuple[float, float, float]
    world_path: Path
    schedule_path: Path
    notes: list[str] = field(default_factory=list)
    install_path: Path | None = None
    storey_choice: StoreyChoice | None = None
    refused: list[dict[str, Any]] = field(default_factory=list)
    """Elements refused (with ``skip_uninstallable``): global_id, name, ifc_class, step_id,
    reason."""

    def summary(self) -> str:
        b = self.building
        doors = sum(1 for w in b.walls for o in w.openings if o.passage)
        closed = sum(1 for w in b.walls for o in w.openings if not o.passage)
        xmin, ymin, xmax, ymax = b.extent
        lines = [
            f"{self.source}: {self.schema}, storey '{self.storey}', "
            f"{xmax - xmin:.2f} m x {ymax - ymin:.2f} m",
        ]
        if self.storey_choice is not None:
            lines.append(f"  {self.storey_choice.text()}")
        lines += [
            f"  read {b.read_text()}",
            f"  {_count(len(b.walls), 'wall')} with {_count(doors, 'passage')} and "
            f"{_count(closed, 'closed opening')} (windows), {_count(len(b.spaces), 'space')}, "
            f"{_count(len(b.furniture), 'piece')} of furniture",
        ]
        if self.elements:
            lines.append(
                f"  stock at ({self.stock.x:.2f}, {self.stock.y:.2f}) heading "
                f"{math.degrees(self.stock.yaw):.0f} deg; robot start at ({self.start[0]:.2f}, "
                f"{self.start[1]:.2f})")
        else:
            lines.append(f"  robot start at ({self.start[0]:.2f}, {self.start[1]:.2f})")
        lines.append(f"  {len(self.elements)} elements to install"
                     + (", in order:" if self.elements else ""))
        for e in self.elements:
            t = e.target
            lines.append(
                f"  {e.order:3d}. {e.ifc_class} '{e.name}' ({e.global_id}) -> ({t['x']:.3f}, "
                f"{t['y']:.3f}, {t['z']:.3f}) yaw {math.degrees(t['yaw']):.1f} deg, "
                f"{e.size[0]:.2f} x {e.size[1]:.2f} x {e.size[2]:.2f} m, {e.mass:.2f} kg"
                + (f", task '{e.task}'" if e.task else "")
                + (f", start {e.start}" if e.start else "")
            )
        lines += [f"  refused: {r['ifc_class']} '{r['name']}' ({r['global_id']}): {r['reason']}"
                  for r in self.refused]
        lines += [f"  note: {n}" for n in self.notes]
        written = [self.world_path]
        written += [self.schedule_path] if self.schedule_path.is_file() else []
        written += [self.install_path] if self.install_path is not None else []
        if len(written) == 1:
            lines.append(f"wrote {written[0]}")
        else:
            lines.append("wrote " + ", ".join(str(p) for p in written[:-1])
                         + f" and {written[-1]}")
        return "\n".join(lines)


def _shift_text(shift: tuple[float, float]) -> str:
    """``; the model's x, y = the world's + (114503, 1185944) m``, or nothing."""
    if shift == (0.0, 0.0):
        return ""
    return f"; the model's x, y = the world's + ({shift[0]:.0f}, {shift[1]:.0f}) m"


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def convert(options: BimOptions) -> Conversion:
    """Read the building, check it, write the world and the schedule; InputError on problems.

    Python's cycle collector is paused while it runs (:func:`paused_cycle_collection`)."""
    with paused_cycle_collection():
        return _convert(options)


@contextmanager
def paused_cycle_collection() -> Iterator[None]:
    """Pause Python's cycle collector for the block, then restore it as it was.

    A conversion makes about a hundred thousand short-lived Python objects (ifcopenshell's
    entity proxies, tuples of coordinates, small lists), none of which form reference cycles;
    each 700 of them would start a collection, every tenth of those one over older objects
    too, and now and then one over all the process's objects (the modules of numpy, scipy and
    ifcopenshell among them). Reference
    counting frees everything the conversion drops, as it goes; what cycles there are wait for
    the collector to run again after the block."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def _convert(options: BimOptions) -> Conversion:
    require_ifcopenshell()
    check_output_folder("--out", options.out)
    descriptor = find_descriptor(options.robot)
    if descriptor is None:
        raise InputError.single("--robot", None, f"unknown robot '{options.robot}'")
    source = open_ifc(options.ifc)
    if options.schedule is not None:
        planned = schedule_from_csv(source, options.schedule)
    else:
        planned = schedule_from_tasks(source)
    if not planned and (options.require_install or options.schedule is not None):
        _no_elements(source, options)
    if len(planned) > MAX_ELEMENTS:
        raise InputError.single(
            str(source.path), None,
            f"{len(planned)} elements to install, more than the limit of {MAX_ELEMENTS}",
        )
    robot = RobotDescription.load(descriptor)
    fp = robot.footprint
    robot_width = 2 * fp.radius if fp.is_circle else fp.width
    robot_radius = fp.circumradius

    fit = robot_fit(robot)
    choice = choose_storey(source, options.storey)
    storey = choice.storey
    floor_z = storey_elevation(source, storey)
    source.shift = model_shift(source, storey)
    names = Names()
    refusals: list[tuple[Any, str]] = []
    elements = _elements(source, planned, choice, floor_z, names, refusals)
    source.raise_problems()
    elements = _refuse(source, options, elements, refusals)
    checks = robot_checks(source, elements, options, fit)
    refusals += checks
    elements = _refuse(source, options, elements, checks)
    band_top = max([fit.tucked_top] + [e.target["z"] + e.size[2] / 2 for e in elements]
                   + [e.size[2] for e in elements]) + BAND_MARGIN
    building = read_building(source, storey, {p.entity.id() for p in planned}, names, band_top)
    source.raise_problems()

    world_stands: list[dict[str, Any]] = []
    world_objects: list[dict[str, Any]] = []
    stock = StockPose(0.0, 0.0, 0.0)
    apron = (0.0, 0.0, 0.0)
    slot_of: dict[int, Slot] = {}
    for _ in range(ROUTE_ROUNDS):
        grid = floor_grid(building)
        if not elements:
            break
        sizes = [(e.size[0], e.size[1], e.size[2]) for e in elements]
        stock = _stock_pose(options, source, building, grid, sizes, elements, robot_width)
        for e, size, slot in zip(elements, sizes, slots(stock, sizes), strict=True):
            slot_of[e.step_id] = slot
            e.stock = {"x": r(slot.x), "y": r(slot.y), "z": r(size[2] / 2 + 0.0005),
                       "yaw": r(slot.yaw)}
            for rect in stand_rects(slot, size):
                grid.block(rect)
        apron = apron_pose(stock, sizes)
        issues = route_problems(building, grid, elements, apron, robot_width)
        if not issues:
            break
        if any(e is None for e, _ in issues) or not options.skip_uninstallable:
            check_routes(source, building, grid, elements, apron, robot_width)
            source.raise_problems()
        routes = [(source.model.by_id(e.step_id), why) for e, why in issues if e is not None]
        refusals += routes
        elements = _refuse(source, options, elements, routes)
    if not elements and options.require_install:
        _no_elements(source, options, refused=bool(refusals))
    for e in elements:
        size = (e.size[0], e.size[1], e.size[2])
        world_stands.append(stand_entry(names.make(f"stand_{e.object}", "stand"),
                                        slot_of[e.step_id], size))
        world_objects.append(element_entry(e.object, slot_of[e.step_id], size, e.mass))
    cross = crossings(building, grid, elements, apron, robot_width) if elements else {}
    start, jitter = _robot_start(options, building, grid, robot_radius)

    walls, furniture = building_entries(building)
    poses: dict[str, list[float]] = {"start": [r(v) for v in start]}
    if elements:
        poses["stock"] = [r(v) for v in apron]
    poses.update(door_poses({c.door for cs in cross.values() for c in cs}, building))
    for space in sorted(building.spaces, key=lambda s: s.entity.id()):
        spot = None
        # room to turn on the spot there (a Navigate goal), else room to stand
        for half in (robot_radius + CLEARANCE, robot_width / 2 + CLEARANCE):
            spot = grid.nearest_clear(space.box.centre[0], space.box.centre[1], half,
                                      within=_space_rect(space))
            if spot is not None:
                break
        if spot is not None:
            space.key = _pose_key(space.name, poses)
            poses[space.key] = [r(spot[0]), r(spot[1]), 0.0]
    world: dict[str, Any] = {
        "name": _world_name(source.path),
        "description": (
            f"generated by bt-manip bim from {source.path.name} ({source.schema}), storey "
            f"'{storey.Name or storey.id()}'; floor extent "
            + ", ".join(f"{v:.2f}" for v in building.extent)
            + " m (xmin, ymin, xmax, ymax)" + _shift_text(source.shift)
        ),
        "walls": walls,
        "furniture": furniture + world_stands,
        "objects": world_objects,
        "robots": [
            {
                "name": "robot",
                "description": options.robot,
                "pose": [r(v) for v in start],
            }
        ],
        "poses": poses,
    }
    if elements:
        world["groups"] = [
            stock_group(stock, [e["name"] for e in world_stands + world_objects] + ["stock"])
        ]
    if "tuck" in robot.states:
        world["robots"][0]["arm_state"] = "tuck"
    if jitter > 0:
        world["robots"][0]["randomize"] = {
            "x": [-jitter, jitter], "y": [-jitter, jitter], "yaw": [-1.5 * jitter, 1.5 * jitter]
        }
    make_folder(options.out)
    world_path = options.out / "world.yaml"
    schedule_path = options.out / "schedule.json"
    header = (
        f"# Generated by `bt-manip bim {source.path.name}`: the building's walls, openings,\n"
        "# furniture and spaces, the elements to install waiting in stands at the stock\n"
        "# (their order and target poses are in schedule.json), and the robot.\n"
    )
    world_path.write_text(header + world_yaml(world))
    conversion = Conversion(
        source.path, source.schema, str(storey.Name or f"#{storey.id()}"), building, elements,
        stock, start, world_path, schedule_path, list(building.notes), storey_choice=choice,
        refused=[_refused_entry(el, why) for el, why in refusals],
    )
    if source.shift != (0.0, 0.0):
        conversion.notes.append(
            f"the storey lies {math.hypot(*source.shift) / 1000:,.1f} km from the model's "
            f"origin: the world is moved{_shift_text(source.shift)}")
    if not elements:
        conversion.notes.append(_no_elements_text(source, options, refused=bool(refusals),
                                                  required=False)
                                + "; the world holds the building alone")
    if planned:
        schedule_path.write_text(
            json.dumps(_schedule_document(conversion, options), indent=2) + "\n")
    elif schedule_path.is_file():
        schedule_path.unlink()  # an earlier conversion's: not this world's
    _check_world(world_path)
    install_path = options.out / "install.xml"
    if elements:
        conversion.install_path = install_path
        install_path.write_text(install_tree(elements, source.path.name, cross))
    elif install_path.is_file():
        install_path.unlink()
    return conversion


FAR_AWAY = 1000.0
"""A storey placed farther (m) from the model's origin moves the world (:func:`model_shift`)."""


def model_shift(source: IfcSource, storey: Any) -> tuple[float, float]:
    """What is subtracted (m) from the model's x and y to give the world's: the storey's
    position rounded to whole metres when it lies more than :data:`FAR_AWAY` from the
    model's origin (an export in surveyed coordinates, a kilometre or a thousand away: the
    simulation's single-precision physics would be centimetres coarse there), else nothing."""
    origin = storey_origin(source, storey)
    if origin is None:
        return (0.0, 0.0)
    x, y, _ = origin
    if math.hypot(x, y) <= FAR_AWAY:
        return (0.0, 0.0)
    return (float(round(x)), float(round(y)))


def _refused_entry(element: Any, reason: str) -> dict[str, Any]:
    return {"global_id": str(element.GlobalId), "name": str(element.Name or ""),
            "ifc_class": element.is_a(), "step_id": int(element.id()), "reason": reason}


def _refuse(source: IfcSource, options: BimOptions, elements: list[InstallElement],
            refusals: list[tuple[Any, str]]) -> list[InstallElement]:
    """Without ``skip_uninstallable``, every refusal is a problem (raised); with it, the
    refused elements are left out (and ``refusals`` kept for the schedule)."""
    if not refusals:
        return elements
    if not options.skip_uninstallable:
        for entity, why in refusals:
            source.fail(entity, why)
        source.raise_problems()
    gone = {int(entity.id()) for entity, _ in refusals}
    out = [e for e in elements if e.step_id not in gone]
    for order, e in enumerate(out, start=1):
        e.order = order
    return out


def robot_checks(source: IfcSource, elements: list[InstallElement], options: BimOptions,
                 fit: RobotFit) -> list[tuple[Any, str]]:
    """Every element the robot cannot handle, with its reason: heavier than its payload, a
    top edge out of its arm's reach where it is fetched (standing in its stand) or placed, or
    thicker than its gripper opens."""
    out: list[tuple[Any, str]] = []
    payload = payload_of(options)
    where = "--payload" if options.payload is not None else f"the {options.robot}'s rated payload"
    for e in elements:
        entity = source.model.by_id(e.step_id)
        if payload is not None and e.mass > payload:
            out.append((entity, f"{e.mass:.2f} kg ({e.mass_source}), heavier than the "
                                f"{payload:g} kg the robot can carry ({where}): not to be "
                                "installed by it"))
        thickness, height = e.size[1], e.size[2]
        place_top = e.target["z"] + height / 2
        for label, top in (("where it is placed", place_top), ("in its stand", height)):
            if not fit.top_edge_reached(top, height):
                out.append((entity, f"its top edge {label}, {top:.2f} m above the floor, is "
                                    f"out of the {options.robot}'s reach for a grasp from above "
                                    f"(top edges at {fit.reach_text()})"))
        if not fit.grips(thickness):
            opening = fit.max_opening * 100
            out.append((entity, f"{thickness * 100:.1f} cm thick, too thick for the "
                                f"{options.robot}'s gripper, which opens {opening:.1f} cm (1 cm "
                                "of it kept free)"))
    return out


def payload_of(options: BimOptions) -> float | None:
    """The payload (kg) elements are checked against: ``--payload``, else the robot's figure
    in :data:`PAYLOADS`; None when neither is known."""
    if options.payload is not None:
        return options.payload
    return PAYLOADS.get(options.robot)


def _no_elements(source: IfcSource, options: BimOptions, refused: bool = False) -> None:
    """Raise the problem of a conversion with nothing to install (``--require-install``)."""
    message = _no_elements_text(source, options, refused)
    if options.schedule is not None and not refused:
        raise InputError.single(str(options.schedule), None, message)
    projects = source.model.by_type("IfcProject")
    if projects:
        raise InputError([source.problem(projects[0], message)])
    raise InputError.single(str(source.path), None, message)


def _no_elements_text(source: IfcSource, options: BimOptions, refused: bool = False,
                      required: bool = True) -> str:
    """Why there is nothing to install: a problem when ``required`` (``--require-install``),
    else a note."""
    if refused:
        message = "nothing to install: every element was refused " + (
            "(see --skip-uninstallable's list), and --require-install asks for one" if required
            else "(schedule.json's 'refused' lists each with its reason)")
    elif options.schedule is not None:
        message = "the schedule lists no element"
    elif source.schema == "IFC2X3":
        message = (
            "no element to install: schedules are read from IFC4 files only; give the order "
            "of an IFC2X3 file's elements with --schedule FILE.csv (GlobalId,start)"
        )
    else:
        message = (
            "no element to install: no IfcTask is linked (IfcRelAssignsToProduct or "
            "IfcRelAssignsToProcess) to an IfcPlate, IfcMember or IfcWall; link them or give "
            "--schedule FILE.csv (GlobalId,start)"
        )
    return message


def _elements(
    source: IfcSource, planned: list[PlannedElement], choice: StoreyChoice, floor_z: float,
    names: Names, refusals: list[tuple[Any, str]],
) -> list[InstallElement]:
    """Target pose, size and mass of each element to install (on the chosen storey); an
    element elsewhere, or not a box, goes to ``refusals`` with its reason."""
    import ifcopenshell.util.element as util

    storey = choice.storey
    reader = ShapeReader(source.scale, source.model, source.shift)
    single = one_level(source.model)
    out: list[InstallElement] = []
    for i, p in enumerate(planned):
        el = p.entity
        if not single:
            on = storey_of(el)
            if on is None or on.id() != storey.id():
                where = f"storey '{on.Name}'" if on is not None else "no storey"
                refusals.append((
                    el,
                    f"it is on {where}; the world is built from storey '{storey.Name}' "
                    f"({choice.reason}) only",
                ))
                continue
        try:
            solid = reader.solid(el)
        except UnsupportedGeometry as exc:
            refusals.append((el, f"unsupported geometry: {exc}"))
            continue
        box = footprint_box(solid.points, reader.yaw(el))
        if not is_box_like(solid, box):
            refusals.append((
                el,
                "unsupported geometry: an element to install must be an upright box; its body "
                f"fills {solid.volume / max(box.volume, 1e-12):.0%} of its upright bounding box "
                f"({box.size[0]:.3f} x {box.size[1]:.3f} x {box.size[2]:.3f} m)",
            ))
            continue
        density, where = None, ""
        for material in util.get_materials(el):
            for pset in util.get_psets(material).values():
                value = pset.get("MassDensity")
                if isinstance(value, int | float) and value > 0:
                    density, where = float(value), f"MassDensity of '{material.Name}'"
                    break
            if density is not None:
                break
        if density is None:
            density, where = DEFAULT_DENSITY, f"default density {DEFAULT_DENSITY:g} kg/m3"
        x, y, z = box.centre
        out.append(
            InstallElement(
                order=i + 1,
                global_id=str(el.GlobalId),
                name=str(el.Name or ""),
                ifc_class=el.is_a(),
                step_id=int(el.id()),
                object=names.make(el.Name, f"element_{el.id()}"),
                target={"x": r(x), "y": r(y), "z": r(z - floor_z), "yaw": r(box.yaw)},
                size=[r(s) for s in box.size],
                mass=r(density * solid.volume),
                mass_source=where,
                task=p.task,
                start=p.start,
                stock={},
            )
        )
    return out


def _space_rect(space: Any) -> Rect:
    b = space.box
    return Rect(b.centre[0], b.centre[1], b.size[0], b.size[1], b.yaw)


def _largest_space(building: Building) -> Rect:
    if building.spaces:
        space = max(building.spaces, key=lambda s: (s.box.size[0] * s.box.size[1], -s.entity.id()))
        return _space_rect(space)
    xmin, ymin, xmax, ymax = building.extent
    return Rect((xmin + xmax) / 2, (ymin + ymax) / 2, xmax - xmin, ymax - ymin)


def _free_areas(building: Building) -> tuple[list[Rect], str]:
    """Where the robot's start or the stock is looked for, in turn, and how to name it: the
    largest space; without spaces, the building's extent, then the floor around it too (a
    single wall or a row of columns leaves no room within its own extent)."""
    area = _largest_space(building)
    if building.spaces:
        return [area], "the largest space"
    return [area, area.grown(MARGIN)], "the building's extent or the floor around it"


def _with_work_zones(grid: FloorGrid, elements: list[InstallElement], depth: float) -> FloorGrid:
    """A copy of ``grid`` with the floor ``depth`` m deep on both sides of each element's place
    blocked (where the robot stands and lines up to place it; 0: none)."""
    import copy

    if depth <= 0:
        return grid
    out = copy.deepcopy(grid)
    for e in elements:
        t = e.target
        c, s = math.cos(t["yaw"]), math.sin(t["yaw"])
        for side in (1.0, -1.0):
            d = side * (depth + e.size[1]) / 2
            out.block(Rect(t["x"] - s * d, t["y"] + c * d, e.size[0] + 0.4, depth, t["yaw"]))
    return out


def _routes_clear(
    source: IfcSource, building: Building, grid: FloorGrid, elements: list[InstallElement],
    sizes: list[tuple[float, float, float]], pose: StockPose, robot_width: float,
) -> bool:
    """Whether, with the stock at ``pose``, every element can be carried to its place."""
    import copy

    trial = copy.deepcopy(grid)
    for size, slot in zip(sizes, slots(pose, sizes), strict=True):
        for rect in stand_rects(slot, size):
            trial.block(rect)
    before = len(source.problems)
    check_routes(source, building, trial, elements, apron_pose(pose, sizes), robot_width)
    ok = len(source.problems) == before
    del source.problems[before:]
    return ok


def _stock_pose(
    options: BimOptions, source: IfcSource, building: Building, grid: FloorGrid,
    sizes: list[tuple[float, float, float]], elements: list[InstallElement],
    robot_width: float,
) -> StockPose:
    if options.stock is not None:
        pose = StockPose(*options.stock)
        rect = footprint(pose, sizes)
        if not grid.is_free(rect):
            raise InputError.single(
                "--stock", None,
                f"the stock area ({rect.length:.2f} m x {rect.width:.2f} m with its apron, "
                f"centred at ({rect.x:.2f}, {rect.y:.2f})) overlaps a wall, a closed opening "
                "or furniture; give a free spot",
            )
        return pose
    areas, label = _free_areas(building)
    for area in areas:
        placed = None
        trials = 0
        for depth in WORK_ZONES:  # keep the floor before the places free, if there is room
            for pose in stock_poses(_with_work_zones(grid, elements, depth), area, sizes):
                placed = placed or pose
                if trials >= MAX_STOCK_TRIALS:
                    break
                trials += 1
                if _routes_clear(source, building, grid, elements, sizes, pose, robot_width):
                    return pose
        if placed is not None:
            return placed
    raise InputError.single(
        str(source.path), None,
        f"no free spot for the stock ({len(sizes)} stands) in {label}: give one with "
        "--stock X;Y;YAW",
    )


def _robot_start(
    options: BimOptions, building: Building, grid: FloorGrid, robot_radius: float
) -> tuple[tuple[float, float, float], float]:
    """The robot's start (nearest the centre of its space with room to turn) and jitter."""
    areas, label = _free_areas(building)
    where = str(options.ifc)
    if options.start_space is not None:
        wanted = options.start_space.lower()
        match = [s for s in building.spaces if s.name.lower() == wanted or
                 _pose_key(s.name, {}) == wanted]
        if not match:
            known = ", ".join(sorted(s.name for s in building.spaces)) or "none"
            raise InputError.single("--start", None,
                                    f"no space named '{options.start_space}'; spaces: {known}")
        areas = [_space_rect(match[0])]
        label = f"space '{match[0].name}'"
        where = "--start"
    for area in areas:
        for jitter in (START_JITTER, 0.0):
            half = robot_radius + jitter * math.sqrt(2) + CLEARANCE
            spot = grid.nearest_clear(area.x, area.y, half, within=area)
            if spot is not None:
                return (spot[0], spot[1], area.yaw), jitter
    raise InputError.single(
        where, None,
        f"no free spot for the robot ({2 * robot_radius:.2f} m across) in {label}",
    )


def _pose_key(name: str, taken: dict[str, Any]) -> str:
    import re

    base = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_").lower() or "space"
    key, n = base, 2
    while key in taken:
        key, n = f"{base}_{n}", n + 1
    return key


def _world_name(path: Path) -> str:
    import re

    return re.sub(r"[^A-Za-z0-9_]+", "_", path.stem).strip("_") or "building"


def _schedule_document(c: Conversion, options: BimOptions) -> dict[str, Any]:
    return {
        "schema_version": SCHEMA_VERSION,
        "source": str(c.source),
        "ifc_schema": c.schema,
        "storey": c.storey,
        "units": {"length": "m", "angle": "rad", "mass": "kg"},
        "robot": options.robot,
        "world": c.world_path.name,
        "stock": {"x": r(c.stock.x), "y": r(c.stock.y), "yaw": r(c.stock.yaw)},
        "spaces": [
            {
                "name": s.name,
                "pose": s.key or None,
                "global_id": str(s.entity.GlobalId),
                "centre": [r(s.box.centre[0]), r(s.box.centre[1])],
                "size": [r(s.box.size[0]), r(s.box.size[1])],
                "yaw": r(s.box.yaw),
            }
            for s in c.building.spaces
        ],
        "elements": [asdict(e) for e in c.elements],
        "refused": list(c.refused),
    }


def _check_world(path: Path) -> None:
    """The written world must load: a problem here is bt-manip's, reported as such."""
    check_world(path)
