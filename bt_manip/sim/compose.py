"""URDF composition: several URDF files grafted into one robot, with every mesh path resolved.

PyBullet and Pinocchio must read the very same file, and committed files carry no absolute
paths. A robot is therefore either one URDF file or a :class:`Recipe`: a ``base`` URDF plus
:class:`Attachment` s (another URDF hung from a link of the tree built so far by a fixed joint),
with optional joint-limit overrides. :func:`composed_urdf` writes the result, meshes as absolute
paths on this machine, to a cache folder (``$BT_MANIP_CACHE`` or ``~/.cache/bt-manip/urdf``)
under a name keyed by a hash of every input, and returns its path. The write is atomic (temporary
file + rename), so several processes may compose the same robot at once.

What composition does to each input file:

- mesh ``filename`` s become absolute paths (``package://``, ``pybullet_data://`` and paths
  relative to the file, see :mod:`bt_manip.sim.assets`);
- ``gazebo`` and ``transmission`` elements are dropped (neither engine reads them);
- the links named in ``drop_links`` are removed with every joint touching them;
- attached links and joints get ``link_prefix`` / ``joint_prefix`` (names must stay unique);
- links without an ``inertial`` get a tiny one (PyBullet would otherwise invent 1 kg);
- xacro leftovers ``$(optenv NAME default)`` in attributes are replaced by their default
  (Pinocchio's URDF parser rejects them).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, cast

import defusedxml.ElementTree as SafeET

from bt_manip.cache import Memo, bytes_key
from bt_manip.cache import cache_dir as shared_cache_dir
from bt_manip.errors import InputError, Problem
from bt_manip.input_files import line_of_text, read_bounded
from bt_manip.sim.assets import resolve_uri
from bt_manip.sim.mesh_check import mesh_problem
from bt_manip.sim.urdf_bounds import check_urdf_size
from bt_manip.sim.yaml_lines import FieldReader

if TYPE_CHECKING:
    from bt_manip.sim.robot_description import RobotDescription

COMPOSER_VERSION = 2
"""Bumped whenever the output of composition changes for the same inputs."""

MAX_URDF_BYTES = 8 * 1024 * 1024
FILLER_MASS = 0.001
FILLER_INERTIA = 1e-7
DROPPED_TAGS = ("gazebo", "transmission")
OPTENV = re.compile(r"\$\(optenv\s+\S+\s*([^)]*)\)")
LIMIT_KEYS = ("lower", "upper", "velocity", "effort")
CONTACT_KEYS = ("lateral_friction", "rolling_friction", "spinning_friction", "stiffness", "damping")
RECIPE_KEYS = {"base", "attach", "joint_limits", "contacts", "frames", "drop_links"}
FRAME_KEYS = ("parent", "xyz", "rpy")
ATTACH_KEYS = {
    "urdf",
    "parent",
    "xyz",
    "rpy",
    "joint_name",
    "link_prefix",
    "joint_prefix",
    "drop_links",
}


@dataclass(frozen=True)
class Attachment:
    """A URDF hung from ``parent`` (a link of the tree so far) by a fixed joint at xyz/rpy."""

    urdf: str
    parent: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    joint_name: str = ""
    link_prefix: str = ""
    joint_prefix: str = ""
    drop_links: tuple[str, ...] = ()


@dataclass(frozen=True)
class Frame:
    """A massless link hung from ``parent`` by a fixed joint at xyz/rpy: a named frame (a grasp
    frame between the pads, a tool frame whose z axis is the approach direction)."""

    parent: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Recipe:
    """How to build one robot URDF: ``base`` plus ``attachments``, paths relative to ``folder``."""

    name: str
    base: str
    folder: Path
    attachments: tuple[Attachment, ...] = ()
    joint_limits: dict[str, dict[str, float]] = field(default_factory=dict)
    """Per joint name, any of ``lower``, ``upper``, ``velocity``, ``effort`` to overwrite."""
    contacts: dict[str, dict[str, float]] = field(default_factory=dict)
    """Per link name, the PyBullet ``<contact>`` values that replace the link's own."""
    frames: dict[str, Frame] = field(default_factory=dict)
    """Named frames added as massless links (after the attachments)."""
    drop_links: tuple[str, ...] = ()
    """Leaf links removed with the joint that carries them (e.g. a planning-only safety box
    that would hold every object off the fingers)."""


def cache_dir() -> Path:
    """Folder for composed URDFs: ``$BT_MANIP_CACHE`` or ``$XDG_CACHE_HOME/bt-manip/urdf``."""
    return shared_cache_dir("urdf", "BT_MANIP_CACHE")


