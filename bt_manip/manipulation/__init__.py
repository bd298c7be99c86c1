"""Manipulation: what an arm does with objects, apart from the tree nodes that ask for it.

- :mod:`~bt_manip.manipulation.grasps`: grasp frames computed from an object's box, and what
  the fingers hold;
- :mod:`~bt_manip.manipulation.placing`: place targets, how far a pose is from one, and the
  hand's frames that put a held object there;
- :mod:`~bt_manip.manipulation.perception`: an object's pose as the robot perceives it;
- :mod:`~bt_manip.manipulation.cartesian`: IK on the robot's own model and straight-line paths;
- :mod:`~bt_manip.manipulation.base_search`: the search for a base pose from which the arm
  works (its checks and budgets), and the one for grasping an object;
- :mod:`~bt_manip.manipulation.place_search`: the search for a base pose from which the arm
  places the object it holds.

The helpers know nothing of behaviour trees: they return a reason, or raise a
:class:`~bt_manip.manipulation.errors.ManipulationError` whose message is the reason; the
behaviour nodes (:mod:`bt_manip.behaviours`) turn it into FAILURE. Importing this package
imports none of its modules.
"""
