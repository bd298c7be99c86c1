"""From a building model (IFC) to a bt-manip world and an installation schedule.

``bt-manip bim BUILDING.ifc --out DIR`` reads an IFC4 or IFC2X3 file with ifcopenshell (the
optional extra ``bt-manip[bim]``) in the units of the file and writes:

- ``DIR/world.yaml``: the walls of one storey with their door openings (a window leaves the
  wall below and above it), the furniture as boxes, named poses at the spaces, the robot at a
  start pose and a stock area where the elements to install wait in slotted stands;
- ``DIR/schedule.json``: the elements to install in schedule order with their target poses;
- ``DIR/install.xml``: the BehaviorTree.CPP tree that installs them in that order.

After a run in that world, the run report's ``as_built`` table says where each element ended
up, and ``bt-manip bim-report REPORT.json --png OUT.png`` draws it on the floor plan.

Modules: :mod:`~bt_manip.bim.ifc_input` (reading, bounds, ``file:line: #id IfcClass 'Name'``
problems), :mod:`~bt_manip.bim.shapes` (element geometry as boxes), :mod:`~bt_manip.bim.building`
(walls, openings, spaces, furniture), :mod:`~bt_manip.bim.schedule` (the 4D schedule or a CSV,
and the elements to install), :mod:`~bt_manip.bim.floor_grid` (the floor as a grid: free spots,
connected places), :mod:`~bt_manip.bim.routes` (carrying each element from the stock through
the doors), :mod:`~bt_manip.bim.doorways` (the poses to cross them straight),
:mod:`~bt_manip.bim.stock` (the stands), :mod:`~bt_manip.bim.world_file` (the world YAML's
entries), :mod:`~bt_manip.bim.world_yaml` (its text), :mod:`~bt_manip.bim.ifc_attributes` (the
attribute positions the geometry is read by),
:mod:`~bt_manip.bim.install_tree` (install.xml), :mod:`~bt_manip.bim.convert` (the whole
conversion), :mod:`~bt_manip.bim.as_built` (the as-built table of a run),
:mod:`~bt_manip.bim.as_built_plot` (its floor plan) and :mod:`~bt_manip.bim.seeds` (a
converted world loaded with many seeds). The verbs' arguments are in :mod:`bt_manip.cli.bim`.
"""

from __future__ import annotations

from bt_manip.errors import InputError

INSTALL_HINT = "pip install 'bt-manip[bim]'"


def require_ifcopenshell() -> None:
    """Raise an InputError saying how to install ifcopenshell when it cannot be imported."""
    try:
        import ifcopenshell  # noqa: F401
    except ImportError:
        raise InputError.single(
            "bt-manip bim",
            None,
            f"reading IFC files needs ifcopenshell, which is not installed: {INSTALL_HINT}",
        ) from None
