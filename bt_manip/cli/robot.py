"""The ``robot`` verb: ``robot init`` writes a robot descriptor from a URDF, ``robot check``
moves every joint of one to its limits and back (the work is :mod:`bt_manip.sim.robot_init`'s
and :mod:`bt_manip.sim.robot_check`'s)."""

from __future__ import annotations

import argparse
from pathlib import Path

from bt_manip.cli.args import joint_list
from bt_manip.manipulation.self_collisions import add_planning_section
from bt_manip.sim.robot_check import check_robot
from bt_manip.sim.robot_description import APPROACH_AXES, RobotDescription
from bt_manip.sim.robot_init import MOBILE_KINDS, InitOptions, init_descriptor


def add_robot_arguments(robot: argparse.ArgumentParser) -> None:
    """The arguments of ``bt-manip robot init`` and ``bt-manip robot check``."""
    verbs = robot.add_subparsers(dest="robot_verb", metavar="init|check", parser_class=type(robot))
    verbs.required = True
    init = verbs.add_parser("init", help="write robots/NAME.yaml from a URDF and check it")
    init.add_argument("urdf", help="the robot's URDF")
    init.add_argument("--base-link", required=True, help="root link of the arm chain")
    init.add_argument("--arm-tip", required=True, help="last link of the arm chain (IK tip)")
    init.add_argument(
        "--gripper", type=joint_list, default=(), metavar="JOINT[,JOINT]",
        help="finger joints, by name or shell pattern ('hand_*_flex_*'): prismatic (a parallel "
        "gripper) or revolute (jaws or a hand); which way each closes is measured",
    )
    init.add_argument(
        "--approach-axis", choices=APPROACH_AXES, default="", metavar="AXIS",
        help="axis of the grasp frame the gripper approaches along (x, y, z, -x, -y, -z; "
        "default: measured from the arm's last link to the grasp frame)",
    )
    init.add_argument(
        "--grasp-frame", default="", metavar="LINK",
        help="link between the finger pads (default: the arm tip)",
    )
    init.add_argument(
        "--mobile", choices=MOBILE_KINDS, default=None,
        help="a mobile base: skid or diff (wheels found from its continuous joints), or "
        "holonomic (virtual x, y, yaw joints above --base-link); default: fixed base",
    )
    init.add_argument(
        "--lidar", default="", metavar="LINK",
        help="a planar laser at the origin of LINK, scanning in its x-y plane (a sensors: entry "
        "with the default 270 deg, 541 beams, 12 m; edit xyz and rpy there)",
    )
    init.add_argument("--name", default="", help="robot name (default: the --out file name)")
    init.add_argument("--out", required=True, help="descriptor to write, e.g. robots/NAME.yaml")
    init.set_defaults(func=cmd_robot_init)
    check = verbs.add_parser(
        "check", help="move every joint of a robot to its limits and back, print a table"
    )
    check.add_argument("robot", help="robot name (robots/NAME.yaml) or descriptor path")
    check.set_defaults(func=cmd_robot_check)


VERB_ARGUMENTS = {"robot": add_robot_arguments}
"""The verbs of this module and the function that adds each one's arguments."""


def cmd_robot_init(args: argparse.Namespace) -> int:
    notes: list[str] = []
    desc = init_descriptor(
        InitOptions(
            urdf=Path(args.urdf),
            base_link=args.base_link,
            arm_tip=args.arm_tip,
            out=Path(args.out),
            gripper=args.gripper,
            mobile=args.mobile,
            name=args.name,
            grasp_frame=args.grasp_frame,
            approach_axis=args.approach_axis,
            lidar=args.lidar,
        ),
        notes,
    )
    desc, allowed = add_planning_section(desc)
    g = desc.gripper
    joints = ", ".join(g.joints[:4]) + (f", ... ({len(g.joints)} joints)" if len(g.joints) > 4
                                        else "")
    gripper = (
        f"{g.kind} gripper {joints} (0 .. {g.max_opening:g} m)" if g.joints else "no gripper"
    )
    print(
        f"wrote {args.out}: {desc.name}, base {desc.base.type}, arm {len(desc.arm.joints)} joints "
        f"({desc.arm.base_link} -> {desc.end_effector}), {gripper}, states "
        f"{', '.join(desc.states)}"
    )
    for note in notes:
        print(f"  assumed: {note}")
    print(f"  planning: {len(allowed.never)} link pairs never touch (left out of the arm's "
          f"collision checks), {len(allowed.default)} touch in a named state (allowed)")
    return 0


def _written_here(name_or_path: str) -> str:
    """``robots/NAME.yaml`` of the current folder when a bare NAME has a descriptor there (the
    one ``robot init --out robots/NAME.yaml`` just wrote), else ``name_or_path`` as given (a
    path, or a shipped robot's name)."""
    local = Path("robots") / f"{name_or_path}.yaml"
    bare = Path(name_or_path).name == name_or_path and Path(name_or_path).suffix == ""
    return str(local) if bare and local.is_file() else name_or_path


def cmd_robot_check(args: argparse.Namespace) -> int:
    report = check_robot(RobotDescription.load(_written_here(args.robot)))
    print(report.table())
    for cause in report.causes:
        print(cause)
    return 0 if report.ok else 1
