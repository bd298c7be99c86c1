"""Positions of the IFC attributes the geometry reader reads, for ``entity.get_argument(i)``.

ifcopenshell reads an attribute by name (``placement.Location``) through a Python
``__getattr__`` that looks the name up in the schema on every call: several microseconds,
where ``get_argument(position)`` takes under one. The readers of :mod:`~bt_manip.bim.shapes`
read tens of thousands of attributes per file, so they read them by position. Each position
below is the same in IFC2X3, IFC4 and IFC4X3 (:data:`POSITIONS` lists them by class and name;
a test checks them against ifcopenshell's schemas).
"""

from __future__ import annotations

OBJECT_PLACEMENT = 5
"""IfcProduct.ObjectPlacement."""
REPRESENTATION = 6
"""IfcProduct.Representation."""
REPRESENTATIONS = 2
"""IfcProductRepresentation.Representations."""
REPRESENTATION_IDENTIFIER = 1
"""IfcRepresentation.RepresentationIdentifier."""
ITEMS = 3
"""IfcRepresentation.Items."""
PLACEMENT_REL_TO = 0
"""IfcLocalPlacement.PlacementRelTo."""
RELATIVE_PLACEMENT = 1
"""IfcLocalPlacement.RelativePlacement."""
LOCATION = 0
"""IfcAxis2Placement3D.Location and IfcAxis2Placement2D.Location."""
AXIS = 1
"""IfcAxis2Placement3D.Axis."""
REF_DIRECTION_3D = 2
"""IfcAxis2Placement3D.RefDirection."""
REF_DIRECTION_2D = 1
"""IfcAxis2Placement2D.RefDirection."""
COORDINATES = 0
"""IfcCartesianPoint.Coordinates (and IfcTessellatedFaceSet.Coordinates,
IfcCartesianPointList3D.CoordList)."""
DIRECTION_RATIOS = 0
"""IfcDirection.DirectionRatios."""
AXIS1, AXIS2, LOCAL_ORIGIN, SCALE, AXIS3, SCALE2, SCALE3 = 0, 1, 2, 3, 4, 5, 6
"""IfcCartesianTransformationOperator3DnonUniform's Axis1, Axis2, LocalOrigin, Scale (all
operators), Axis3 (3D ones), Scale2 and Scale3."""
MAPPING_SOURCE, MAPPING_TARGET = 0, 1
"""IfcMappedItem.MappingSource and .MappingTarget."""
MAPPING_ORIGIN, MAPPED_REPRESENTATION = 0, 1
"""IfcRepresentationMap.MappingOrigin and .MappedRepresentation."""
SWEPT_AREA, POSITION, EXTRUDED_DIRECTION, DEPTH = 0, 1, 2, 3
"""IfcExtrudedAreaSolid.SweptArea, .Position, .ExtrudedDirection and .Depth."""
FIRST_OPERAND = 1
"""IfcBooleanResult.FirstOperand."""
OUTER, VOIDS = 0, 1
"""IfcManifoldSolidBrep.Outer and IfcFacetedBrepWithVoids.Voids."""
FACES = 0
"""IfcConnectedFaceSet.CfsFaces, IfcFaceBasedSurfaceModel.FbsmFaces,
IfcShellBasedSurfaceModel.SbsmBoundary."""
BOUNDS = 0
"""IfcFace.Bounds."""
BOUND = 0
"""IfcFaceBound.Bound."""
POLYGON = 0
"""IfcPolyLoop.Polygon."""
PROFILE_POSITION, X_DIM, Y_DIM, RADIUS, OUTER_CURVE = 2, 3, 4, 3, 2
"""IfcParameterizedProfileDef.Position, IfcRectangleProfileDef.XDim and .YDim,
IfcCircleProfileDef.Radius, IfcArbitraryClosedProfileDef.OuterCurve."""
POINTS = 0
"""IfcPolyline.Points and IfcIndexedPolyCurve.Points."""
SEGMENTS, INDEXED_SEGMENTS = 0, 1
"""IfcCompositeCurve.Segments and IfcIndexedPolyCurve.Segments."""
PARENT_CURVE = 2
"""IfcCompositeCurveSegment.ParentCurve."""
BASIS_CURVE, TRIM1, TRIM2, SENSE_AGREEMENT = 0, 1, 2, 3
"""IfcTrimmedCurve.BasisCurve, .Trim1, .Trim2 and .SenseAgreement."""
CIRCLE_POSITION, CIRCLE_RADIUS = 0, 1
"""IfcCircle.Position and .Radius."""

