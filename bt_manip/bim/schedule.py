"""Which elements are installed, in which order: the file's 4D schedule or a CSV.

In an IFC4 file, an element to install (an IfcPlate, IfcMember or IfcWall) is linked to an
IfcTask either as the task's output (IfcRelAssignsToProduct: the task is a related object, the
element the relating product, as Bonsai writes it) or as an object assigned to the task
(IfcRelAssignsToProcess). Tasks are ordered by their IfcRelSequence links (a task comes after
its predecessors), and tasks free to go at the same point (ties, tasks without sequence links)
by their IfcTaskTime.ScheduleStart, then by name. A CSV ``GlobalId,start`` (given with
``--schedule``; the only source for IFC2X3 files) orders the elements by ``start`` (an ISO 8601
date or date-time, or a number), ties in the order of the rows.
"""

from __future__ import annotations

import csv
import heapq
import io
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

from bt_manip.bim.ifc_input import IfcSource, check_count
from bt_manip.errors import InputError, Problem
from bt_manip.input_files import MIB, read_bounded

INSTALLABLE = ("IfcPlate", "IfcMember", "IfcWall")
"""IFC classes (and their subtypes) of the elements that can be installed."""
MAX_TASKS = 20000
MAX_ELEMENTS = 500
"""Elements to install at most (each becomes a world object and a stand)."""
MAX_CSV_BYTES = 1 * MIB


@dataclass
class PlannedElement:
    """An element to install, as the schedule gives it (before its geometry is read)."""

    entity: Any
    task: str | None
    start: str | None


@dataclass
class InstallElement:
    """One element to install, in schedule order, with everything a tree needs about it."""

    order: int
    global_id: str
    name: str
    ifc_class: str
    step_id: int
    object: str
    """Name of the world object standing for it."""
    target: dict[str, float]
    """Pose of its centre once installed: x, y, z (m, floor at z = 0) and yaw (rad)."""
    size: list[float]
    """Length along its yaw, width (thickness), height (m)."""
    mass: float
    mass_source: str
    task: str | None
    start: str | None
    stock: dict[str, float]
    """Pose of its centre in its stand at the stock (before the per-seed jitter)."""


def _time_key(text: str | None) -> tuple[int, float]:
    """Sort key of a start: unset last."""
    if text is None:
        return (1, 0.0)
    try:
        return (0, datetime.fromisoformat(text).timestamp())
    except ValueError:
        return (1, 0.0)


def schedule_from_tasks(source: IfcSource) -> list[PlannedElement]:
    """The installable elements linked to tasks, in task order (see the module docstring)."""
    model = source.model
    if model.schema == "IFC2X3":
        return []
    tasks = model.by_type("IfcTask")
    check_count(source, "IfcTask", tasks, MAX_TASKS)
    if not tasks:
        return []
    task_ids = {t.id() for t in tasks}
    outputs: dict[int, list[Any]] = {t.id(): [] for t in tasks}
    for rel in model.by_type("IfcRelAssignsToProduct"):
        product = rel.RelatingProduct
        for obj in rel.RelatedObjects or []:
            if obj.id() in task_ids:
                outputs[obj.id()].append(product)
    for rel in model.by_type("IfcRelAssignsToProcess"):
        process = rel.RelatingProcess
        if process is not None and process.id() in task_ids:
            outputs[process.id()].extend(rel.RelatedObjects or [])
    starts: dict[int, str | None] = {}
    for t in tasks:
        time = getattr(t, "TaskTime", None)
        start = getattr(time, "ScheduleStart", None) if time is not None else None
        if start is not None and _time_key(start)[0] == 1:
            source.fail(time, f"ScheduleStart '{start}' is not an ISO 8601 date-time")
            start = None
        starts[t.id()] = start
    successors: dict[int, list[int]] = {t.id(): [] for t in tasks}
    indegree = dict.fromkeys(task_ids, 0)
    for rel in model.by_type("IfcRelSequence"):
        a, b = rel.RelatingProcess, rel.RelatedProcess
        if a is None or b is None or a.id() not in task_ids or b.id() not in task_ids:
            continue
        successors[a.id()].append(b.id())
        indegree[b.id()] += 1
    by_id = {t.id(): t for t in tasks}

    def key(tid: int) -> tuple[Any, ...]:
        return (_time_key(starts[tid]), by_id[tid].Name or "", tid)

    ready = [key(tid) for tid, n in indegree.items() if n == 0]
    heapq.heapify(ready)
    order: list[int] = []
    while ready:
        tid = heapq.heappop(ready)[-1]
        order.append(tid)
        for nxt in successors[tid]:
            indegree[nxt] -= 1
            if indegree[nxt] == 0:
                heapq.heappush(ready, key(nxt))
    if len(order) < len(tasks):
        stuck = sorted(tid for tid, n in indegree.items() if n > 0)
        for rel in model.by_type("IfcRelSequence"):
            if rel.RelatedProcess is not None and rel.RelatedProcess.id() == stuck[0]:
                source.fail(rel, "the task sequences form a cycle: no order satisfies them all")
                break
        source.raise_problems()
    out: list[PlannedElement] = []
    seen: set[int] = set()
    for tid in order:
        for el in outputs[tid]:
            if el.id() in seen or not any(el.is_a(c) for c in INSTALLABLE):
                continue
            seen.add(el.id())
            out.append(PlannedElement(el, by_id[tid].Name, starts[tid]))
    return out


