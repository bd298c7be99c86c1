"""World groups: several entities of a world file moved together by one rigid motion.

A ``groups:`` entry of a world file names its ``members`` (movable objects, furniture, models
and named poses) and how the group moves::

    groups:
      - name: panel_set
        members: [panel, panel_stand, pregrasp_panel]
        origin: [x, y]            # pivot of the turn (default: the centre of the members)
        move: [dx, dy, dyaw]      # fixed rigid move, the same for every seed
        randomize: {x: [lo, hi], y: [lo, hi], yaw: [lo, hi]}   # offsets drawn per seed

Each group gets one planar rigid transform per world seed: a turn by ``dyaw`` about ``origin``
followed by a shift by ``(dx, dy)``, where each of ``dx``, ``dy`` and ``dyaw`` is the ``move``
value plus the offset drawn from ``randomize`` (seeded by the world seed and the group's name,
as every randomised entity is). Every member's pose is moved by that same transform, so the
members keep their poses relative to each other exactly. A member belongs to one group at
most and cannot have a ``randomize`` of its own. A name that is both a body and a named pose
moves both.

:func:`parse_groups` checks the entries (each problem with its file and line) into
:class:`~bt_manip.sim.world_spec.GroupSpec` records;
:func:`bt_manip.sim.randomize.place_groups` returns the world spec with every group moved for
one seed.
"""

from __future__ import annotations

import difflib
import math
from typing import TYPE_CHECKING, Any

from bt_manip.sim.world_spec import BodySpec, GroupSpec, Range2D, WorldSpec

if TYPE_CHECKING:
    from bt_manip.sim.world_reader import _Reader
    from bt_manip.sim.yaml_lines import LineDict, LineList

GROUP_KEYS = {"name", "members", "origin", "move", "randomize"}

MAX_SHIFT = 1000.0
"""Largest shift (m) a group's ``move`` or ``randomize`` may give along x or y."""
MAX_TURN = 2.0 * math.pi
"""Largest turn (rad) a group's ``move`` or ``randomize`` may give."""
MAX_MEMBERS = 1000
"""Members a group may list at most."""


def parse_groups(rd: _Reader, data: LineDict, spec: WorldSpec) -> list[GroupSpec]:
    """Check the ``groups`` section of a world file against the entities already parsed in
    ``spec``; problems go to ``rd`` with their lines."""
    if "groups" not in data:
        return []
    items = rd.seq(data["groups"], data.line_of("groups"), "groups")
    bodies: dict[str, BodySpec] = {
        b.name: b for b in spec.furniture + spec.objects + spec.models
    }
    other_kinds = {w.name: "a wall" for w in spec.walls}
    other_kinds.update({r.name: "a robot" for r in spec.robots})
    known = sorted(set(bodies) | set(spec.poses))
    owner: dict[str, str] = {}
    names: dict[str, int] = {}
    out: list[GroupSpec] = []
    for _, where, d in rd.entries(items, "groups", GROUP_KEYS):
        name = rd.name(d, where)
        if name in names:
            rd.fail(d.line_of("name"),
                    f"{where}: group name '{name}' is used twice (first at line {names[name]})")
        names.setdefault(name, d.line)
        if name in bodies or name in other_kinds:
            rd.fail(d.line_of("name"), f"{where}: group name '{name}' is already the name of an "
                    "entity; give the group a name of its own")
        members = _members(rd, d, where, name, bodies, other_kinds, known, owner)
        origin = _origin(rd, d, where, members, bodies, spec)
        move = _move(rd, d, where)
        randomize = rd.randomize(d, where)
        _check_ranges(rd, d, where, randomize)
        if members is None or origin is None or move is None:
            continue
        out.append(GroupSpec(name, members, origin, move, randomize, d.line))
    return out