POSITIONS: dict[tuple[str, str], int] = {
    ("IfcProduct", "ObjectPlacement"): OBJECT_PLACEMENT,
    ("IfcProduct", "Representation"): REPRESENTATION,
    ("IfcProductDefinitionShape", "Representations"): REPRESENTATIONS,
    ("IfcShapeRepresentation", "RepresentationIdentifier"): REPRESENTATION_IDENTIFIER,
    ("IfcShapeRepresentation", "Items"): ITEMS,
    ("IfcLocalPlacement", "PlacementRelTo"): PLACEMENT_REL_TO,
    ("IfcLocalPlacement", "RelativePlacement"): RELATIVE_PLACEMENT,
    ("IfcAxis2Placement3D", "Location"): LOCATION,
    ("IfcAxis2Placement3D", "Axis"): AXIS,
    ("IfcAxis2Placement3D", "RefDirection"): REF_DIRECTION_3D,
    ("IfcAxis2Placement2D", "Location"): LOCATION,
    ("IfcAxis2Placement2D", "RefDirection"): REF_DIRECTION_2D,
    ("IfcCartesianPoint", "Coordinates"): COORDINATES,
    ("IfcTessellatedFaceSet", "Coordinates"): COORDINATES,
    ("IfcCartesianPointList3D", "CoordList"): COORDINATES,
    ("IfcDirection", "DirectionRatios"): DIRECTION_RATIOS,
    ("IfcCartesianTransformationOperator3DnonUniform", "Axis1"): AXIS1,
    ("IfcCartesianTransformationOperator3DnonUniform", "Axis2"): AXIS2,
    ("IfcCartesianTransformationOperator3DnonUniform", "LocalOrigin"): LOCAL_ORIGIN,
    ("IfcCartesianTransformationOperator3DnonUniform", "Scale"): SCALE,
    ("IfcCartesianTransformationOperator3DnonUniform", "Axis3"): AXIS3,
    ("IfcCartesianTransformationOperator3DnonUniform", "Scale2"): SCALE2,
    ("IfcCartesianTransformationOperator3DnonUniform", "Scale3"): SCALE3,
    ("IfcMappedItem", "MappingSource"): MAPPING_SOURCE,
    ("IfcMappedItem", "MappingTarget"): MAPPING_TARGET,
    ("IfcRepresentationMap", "MappingOrigin"): MAPPING_ORIGIN,
    ("IfcRepresentationMap", "MappedRepresentation"): MAPPED_REPRESENTATION,
    ("IfcExtrudedAreaSolid", "SweptArea"): SWEPT_AREA,
    ("IfcExtrudedAreaSolid", "Position"): POSITION,
    ("IfcExtrudedAreaSolid", "ExtrudedDirection"): EXTRUDED_DIRECTION,
    ("IfcExtrudedAreaSolid", "Depth"): DEPTH,
    ("IfcBooleanClippingResult", "FirstOperand"): FIRST_OPERAND,
    ("IfcFacetedBrep", "Outer"): OUTER,
    ("IfcFacetedBrepWithVoids", "Voids"): VOIDS,
    ("IfcConnectedFaceSet", "CfsFaces"): FACES,
    ("IfcFaceBasedSurfaceModel", "FbsmFaces"): FACES,
    ("IfcShellBasedSurfaceModel", "SbsmBoundary"): FACES,
    ("IfcFace", "Bounds"): BOUNDS,
    ("IfcFaceBound", "Bound"): BOUND,
    ("IfcPolyLoop", "Polygon"): POLYGON,
    ("IfcRectangleProfileDef", "Position"): PROFILE_POSITION,
    ("IfcRectangleProfileDef", "XDim"): X_DIM,
    ("IfcRectangleProfileDef", "YDim"): Y_DIM,
    ("IfcCircleProfileDef", "Position"): PROFILE_POSITION,
    ("IfcCircleProfileDef", "Radius"): RADIUS,
    ("IfcArbitraryClosedProfileDef", "OuterCurve"): OUTER_CURVE,
    ("IfcPolyline", "Points"): POINTS,
    ("IfcIndexedPolyCurve", "Points"): POINTS,
    ("IfcCompositeCurve", "Segments"): SEGMENTS,
    ("IfcIndexedPolyCurve", "Segments"): INDEXED_SEGMENTS,
    ("IfcCompositeCurveSegment", "ParentCurve"): PARENT_CURVE,
    ("IfcTrimmedCurve", "BasisCurve"): BASIS_CURVE,
    ("IfcTrimmedCurve", "Trim1"): TRIM1,
    ("IfcTrimmedCurve", "Trim2"): TRIM2,
    ("IfcTrimmedCurve", "SenseAgreement"): SENSE_AGREEMENT,
    ("IfcCircle", "Position"): CIRCLE_POSITION,
    ("IfcCircle", "Radius"): CIRCLE_RADIUS,
}
"""Every position above by (class, attribute name)."""