def composed_urdf(description: RobotDescription | Recipe | Path | str) -> Path:
    """Path of the URDF that both PyBullet and Pinocchio load for this robot.

    ``description`` is a :class:`~bt_manip.sim.robot_description.RobotDescription`, a
    :class:`Recipe` or a URDF path. A plain URDF without meshes is returned as it is; otherwise
    the resolved or composed file is written to :func:`cache_dir` once and its path returned.
    """
    source: object = getattr(description, "urdf", description)
    if isinstance(source, Recipe):
        return _compose_recipe(source)
    return _resolve_single(Path(cast("Path | str", source)))


def _compose_recipe(recipe: Recipe) -> Path:
    base_path = resolve_uri(recipe.base, recipe.folder)
    parts = [base_path] + [resolve_uri(a.urdf, recipe.folder) for a in recipe.attachments]
    key = _hash_inputs(
        {
            "version": COMPOSER_VERSION,
            "name": recipe.name,
            "base": str(base_path),
            "attachments": [asdict(a) for a in recipe.attachments],
            "limits": recipe.joint_limits,
            "contacts": recipe.contacts,
            "frames": {k: asdict(v) for k, v in recipe.frames.items()},
            "drop_links": list(recipe.drop_links),
        },
        parts,
    )
    target = cache_dir() / f"{recipe.name}-{key}.urdf"
    if target.is_file():
        return target
    robot = _read_urdf(base_path)
    robot.set("name", recipe.name)
    for i, attachment in enumerate(recipe.attachments):
        _graft(robot, attachment, parts[i + 1], f"{recipe.name}: attachments[{i}]")
    _drop_leaf_links(robot, recipe.drop_links, recipe.name)
    _add_frames(robot, recipe.frames, recipe.name)
    _override_limits(robot, recipe.joint_limits, recipe.name)
    _replace_contacts(robot, recipe.contacts, recipe.name)
    _fill_inertials(robot)
    _write_atomic(target, _to_text(robot))
    return target


_MESHES_SEEN: Memo[tuple[tuple[str, tuple[int, int, int] | None], ...]] = Memo(16)
"""For the plain URDFs read in this process, by path and bytes: the meshes they name (resolved)
with the size, modification time and inode each had when checked."""


