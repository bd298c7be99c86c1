"""The attribute positions the geometry reader reads by are those of ifcopenshell's schemas.

:mod:`bt_manip.bim.ifc_attributes` names each position once for IFC2X3, IFC4 and IFC4X3: a
position that one schema puts elsewhere would read the wrong attribute, so each is checked
against every schema bt-manip reads.
"""

from __future__ import annotations

import pytest

from bt_manip.bim.ifc_attributes import POSITIONS

wrapper = pytest.importorskip("ifcopenshell.ifcopenshell_wrapper")

SCHEMAS = ("IFC2X3", "IFC4", "IFC4X3_ADD2")
ONLY_IFC4 = {"IfcIndexedPolyCurve", "IfcTessellatedFaceSet", "IfcCartesianPointList3D"}
"""Classes that IFC2X3 lacks."""


@pytest.mark.parametrize("schema", SCHEMAS)
def test_positions_match_the_schema(schema: str) -> None:
    declarations = wrapper.schema_by_name(schema)
    checked = 0
    for (ifc_class, name), position in POSITIONS.items():
        if schema == "IFC2X3" and ifc_class in ONLY_IFC4:
            continue
        names = [a.name() for a in declarations.declaration_by_name(ifc_class).all_attributes()]
        assert names.index(name) == position, (schema, ifc_class, name, names)
        checked += 1
    assert checked == len(POSITIONS) - (4 if schema == "IFC2X3" else 0)

