"""``bt-manip bim`` timed: real exports against their parse time, and a generated building.

Run: ``.venv/bin/python benchmarks/bim_convert.py [--rooms N] [--keep DIR] [--samples DIR]
[--repeat N]``

Real exports (the ``.ifc`` files of ``--samples``, by default ``../shared/samples/ifc``): for
each file, the median over ``--repeat`` runs (after one warm-up conversion that loads the
modules and the robot's reach map) of the time to parse it (reading the bytes and
ifcopenshell's parse: the peer every other figure is compared with), to convert it (parse
included, with ``--skip-uninstallable``: an export whose schedule the robot cannot carry out
still becomes a world), and to report the
first error of the same file with one line broken near its end (a copy whose last entity's
class name is misspelt, ``#9= XIFCWALL(...)``: the error must name that line). One JSON
line per file, with the ratios conversion / parse and first error / parse, in wall time and in
CPU time (the process's: on a shared machine the steadier of the two). Each ratio is the
median of the ratios of single rounds, a conversion or a first error against the parses
timed just before and after it (see ``_paired_times``), not a ratio of medians.

Generates with ``ifcopenshell.api`` (in millimetres, IFC4) a storey of N x N rooms of 6 m x 6 m
(default 7 x 7: 112 walls, each room side its own IfcWall, 0.2 m thick and 2.5 m high), with a
1.6 m door in every inner wall and a window in every outer wall, a space and a table in every
room, a slab under everything, and 8 panels (IfcPlate, 1.2 x 0.02 x 0.3 m) on walls across the
building (standing on the floor, within the arm's reach), each the output of an IfcTask, the
tasks chained by IfcRelSequence. The file is
written once, then converted (reading, schedule, walls and openings, floor grid, stock, routes,
world.yaml and schedule.json, and the check that the world file loads) and timed.

Prints one JSON line: walls, openings, spaces, elements, the file's size, and the wall and CPU
seconds of the conversion.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from bt_manip.cli.args import positive

WALL_T = 0.2
WALL_H = 2.5
ROOM = 6.0


def _matrix(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    m = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    m[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    m[:3, 3] = [x, y, z]
    return m


def generate(rooms: int, path: Path) -> dict[str, int]:
    """Write the building of the module docstring to ``path``; returns what it holds."""
    import ifcopenshell
    import ifcopenshell.api

    api = ifcopenshell.api.run
    f = ifcopenshell.file(schema="IFC4")
    project = api("root.create_entity", f, ifc_class="IfcProject", name="Grid of rooms")
    api("unit.assign_unit", f, units=[api("unit.add_si_unit", f, unit_type="LENGTHUNIT",
                                          prefix="MILLI")])
    model = api("context.add_context", f, context_type="Model")
    body = api("context.add_context", f, context_type="Model", context_identifier="Body",
               target_view="MODEL_VIEW", parent=model)
    site = api("root.create_entity", f, ifc_class="IfcSite", name="Site")
    building = api("root.create_entity", f, ifc_class="IfcBuilding", name="Building")
    storey = api("root.create_entity", f, ifc_class="IfcBuildingStorey", name="Level 0")
    api("aggregate.assign_object", f, products=[site], relating_object=project)
    api("aggregate.assign_object", f, products=[building], relating_object=site)
    api("aggregate.assign_object", f, products=[storey], relating_object=building)

    def box(cls: str, name: str, size: tuple[float, float, float], m: np.ndarray) -> Any:
        el = api("root.create_entity", f, ifc_class=cls, name=name)
        rep = api("geometry.add_wall_representation", f, context=body, length=size[0],
                  height=size[2], thickness=size[1])
        api("geometry.assign_representation", f, product=el, representation=rep)
        api("geometry.edit_object_placement", f, product=el, matrix=m)
        if cls not in ("IfcOpeningElement", "IfcSpace"):
            api("spatial.assign_container", f, products=[el], relating_structure=storey)
        return el

    counts = {"walls": 0, "openings": 0, "spaces": 0, "elements": 0}
    walls: list[tuple[Any, np.ndarray]] = []
    span = rooms * ROOM
    for k in range(rooms + 1):  # walls along x at y = k * ROOM, and along y at x = k * ROOM
        for i in range(rooms):
            for along_x in (True, False):
                a = (i * ROOM, k * ROOM) if along_x else (k * ROOM, i * ROOM)
                yaw = 0.0 if along_x else math.pi / 2
                nx, ny = -math.sin(yaw), math.cos(yaw)
                m = _matrix(a[0] - nx * WALL_T / 2, a[1] - ny * WALL_T / 2, 0.0, yaw)
                wall = box("IfcWall", f"Wall {'x' if along_x else 'y'} {k}.{i}",
                           (ROOM, WALL_T, WALL_H), m)
                counts["walls"] += 1
                walls.append((wall, m))
                outer = k in (0, rooms)
                width, sill, height = (1.2, 0.9, 1.2) if outer else (1.6, 0.0, 2.1)
                opening = box("IfcOpeningElement", f"{wall.Name} opening",
                              (width, WALL_T + 0.1, height),
                              m @ _matrix(ROOM / 2 - width / 2, -0.05, sill, 0.0))
                api("feature.add_feature", f, feature=opening, element=wall)
                counts["openings"] += 1
    for i in range(rooms):
        for j in range(rooms):
            x0, y0 = i * ROOM, j * ROOM
            space = box("IfcSpace", f"Room {i}.{j}", (ROOM - WALL_T, ROOM - WALL_T, WALL_H),
                        _matrix(x0 + WALL_T / 2, y0 + WALL_T / 2, 0.0, 0.0))
            api("aggregate.assign_object", f, products=[space], relating_object=storey)
            counts["spaces"] += 1
            box("IfcFurniture", f"Table {i}.{j}", (0.8, 0.5, 0.75),
                _matrix(x0 + ROOM - 1.0, y0 + ROOM - 0.7, 0.0, 0.0))
    box("IfcSlab", "Slab", (span + 0.2, span + 0.2, 0.2), _matrix(-0.1, -0.1, -0.2, 0.0))
    schedule = api("sequence.add_work_schedule", f, name="Panels")
    previous = None
    for n in range(8):  # on the west faces of the rooms' east walls, across the building
        i, j = (n * 5) % rooms, (n * 3) % rooms
        cx, cy = (i + 1) * ROOM - WALL_T / 2 - 0.01, j * ROOM + 1.0
        m = _matrix(cx + 0.01, cy - 0.6, 0.0, math.pi / 2)
        panel = box("IfcPlate", f"Panel {n}", (1.2, 0.02, 0.3), m)
        task = api("sequence.add_task", f, work_schedule=schedule, name=f"Install panel {n}")
        api("sequence.assign_product", f, relating_product=panel, related_object=task)
        if previous is not None:
            api("sequence.assign_sequence", f, relating_process=previous, related_process=task)
        previous = task
        counts["elements"] += 1
    f.write(str(path))
    return counts


def _timed(run: Any) -> tuple[float, float]:
    """Wall and CPU seconds of one call of ``run``."""
    t0, c0 = time.perf_counter(), time.process_time()
    run()
    return time.perf_counter() - t0, time.process_time() - c0


def _paired_times(parse: Any, convert: Any, first_error: Any, repeat: int) -> dict[str, float]:
    """Medians over ``repeat`` rounds of the three times (wall and CPU), and of each round's
    conversion and first error over the parses timed next to them.

    A round parses, converts, parses, reports the first error and parses again; a conversion
    is compared with the mean of the parses just before and after it, the first error with
    the mean of the two around it. This machine's speed drifts by half from one second to
    the next, and a ratio of medians taken over the whole run mixes times from different
    speeds; a ratio within one round does not."""
    rows: dict[str, list[float]] = {k: [] for k in (
        "parse_s", "convert_s", "first_error_s", "parse_cpu_s", "convert_cpu_s",
        "first_error_cpu_s", "convert_over_parse", "first_error_over_parse",
        "convert_over_parse_cpu", "first_error_over_parse_cpu")}
    for _ in range(repeat):
        p0, c, p1, e, p2 = (_timed(parse), _timed(convert), _timed(parse), _timed(first_error),
                            _timed(parse))
        for k, suffix in ((0, ""), (1, "_cpu")):
            rows[f"parse{suffix}_s"] += [p0[k], p1[k], p2[k]]
            rows[f"convert{suffix}_s"].append(c[k])
            rows[f"first_error{suffix}_s"].append(e[k])
            rows[f"convert_over_parse{suffix}"].append(c[k] / ((p0[k] + p1[k]) / 2))
            rows[f"first_error_over_parse{suffix}"].append(e[k] / ((p1[k] + p2[k]) / 2))
    return {k: round(float(np.median(v)), 3 if k.endswith("_s") else 2)
            for k, v in rows.items()}


def broken_copy(path: Path, out: Path) -> tuple[Path, int]:
    """A copy of ``path`` in ``out`` whose last entity line has its class name misspelt (an
    ``X`` put before it), and the number of that line."""
    lines = path.read_bytes().split(b"\n")
    last = max(i for i, text in enumerate(lines) if text.lstrip().startswith(b"#"))
    lines[last] = lines[last].replace(b"=", b"= X", 1)
    broken = out / f"{path.stem}-broken.ifc"
    broken.write_bytes(b"\n".join(lines))
    return broken, last + 1


def time_samples(folder: Path, out: Path, repeat: int) -> None:
    """Print the parse, conversion and first-error times of each IFC file in ``folder``."""
    from bt_manip.bim.convert import BimOptions, convert
    from bt_manip.bim.ifc_input import open_ifc
    from bt_manip.errors import InputError

    for path in sorted(folder.glob("*.ifc")):
        convert(BimOptions(path, out / f"{path.stem}-warm", skip_uninstallable=True))
        broken, line = broken_copy(path, out)

        def first_error(broken: Path = broken, line: int = line) -> None:
            try:
                convert(BimOptions(broken, out / f"{broken.stem}-err"))
            except InputError as exc:
                if f"{broken}:{line}:" not in str(exc):  # the message, with its line number
                    raise AssertionError(f"{broken}: not reported at line {line}: {exc}") from None
            else:
                raise AssertionError(f"{broken}: the broken line {line} was not reported")

        times = _paired_times(lambda path=path: open_ifc(path),
                              lambda path=path: convert(BimOptions(path, out / path.stem,
                                                                   skip_uninstallable=True)),
                              first_error, repeat)
        print(json.dumps({"bench": "bim_convert", "file": path.name,
                          "ifc_bytes": path.stat().st_size, **times}), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rooms", type=positive(int), default=7, help="rooms per side (default 7)")
    parser.add_argument("--keep", type=Path, help="folder to keep the IFC file and outputs in")
    parser.add_argument("--samples", type=Path, default=Path("../shared/samples/ifc"),
                        help="folder of real IFC exports (default ../shared/samples/ifc)")
    parser.add_argument("--repeat", type=positive(int), default=3, help="runs per figure (median)")
    args = parser.parse_args()
    from bt_manip.bim.convert import BimOptions, convert

    if args.samples.is_dir():
        with tempfile.TemporaryDirectory() as tmp:
            time_samples(args.samples, Path(tmp), args.repeat)
    else:
        print(json.dumps({"bench": "bim_convert", "skipped": f"{args.samples} is absent"}))

    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(exist_ok=True)
        ifc = folder / f"grid_{args.rooms}x{args.rooms}.ifc"
        counts = generate(args.rooms, ifc)
        wall0, cpu0 = time.perf_counter(), time.process_time()
        # the panels have no material: at the default density they weigh 3.02 kg, just over
        # the UR3's 3 kg; the payload check is not what is timed here
        conversion = convert(BimOptions(ifc, folder / "out", payload=5.0))
        wall1, cpu1 = time.perf_counter(), time.process_time()
        print(json.dumps({
            "bench": "bim_convert",
            **counts,
            "world_walls": len(conversion.building.walls),
            "ifc_bytes": ifc.stat().st_size,
            "convert_wall_s": round(wall1 - wall0, 3),
            "convert_cpu_s": round(cpu1 - cpu0, 3),
        }))


if __name__ == "__main__":
    main()