def file_stamp(path: str | Path) -> tuple[int, int, int] | None:
    """A file's size, modification time (ns) and inode; None if it cannot be read."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_size, st.st_mtime_ns, st.st_ino


def _resolve_single(path: Path) -> Path:
    path = path.resolve()
    data = read_bounded(path, MAX_URDF_BYTES, "URDF file")
    seen_key = (str(path), bytes_key(data))
    seen = _MESHES_SEEN.get(seen_key)
    root = None
    if seen is None or any(file_stamp(mesh) != stamp for mesh, stamp in seen):
        # bytes not read before, or a mesh changed since: parse them and check the meshes
        root = _read_urdf(path)
        meshes = dict.fromkeys(el.get("filename", "") for el in root.iter("mesh"))
        seen = tuple((mesh, file_stamp(mesh)) for mesh in meshes)
        _MESHES_SEEN.put(seen_key, seen)
    if not seen:
        return path
    key = _hash_contents({"version": COMPOSER_VERSION, "file": str(path)}, [(path, data)])
    target = cache_dir() / f"{path.stem}-{key}.urdf"
    if not target.is_file():
        _write_atomic(target, _to_text(root if root is not None else _read_urdf(path)))
    return target


def _hash_inputs(recipe: dict, files: list[Path]) -> str:
    return _hash_contents(
        recipe, [(f, read_bounded(f, MAX_URDF_BYTES, "URDF file")) for f in files]
    )


def _hash_contents(recipe: dict, contents: list[tuple[Path, bytes]]) -> str:
    """:func:`_hash_inputs` of files already read (path and bytes of each)."""
    digest = hashlib.sha256(json.dumps(recipe, sort_keys=True, default=str).encode())
    for f, data in contents:
        digest.update(str(f).encode())
        digest.update(data)
    return digest.hexdigest()[:16]


def _read_urdf(path: Path) -> ET.Element:
    """Parse a URDF (no entities), drop simulator-specific tags, make mesh paths absolute."""
    data = read_bounded(path, MAX_URDF_BYTES, "URDF file")
    try:
        root: ET.Element = SafeET.fromstring(data)
    except Exception as exc:  # defusedxml and expat raise several unrelated types
        raise InputError.single(str(path), None, f"unreadable URDF: {exc}") from None
    if root.tag != "robot":
        raise InputError.single(str(path), None, f"root element is <{root.tag}>, not <robot>")
    check_urdf_size(path, root, data)
    for tag in DROPPED_TAGS:
        for el in root.findall(tag):
            root.remove(el)
    for el in root.iter():
        for key, value in el.attrib.items():
            if "$(" in value:
                el.set(key, OPTENV.sub(lambda m: m.group(1).strip(), value))
    problems: list[Problem] = []
    for mesh in root.iter("mesh"):
        uri = mesh.get("filename", "")
        resolved = resolve_uri(uri, path.parent)
        problem = mesh_problem(resolved, uri)
        if problem is not None:
            problems.append(Problem(str(path), line_of_text(data, uri), problem))
        mesh.set("filename", str(resolved))
    if problems:
        raise InputError(problems)
    return root


def _graft(robot: ET.Element, att: Attachment, path: Path, where: str) -> None:
    """Add the links and joints of ``path`` under ``att.parent`` of ``robot``."""
    part = _read_urdf(path)
    dropped = set(att.drop_links)
    links = {el.get("name", ""): el for el in part.findall("link")}
    joints = part.findall("joint")
    missing = dropped - links.keys()
    if missing:
        raise InputError.single(where, None, f"drop_links: no link {sorted(missing)} in {path}")
    kept_joints = [
        j
        for j in joints
        if _joint_end(j, "parent") not in dropped and _joint_end(j, "child") not in dropped
    ]
    kept_links = [name for name in links if name not in dropped]
    children = {_joint_end(j, "child") for j in kept_joints}
    roots = [name for name in kept_links if name not in children]
    if len(roots) != 1:
        raise InputError.single(
            where, None, f"{path} must form one tree after drop_links; found root links {roots}"
        )
    existing_links = {el.get("name") for el in robot.findall("link")}
    existing_joints = {el.get("name") for el in robot.findall("joint")}
    if att.parent not in existing_links:
        raise InputError.single(where, None, f"parent link '{att.parent}' not in the robot so far")

    def link_name(name: str) -> str:
        return att.link_prefix + name

    clashes = [link_name(n) for n in kept_links if link_name(n) in existing_links]
    clashes += [
        att.joint_prefix + (j.get("name") or "")
        for j in kept_joints
        if att.joint_prefix + (j.get("name") or "") in existing_joints
    ]
    mount_name = att.joint_name or f"{link_name(roots[0])}_mount"
    if mount_name in existing_joints:
        clashes.append(mount_name)
    if clashes:
        raise InputError.single(
            where,
            None,
            f"names already used in the robot: {clashes}; set link_prefix / joint_prefix",
        )

    known_materials = {m.get("name") for m in robot.findall("material")}
    for mat in part.findall("material"):
        if mat.get("name") not in known_materials:
            robot.append(mat)
            known_materials.add(mat.get("name"))
    for name in kept_links:
        el = links[name]
        el.set("name", link_name(name))
        robot.append(el)
    for j in kept_joints:
        j.set("name", att.joint_prefix + (j.get("name") or ""))
        for end in ("parent", "child"):
            end_el = j.find(end)
            if end_el is not None:
                end_el.set("link", link_name(end_el.get("link", "")))
        robot.append(j)
    mount = ET.SubElement(robot, "joint", name=mount_name, type="fixed")
    ET.SubElement(mount, "parent", link=att.parent)
    ET.SubElement(mount, "child", link=link_name(roots[0]))
    ET.SubElement(mount, "origin", xyz=_vec(att.xyz), rpy=_vec(att.rpy))


def _joint_end(joint: ET.Element, end: str) -> str:
    el = joint.find(end)
    return el.get("link", "") if el is not None else ""


def _drop_leaf_links(robot: ET.Element, names: tuple[str, ...], where: str) -> None:
    """Remove each named leaf link and the joint that carries it."""
    links = {el.get("name"): el for el in robot.findall("link")}
    joints = robot.findall("joint")
    problems: list[Problem] = []
    for name in names:
        if name not in links:
            problems.append(Problem(where, None, f"drop_links: no link '{name}' in the robot"))
            continue
        below = [_joint_end(j, "child") for j in joints if _joint_end(j, "parent") == name]
        if below:
            problems.append(Problem(
                where, None, f"drop_links: link '{name}' carries {sorted(below)}; only a leaf "
                "link (one no joint hangs from) can be dropped",
            ))
            continue
        robot.remove(links[name])
        for j in joints:
            if _joint_end(j, "child") == name:
                robot.remove(j)
    if problems:
        raise InputError(problems)


def _add_frames(robot: ET.Element, frames: dict[str, Frame], where: str) -> None:
    """Add each frame as a massless link on a fixed joint named ``<frame>_joint``."""
    links = {el.get("name") for el in robot.findall("link")}
    joints = {el.get("name") for el in robot.findall("joint")}
    problems: list[Problem] = []
    for name, frame in frames.items():
        if name in links or f"{name}_joint" in joints:
            problems.append(Problem(where, None, f"frames: '{name}' is already a link name"))
            continue
        if frame.parent not in links:
            problems.append(
                Problem(where, None, f"frames.{name}: no parent link '{frame.parent}' in the robot")
            )
            continue
        ET.SubElement(robot, "link", name=name)
        joint = ET.SubElement(robot, "joint", name=f"{name}_joint", type="fixed")
        ET.SubElement(joint, "parent", link=frame.parent)
        ET.SubElement(joint, "child", link=name)
        ET.SubElement(joint, "origin", xyz=_vec(frame.xyz), rpy=_vec(frame.rpy))
        links.add(name)
    if problems:
        raise InputError(problems)


def _override_limits(robot: ET.Element, limits: dict[str, dict[str, float]], where: str) -> None:
    joints = {j.get("name"): j for j in robot.findall("joint")}
    problems: list[Problem] = []
    for name, values in limits.items():
        joint = joints.get(name)
        if joint is None:
            problems.append(Problem(where, None, f"joint_limits: no joint '{name}' in the robot"))
            continue
        limit = joint.find("limit")
        if limit is None:
            limit = ET.SubElement(joint, "limit")
        for key, value in values.items():
            limit.set(key, repr(float(value)))
    if problems:
        raise InputError(problems)


def _replace_contacts(robot: ET.Element, contacts: dict[str, dict[str, float]], where: str) -> None:
    links = {el.get("name"): el for el in robot.findall("link")}
    unknown = sorted(set(contacts) - links.keys())
    if unknown:
        raise InputError.single(where, None, f"contacts: no link {unknown} in the robot")
    for name, values in contacts.items():
        link = links[name]
        for old in link.findall("contact"):
            link.remove(old)
        contact = ET.SubElement(link, "contact")
        for key, value in values.items():
            ET.SubElement(contact, key, value=repr(float(value)))


def _fill_inertials(robot: ET.Element) -> None:
    for link in robot.findall("link"):
        if link.find("inertial") is not None:
            continue
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
        ET.SubElement(inertial, "mass", value=repr(FILLER_MASS))
        i = repr(FILLER_INERTIA)
        ET.SubElement(inertial, "inertia", ixx=i, ixy="0", ixz="0", iyy=i, iyz="0", izz=i)


def _vec(values: tuple[float, ...]) -> str:
    return " ".join(repr(float(v)) for v in values)


def _to_text(root: ET.Element) -> str:
    ET.indent(root, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _write_atomic(target: Path, text: str) -> None:
    """Write ``text`` to ``target`` so that readers see either nothing or the whole file."""
    write_atomic_bytes(target, text.encode("utf-8"))


def write_atomic_bytes(target: Path, data: bytes) -> None:
    """Write ``data`` to ``target`` (its folder made if missing) so that readers, in this or
    another process, see either nothing or the whole file."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}-", suffix=".tmp", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def parse_recipe(data: dict, path: Path, name: str) -> Recipe:
    """Check a recipe read from the ``urdf:`` mapping of descriptor ``path``.

    Raises :class:`~bt_manip.errors.InputError` naming the file, line and key of each problem.
    """
    reader = FieldReader(path)

    def line(d: object, key: str | int | None = None) -> int | None:
        if key is not None and hasattr(d, "line_of"):
            return cast("int | None", d.line_of(key))
        return getattr(d, "line", None)

    def fail(where: object, key: str | int | None, message: str) -> None:
        reader.fail(line(where, key), message)

    def vec3(d: dict, key: str, where: str) -> tuple[float, float, float]:
        if key not in d:
            return (0.0, 0.0, 0.0)
        value = reader.vector(d[key], 3, line(d, key), f"{where}.{key}")  # type: ignore[arg-type]
        return (0.0, 0.0, 0.0) if value is None else (value[0], value[1], value[2])

    def table(d: dict, key: str, allowed: tuple[str, ...]) -> dict[str, dict[str, float]]:
        value = d.get(key) or {}
        out: dict[str, dict[str, float]] = {}
        if not isinstance(value, dict):
            fail(d, key, f"urdf.{key} must be a mapping of names to mappings")
            return out
        for item, values in value.items():
            if not isinstance(values, dict) or not values:
                fail(value, item, f"urdf.{key}.{item} must be a mapping of {', '.join(allowed)}")
                continue
            for k, v in values.items():
                if k not in allowed:
                    fail(
                        values,
                        k,
                        f"unknown key '{k}' in urdf.{key}.{item}; allowed: {', '.join(allowed)}",
                    )
                elif isinstance(v, bool) or not isinstance(v, int | float):
                    fail(values, k, f"urdf.{key}.{item}.{k} must be a number, got {v!r}")
            out[str(item)] = {
                k: float(v)
                for k, v in values.items()
                if k in allowed and isinstance(v, int | float)
            }
        return out

    for key in data:
        if key not in RECIPE_KEYS:
            allowed = ", ".join(sorted(RECIPE_KEYS))
            fail(data, key, f"unknown key '{key}' in urdf; allowed: {allowed}")
    base = data.get("base")
    if not isinstance(base, str) or not base:
        fail(data, "base", "urdf.base must name the base URDF (URI or relative path)")
        base = ""
    elif not resolve_uri(base, path.parent).is_file():
        fail(data, "base", f"urdf.base: file '{base}' not found")
    attachments: list[Attachment] = []
    raw = data.get("attach") or []
    if not isinstance(raw, list):
        fail(data, "attach", "urdf.attach must be a list")
        raw = []
    for i, item in enumerate(raw):
        where = f"urdf.attach[{i}]"
        if not isinstance(item, dict):
            fail(raw, i, f"{where} must be a mapping")
            continue
        for key in item:
            if key not in ATTACH_KEYS:
                fail(
                    item,
                    key,
                    f"unknown key '{key}' in {where}; allowed: {', '.join(sorted(ATTACH_KEYS))}",
                )
        texts = {}
        for key in ("urdf", "parent", "joint_name", "link_prefix", "joint_prefix"):
            value = item.get(key, "")
            if not isinstance(value, str) or (key in ("urdf", "parent") and not value):
                fail(item, key, f"{where}.{key} must be text")
                value = ""
            texts[key] = value
        if texts["urdf"] and not resolve_uri(texts["urdf"], path.parent).is_file():
            fail(item, "urdf", f"{where}.urdf: file '{texts['urdf']}' not found")
        drop = item.get("drop_links", [])
        if not isinstance(drop, list) or not all(isinstance(d, str) for d in drop):
            fail(item, "drop_links", f"{where}.drop_links must be a list of link names")
            drop = []
        attachments.append(
            Attachment(
                texts["urdf"],
                texts["parent"],
                vec3(item, "xyz", where),
                vec3(item, "rpy", where),
                texts["joint_name"],
                texts["link_prefix"],
                texts["joint_prefix"],
                tuple(drop),
            )
        )
    limits = table(data, "joint_limits", LIMIT_KEYS)
    contacts = table(data, "contacts", CONTACT_KEYS)
    frames: dict[str, Frame] = {}
    raw_frames = data.get("frames") or {}
    if not isinstance(raw_frames, dict):
        fail(data, "frames", "urdf.frames must map frame names to {parent, xyz, rpy}")
        raw_frames = {}
    for fname, item in raw_frames.items():
        where = f"urdf.frames.{fname}"
        if not isinstance(item, dict) or not isinstance(item.get("parent"), str):
            fail(raw_frames, fname, f"{where} must be a mapping with a parent link name")
            continue
        for key in item:
            if key not in FRAME_KEYS:
                fail(item, key, f"unknown key '{key}' in {where}; allowed: {', '.join(FRAME_KEYS)}")
        frames[str(fname)] = Frame(
            item["parent"], vec3(item, "xyz", where), vec3(item, "rpy", where)
        )
    drop_top = data.get("drop_links", [])
    if not isinstance(drop_top, list) or not all(isinstance(d, str) for d in drop_top):
        fail(data, "drop_links", "urdf.drop_links must be a list of link names")
        drop_top = []
    if reader.problems:
        raise InputError(reader.problems)
    return Recipe(
        name, base, path.parent, tuple(attachments), limits, contacts, frames, tuple(drop_top)
    )
