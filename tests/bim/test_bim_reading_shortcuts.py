"""The conversion's reading shortcuts give what the plain ifcopenshell and numpy calls give.

An element's storey is found with each climb of containers and wholes kept per file; a closed
profile's last point is compared with its first without numpy's ``allclose``. Both are checked
against the plain calls, on a generated building and on the shared sample exports (skipped
when ``../shared/samples/ifc`` is absent).
"""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("ifcopenshell")

import ifcopenshell.util.element as util
from ifc_buildings import three_rooms

from bt_manip.bim.shapes import _close
from bt_manip.bim.storeys import direct_containers, storey_of

SAMPLES = Path("../shared/samples/ifc")


def _plain_storey(el: Any) -> Any:
    """The storey by ifcopenshell's calls alone, one element at a time."""
    current = util.get_container(el) or util.get_aggregate(el)
    for _ in range(16):
        if current is None or current.is_a("IfcBuildingStorey"):
            return current
        current = util.get_container(current) or util.get_aggregate(current)
    return None


def _check_storeys(model: Any) -> int:
    memo: dict[tuple[str, int], Any] = {}
    contained = direct_containers(model)
    products = model.by_type("IfcProduct")
    for el in products:
        assert storey_of(el, memo, contained) == _plain_storey(el), el
        assert storey_of(el) == _plain_storey(el), el
    return len(products)


def test_storeys_kept_per_file_are_ifcopenshells() -> None:
    building = three_rooms()
    assert _check_storeys(building.file) > 20


@pytest.mark.parametrize("name", ["Example_Import_IFC.ifc", "modelo2016.ifc",
                                  "web-ifc-viewer_test.ifc"])
def test_storeys_of_real_exports(name: str) -> None:
    path = SAMPLES / name
    if not path.is_file():
        pytest.skip(f"{path} is absent (the shared samples are read relative to the project root)")
    import ifcopenshell

    model = ifcopenshell.open(str(path))
    spaces_or_parts = [el for el in model.by_type("IfcProduct")
                       if el.id() not in direct_containers(model)]
    assert spaces_or_parts  # elements whose storey is found by a climb
    assert _check_storeys(model) > 100


def test_close_points_are_numpys() -> None:
    rng = random.Random(3)
    for _ in range(20000):
        b = np.array([rng.uniform(-1e4, 1e4), rng.choice([0.0, rng.uniform(-10, 10)])])
        step = rng.choice([0.0, 1e-9, 1e-8, 2e-8, 1e-5 * abs(b[0]), 1.0000001e-5 * abs(b[0])])
        a = b + np.array([step, rng.choice([0.0, 1e-8, 1.0000001e-8])])
        assert _close(a, b) == bool(np.allclose(a, b))
    for a, b in [((np.inf, 0.0), (np.inf, 0.0)), ((np.nan, 0.0), (np.nan, 0.0)),
                 ((np.inf, 0.0), (-np.inf, 0.0))]:
        assert _close(np.array(a), np.array(b)) == bool(np.allclose(a, b))