def _members(
    rd: _Reader,
    d: LineDict,
    where: str,
    group: str,
    bodies: dict[str, BodySpec],
    other_kinds: dict[str, str],
    known: list[str],
    owner: dict[str, str],
) -> tuple[str, ...] | None:
    raw = d.get("members")
    if not isinstance(raw, list) or not raw:
        rd.fail(d.line_of("members"), f"{where} ('{group}') needs 'members': a non-empty list "
                "of names of objects, furniture, models or named poses")
        return None
    if len(raw) > MAX_MEMBERS:
        rd.fail(d.line_of("members"), f"{where}.members: {len(raw)} members, at most "
                f"{MAX_MEMBERS} allowed")
        return None
    lines: LineList = raw  # type: ignore[assignment]
    ok = True
    for i, member in enumerate(raw):
        line = lines.line_of(i) if hasattr(lines, "line_of") else d.line_of("members")
        if not isinstance(member, str) or not member:
            rd.fail(line, f"{where}.members[{i}] must be a name, got {member!r}")
            ok = False
            continue
        if member in other_kinds and member not in bodies:
            rd.fail(line, f"{where}.members: '{member}' is {other_kinds[member]}; a group "
                    "moves objects, furniture, models and named poses only")
            ok = False
            continue
        if member not in bodies and member not in known:
            close = difflib.get_close_matches(member, known, n=1)
            hint = (
                f"did you mean '{close[0]}'?" if close else f"known: {', '.join(known) or 'none'}"
            )
            rd.fail(line, f"{where}.members: unknown member '{member}'; {hint}")
            ok = False
            continue
        if member in owner:
            first = owner[member]
            what = (
                "listed twice in this group" if first == group else f"already in group '{first}'"
            )
            rd.fail(line, f"{where}.members: '{member}' is {what}; an entity belongs to "
                    "one group at most")
            ok = False
            continue
        owner[member] = group
        body = bodies.get(member)
        if body is not None and not body.randomize.is_zero():
            rd.fail(line, f"{where}.members: '{member}' has a randomize of its own (line "
                    f"{body.line}); a group member moves only with its group: remove one")
            ok = False
    return tuple(raw) if ok else None


def _origin(
    rd: _Reader,
    d: LineDict,
    where: str,
    members: tuple[str, ...] | None,
    bodies: dict[str, BodySpec],
    spec: WorldSpec,
) -> tuple[float, float] | None:
    if "origin" in d:
        vec = rd.vector(d["origin"], 2, d.line_of("origin"), f"{where}.origin ([x, y])")
        if vec is None:
            return None
        if any(abs(v) > MAX_SHIFT for v in vec):
            rd.fail(d.line_of("origin"), f"{where}.origin must lie within +-{MAX_SHIFT:g} m")
            return None
        return vec[0], vec[1]
    if members is None:
        return None
    points: list[tuple[float, float]] = []
    for member in members:
        if member in bodies:
            points.append((bodies[member].pose.xyz[0], bodies[member].pose.xyz[1]))
        if member in spec.poses:
            points.append((spec.poses[member].x, spec.poses[member].y))
    return (
        sum(p[0] for p in points) / len(points),
        sum(p[1] for p in points) / len(points),
    )


def _move(rd: _Reader, d: LineDict, where: str) -> tuple[float, float, float] | None:
    if "move" not in d:
        return 0.0, 0.0, 0.0
    vec = rd.vector(d["move"], 3, d.line_of("move"), f"{where}.move ([dx, dy, dyaw])")
    if vec is None:
        return None
    if abs(vec[0]) > MAX_SHIFT or abs(vec[1]) > MAX_SHIFT or abs(vec[2]) > MAX_TURN:
        rd.fail(d.line_of("move"), f"{where}.move: shifts must lie within +-{MAX_SHIFT:g} m "
                f"and the turn within +-{MAX_TURN:.4f} rad, got {list(vec)}")
        return None
    return vec[0], vec[1], vec[2]


def _check_ranges(rd: _Reader, d: LineDict, where: str, r: Range2D) -> None:
    if "randomize" not in d or not isinstance(d["randomize"], dict):
        return
    lines: Any = d["randomize"]
    for key, (lo, hi), bound, unit in (
        ("x", r.x, MAX_SHIFT, "m"),
        ("y", r.y, MAX_SHIFT, "m"),
        ("yaw", r.yaw, MAX_TURN, "rad"),
    ):
        if abs(lo) > bound or abs(hi) > bound:
            rd.fail(lines.line_of(key), f"{where}.randomize.{key} must lie within "
                    f"+-{bound:.4g} {unit}, got [{lo}, {hi}]")