def schedule_from_csv(source: IfcSource, path: str | Path) -> list[PlannedElement]:
    """The elements a CSV ``GlobalId,start`` names, ordered by start (ties by row)."""
    path = Path(path)
    data = read_bounded(path, MAX_CSV_BYTES, "schedule file")
    name = str(path)
    problems: list[Problem] = []
    rows: list[tuple[tuple[int, Any], int, Any, str]] = []
    kinds: set[str] = set()
    seen: dict[str, int] = {}
    text = data.decode("utf-8-sig", errors="replace")
    reader = csv.reader(io.StringIO(text))
    for index, row in enumerate(reader):
        line = reader.line_num  # the row's last line (a quoted field may span lines)
        cells = [c.strip() for c in row]
        if not cells or all(not c for c in cells) or cells[0].startswith("#"):
            continue
        if index == 0 and cells[0].lower() == "globalid":
            continue
        if len(cells) != 2:
            problems.append(
                Problem(name, line, f"expected 'GlobalId,start', got {len(cells)} fields")
            )
            continue
        gid, start = cells
        if len(rows) >= MAX_ELEMENTS:
            problems.append(
                Problem(name, line, f"more than {MAX_ELEMENTS} elements to install (the limit)")
            )
            break
        sort_key: tuple[int, Any]
        try:
            sort_key = (0, float(start))
            kinds.add("number")
        except ValueError:
            try:
                sort_key = (0, datetime.fromisoformat(start).timestamp())
                kinds.add("date")
            except ValueError:
                problems.append(
                    Problem(
                        name, line,
                        f"start '{start}' is neither a number nor an ISO 8601 date or date-time",
                    )
                )
                continue
        if len(kinds) > 1:
            problems.append(Problem(name, line, "starts mix numbers and dates; use one kind"))
            continue
        try:
            entity = source.model.by_guid(gid)
        except RuntimeError:
            entity = None
        if entity is None:
            problems.append(
                Problem(
                    name, line, f"unknown GlobalId '{gid}': no entity of {source.path.name} has it"
                )
            )
            continue
        if not any(entity.is_a(c) for c in INSTALLABLE):
            where = source.problem(entity, "").message.rstrip(": ")
            problems.append(
                Problem(
                    name, line,
                    f"GlobalId '{gid}' is {where}; only IfcPlate, IfcMember and IfcWall elements "
                    "are installed",
                )
            )
            continue
        if gid in seen:
            problems.append(
                Problem(name, line, f"GlobalId '{gid}' is listed twice (first at line {seen[gid]})")
            )
            continue
        seen[gid] = line
        rows.append((sort_key, line, entity, start))
    if problems:
        raise InputError(problems)
    rows.sort(key=lambda r: (r[0], r[1]))
    return [PlannedElement(entity, None, start) for _, _, entity, start in rows]
