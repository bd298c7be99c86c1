"""Nav2's selector nodes: which planner, controller, goal checker, progress checker, path
handler or smoother the next actions use. Nav2 takes a selection published on ``topic_name``;
bt-manip has no topics, so the selection is the default given in the tree (a later tick keeps
it)."""

from __future__ import annotations

from typing import ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.node import SyncActionNode
from bt_manip.bt.registry import registry


class _Selector(SyncActionNode):
    """Writes ``default_X`` to ``selected_X``; SUCCESS (FAILURE when there is no default)."""

    WHAT: ClassVar[str] = ""

    def update(self) -> Status:
        chosen = self.get_input(f"default_{self.WHAT}", "")
        if not chosen:
            self.feedback_message = f"no default_{self.WHAT} to select"
            return Status.FAILURE
        self.set_output(f"selected_{self.WHAT}", chosen)
        return Status.SUCCESS


def _ports(what: str, topic: str) -> dict[str, PortInformation]:
    return {
        f"default_{what}": PortInformation(str, False, f"the default {what} to use", ""),
        "topic_name": PortInformation(str, False, f"the topic selecting the {what}", topic),
    }


def _out(what: str) -> dict[str, PortInformation]:
    return {f"selected_{what}": PortInformation(str, False, f"the {what} selected")}


@registry.register
class PlannerSelector(_Selector):
    """Selects the planner for ComputePathToPose (``selected_planner``)."""

    WHAT = "planner"
    INPUT_PORTS: dict[str, PortInformation] = _ports("planner", "planner_selector")
    OUTPUT_PORTS: dict[str, PortInformation] = _out("planner")


@registry.register
class ControllerSelector(_Selector):
    """Selects the controller for FollowPath (``selected_controller``)."""

    WHAT = "controller"
    INPUT_PORTS: dict[str, PortInformation] = _ports("controller", "controller_selector")
    OUTPUT_PORTS: dict[str, PortInformation] = _out("controller")


@registry.register
class GoalCheckerSelector(_Selector):
    """Selects the goal checker for FollowPath (``selected_goal_checker``)."""

    WHAT = "goal_checker"
    INPUT_PORTS: dict[str, PortInformation] = _ports(
        "goal_checker", "goal_checker_selector"
    )
    OUTPUT_PORTS: dict[str, PortInformation] = _out("goal_checker")


@registry.register
class SmootherSelector(_Selector):
    """Selects the smoother for SmoothPath (``selected_smoother``)."""

    WHAT = "smoother"
    INPUT_PORTS: dict[str, PortInformation] = _ports("smoother", "smoother_selector")
    OUTPUT_PORTS: dict[str, PortInformation] = _out("smoother")


@registry.register
class ProgressCheckerSelector(_Selector):
    """Selects the progress checker for FollowPath (``selected_progress_checker``)."""

    WHAT = "progress_checker"
    INPUT_PORTS: dict[str, PortInformation] = _ports(
        "progress_checker", "progress_checker_selector"
    )
    OUTPUT_PORTS: dict[str, PortInformation] = _out("progress_checker")


@registry.register
class PathHandlerSelector(_Selector):
    """Selects the path handler for FollowPath (``selected_path_handler``)."""

    WHAT = "path_handler"
    INPUT_PORTS: dict[str, PortInformation] = _ports(
        "path_handler", "path_handler_selector"
    )
    OUTPUT_PORTS: dict[str, PortInformation] = _out("path_handler")
