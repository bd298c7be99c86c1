"""``DIR/install.xml``: the BehaviorTree.CPP v4 tree that installs the elements in schedule order.

The main tree counts on the blackboard (``installed``, ``to_install``) and runs one
``InstallElement`` SubTree per element, in order, with the element's world object, its target
pose and its GlobalId remapped in, and its deviation (``deviation_mm_<object>``,
``deviation_deg_<object>``) and placed pose (``placed_<object>``) remapped out. Each
InstallElement:

1. fetches the element from its stand (``FetchElement``, up to 3 attempts): plan a base pose
   from which the arm takes it from above, line up and drive in, reach down by IK on a
   straight line, close, attach, lift it straight out of the stand; on a failure the hand lets
   go, backs off and the attempt is planned again;
2. carries it through each door on its route (``CarryThroughDoor``: to a pose before the door,
   facing through it, then straight through; :mod:`~bt_manip.bim.doorways`; an element whose
   route crosses N doors has the SubTree ``InstallElementViaNDoor(s)``, with the crossing poses
   remapped in), then places it (``PlaceElement``, up to 2 attempts): plan a base pose from which
   the arm sets it down at its target, drive there with it (a drive that fails backs up and
   tries again), Place (straight down, the pose checked: a touch before the final motion or a
   pose out of tolerance fails), Fasten (only within tolerance), open, detach, hand up, arm
   tucked, back off; a failed Place lifts the element back up and backs off, and the attempt
   is planned again from there;
3. counts it: ``installed`` + 1, ``to_install`` - 1.

Elements still at the stock stand there, not at their places; elements placed are movable
objects where they stand, so the navigator plans around them for the next drives.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence

from bt_manip.bim.doorways import Crossing
from bt_manip.bim.schedule import InstallElement

LIFT = 0.15
"""How high (m) an element is lifted straight out of its stand."""
PULL_IN = 0.12
"""How far (m) the element is pulled in towards the robot for the carry."""
FINGER_PLAY = 0.001
"""The fingers close to this much (m) wider than the element."""


def _node(parent: ET.Element, tag: str, **attrs: str) -> ET.Element:
    return ET.SubElement(parent, tag, {k: v for k, v in attrs.items()})


def install_id(doors: int) -> str:
    """ID of the InstallElement SubTree for an element whose route crosses ``doors`` doors."""
    if doors == 0:
        return "InstallElement"
    return f"InstallElementVia{doors}Door" + ("s" if doors > 1 else "")


def _main(
    root: ET.Element, elements: Sequence[InstallElement], crossings: Mapping[str, list[Crossing]]
) -> None:
    tree = _node(root, "BehaviorTree", ID="Install")
    seq = _node(tree, "Sequence", name="install_in_schedule_order")
    _node(seq, "Script", name="count_elements",
          code=f"installed := 0; to_install := {len(elements)}")
    _node(seq, "MoveJoints", name="tuck_arm", state="tuck")
    _node(seq, "OpenGripper", name="open_gripper")
    for e in elements:
        t = e.target
        opening = min(e.size[0], e.size[1]) + FINGER_PLAY
        doors = {}
        for j, c in enumerate(crossings.get(e.object, []), start=1):
            doors[f"door{j}_near"] = c.near
            doors[f"door{j}_far"] = c.far
        _node(
            seq, "SubTree", ID=install_id(len(doors) // 2), name=f"{e.order}_{e.object}",
            element=e.object,
            **doors,
            global_id=e.global_id,
            target=f"{t['x']:.4f};{t['y']:.4f};{t['z']:.4f};{t['yaw']:.4f}",
            opening=f"{opening:.4f}",
            installed="{installed}",
            to_install="{to_install}",
            placed_pose=f"{{placed_{e.object}}}",
            deviation_mm=f"{{deviation_mm_{e.object}}}",
            deviation_deg=f"{{deviation_deg_{e.object}}}",
        )


def _install_element(root: ET.Element, doors: int) -> None:
    tree = _node(root, "BehaviorTree", ID=install_id(doors))
    seq = _node(tree, "Sequence", name="install_element")
    fetch = _node(seq, "RetryUntilSuccessful", name="fetch_attempts", num_attempts="3")
    _node(fetch, "SubTree", ID="FetchElement", element="{element}", opening="{opening}")
    for j in range(1, doors + 1):
        _node(seq, "SubTree", ID="CarryThroughDoor", name=f"door_{j}", element="{element}",
              near=f"{{door{j}_near}}", far=f"{{door{j}_far}}")
    place = _node(seq, "RetryUntilSuccessful", name="place_attempts", num_attempts="2")
    _node(place, "SubTree", ID="PlaceElement", element="{element}", target="{target}",
          placed_pose="{placed_pose}", deviation_mm="{deviation_mm}",
          deviation_deg="{deviation_deg}")
    _node(seq, "Script", name="count_installed",
          code="installed := installed + 1; to_install := to_install - 1")


def _back_off(parent: ET.Element, name: str, hand_up: float) -> None:
    """Let go, hand straight up, arm tucked, base backed off; then fail (the attempt)."""
    seq = _node(parent, "Sequence", name=name)
    force = _node(seq, "ForceSuccess")
    _node(force, "Detach", name="let_go", object="{element}")
    _node(seq, "OpenGripper", name="open_to_let_go")
    force = _node(seq, "ForceSuccess")
    _node(force, "Lift", name="hand_clear", height=f"{hand_up:g}")
    _node(seq, "MoveJoints", name="tuck_after_letting_go", state="tuck")
    force = _node(seq, "ForceSuccess")
    _node(force, "Reverse", name="back_out", distance="0.5")
    _node(seq, "AlwaysFailure", name="attempt_failed")


def _drive(parent: ET.Element, name: str, goal: str, tolerance: str = "0.05") -> None:
    """Navigate to ``goal`` (within ``tolerance`` m and rad), backing up half a metre and trying
    again on a failure."""
    retry = _node(parent, "RetryUntilSuccessful", name=f"{name}_attempts", num_attempts="3")
    fb = _node(retry, "Fallback", name=f"{name}_or_back_up")
    _node(fb, "Navigate", name=name, goal=goal, xy_tolerance=tolerance, yaw_tolerance=tolerance)
    seq = _node(fb, "Sequence", name=f"{name}_back_up")
    force = _node(seq, "ForceSuccess")
    _node(force, "Reverse", name="back_up", distance="0.5")
    _node(seq, "AlwaysFailure", name=f"{name}_failed")


def _carry_through_door(root: ET.Element) -> None:
    tree = _node(root, "BehaviorTree", ID="CarryThroughDoor")
    seq = _node(tree, "Sequence", name="carry_through_door")
    _node(seq, "IsAttached", name="element_in_hand", object="{element}")
    _drive(seq, "to_door", "{near}", "0.15")
    # straight through: a follower correcting its heading in the doorway would sweep the
    # element's ends into the jambs
    _node(seq, "DriveStraight", name="through_door", goal="{far}", xy_tolerance="0.1",
          yaw_tolerance="0.1")


def _fetch_element(root: ET.Element) -> None:
    tree = _node(root, "BehaviorTree", ID="FetchElement")
    fb = _node(tree, "Fallback", name="fetch_or_back_off")
    seq = _node(fb, "Sequence", name="grasp_and_lift")
    _node(seq, "OpenGripper", name="open_fingers")
    _node(seq, "MoveJoints", name="tuck_for_driving", state="tuck")
    _node(seq, "PlanBaseForGrasp", name="plan_grasp_base", object="{element}", grasp="top",
          approach="0.12", staging="0.45", base_pose="{base_pose}",
          staging_pose="{staging_pose}")
    _drive(seq, "to_grasp_staging", "{staging_pose}", "0.08")
    # the drive in corrects little sideways over its 0.45 m from a staging pose reached within
    # 8 cm; the arm's reach takes up what is left (MoveToPose plans from where the base stands)
    _node(seq, "DriveStraight", name="drive_in", goal="{base_pose}", xy_tolerance="0.07",
          yaw_tolerance="0.08")
    _node(seq, "MoveJoints", name="arm_ready", state="home")
    _node(seq, "MoveToPose", name="reach_element", object="{element}", grasp="top",
          approach="0.12", tolerance="0.002")
    _node(seq, "CloseGripper", name="close_gripper", opening="{opening}")
    _node(seq, "Attach", name="attach_element", object="{element}")
    _node(seq, "Lift", name="lift_out_of_stand", height=f"{LIFT:g}", speed="0.05",
          via_tolerance="0.01")
    _node(seq, "IsAttached", name="element_attached", object="{element}")
    _node(seq, "ObjectAbove", name="element_off_floor", object="{element}", height="0.1")
    # pulled in towards the robot for the carry: at the place the robot stops short of the
    # wall with the element clear of it, and the arm reaches out again to set it down (the
    # place is planned from wherever the element is in the hand: a pull that stops short is
    # no reason to put it back)
    force = _node(seq, "ForceSuccess")
    _node(force, "MoveToolBy", name="pull_in", offset=f"{-PULL_IN:g};0;0", speed="0.2",
          via_tolerance="0.02", tolerance="0.02")
    # out of the stock the way the robot came in, before the carry is planned among the
    # elements still standing there
    force = _node(seq, "ForceSuccess")
    _node(force, "DriveStraight", name="back_out_with_it", goal="{staging_pose}",
          direction="backward", xy_tolerance="0.1", yaw_tolerance="0.1")
    _back_off(fb, "put_back", 0.12)


def _place_element(root: ET.Element) -> None:
    tree = _node(root, "BehaviorTree", ID="PlaceElement")
    fb = _node(tree, "Fallback", name="place_or_lift_back")
    seq = _node(fb, "Sequence", name="carry_place_fasten")
    _node(seq, "IsAttached", name="element_in_hand", object="{element}")
    _node(seq, "PlanBaseForPlace", name="plan_place_base", object="{element}",
          target="{target}", base_pose="{place_base}", staging_pose="{place_staging}")
    _drive(seq, "carry_to_staging", "{place_staging}", "0.1")
    # straight in: a path follower turning on the spot at the goal would sweep the load round
    _node(seq, "DriveStraight", name="drive_to_place", goal="{place_base}", xy_tolerance="0.04",
          yaw_tolerance="0.08")
    _node(seq, "Place", name="place_element", object="{element}", target="{target}",
          placed_pose="{placed_pose}", deviation_mm="{deviation_mm}",
          deviation_deg="{deviation_deg}", via_tolerance="0.01", speed="0.2")
    _node(seq, "Fasten", name="fasten_element", object="{element}", target="{target}")
    _node(seq, "OpenGripper", name="release")
    _node(seq, "Detach", name="detach_element", object="{element}")
    force = _node(seq, "ForceSuccess")
    _node(force, "Lift", name="hand_up", height="0.1")
    _node(seq, "MoveJoints", name="tuck_after_placing", state="tuck")
    force = _node(seq, "ForceSuccess")
    _node(force, "Reverse", name="back_off", distance="0.5")
    # the element is still in the hand: up again, away from the wall, and plan again
    lift = _node(fb, "Sequence", name="lift_back")
    _node(lift, "IsAttached", name="still_in_hand", object="{element}")
    force = _node(lift, "ForceSuccess")
    _node(force, "Lift", name="lift_again", height="0.1")
    force = _node(lift, "ForceSuccess")
    _node(force, "Reverse", name="back_away", distance="0.5")
    _node(lift, "AlwaysFailure", name="place_failed")


HEADER = """Generated by `bt-manip bim {source}`: installs the {count} elements of schedule.json in
     schedule order. Each is fetched from its stand at the stock (base planned from where the
     element stands, straight reach down, attach, straight lift), carried straight through the
     doors on its route and to a base pose planned for its target, set down by Place (straight
     final motion, pose checked within 2 cm and 2 deg, nothing touched before the final
     motion), fastened to the structure, released and left. Blackboard: installed,
     to_install, and per element placed_OBJECT, deviation_mm_OBJECT and deviation_deg_OBJECT.
     Run it with the world.yaml written beside it."""


def install_tree(
    elements: Sequence[InstallElement], source: str,
    crossings: Mapping[str, list[Crossing]] | None = None,
) -> str:
    """The text of ``install.xml`` for ``elements`` (in schedule order), each carried through
    the doors of its ``crossings`` (by world object; :mod:`~bt_manip.bim.doorways`)."""
    crossings = crossings or {}
    root = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": "Install"})
    root.append(ET.Comment(" " + HEADER.format(source=source, count=len(elements)) + " "))
    _main(root, elements, crossings)
    for doors in sorted({len(crossings.get(e.object, [])) for e in elements}):
        _install_element(root, doors)
    if any(crossings.get(e.object) for e in elements):
        _carry_through_door(root)
    _fetch_element(root)
    _place_element(root)
    ET.indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
