"""Per-face lists that foamlib would misread (ehlfoam.case.foam_lists): a scalar list of 3
values and a symmTensor list of 3 faces go in through placeholders and read back as written."""

from __future__ import annotations

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.case.foam_lists import fill_placeholders, list_text, placeholder

FIELD = """FoamFile
{
    version     2.0;
    format      ascii;
    class       volScalarField;
    object      alpha.oil;
}
dimensions      [0 0 0 0 0 0 0];
internalField   uniform 0;
boundaryField
{
    supply { type fixedValue; value uniform 0; }
    wall { type directionMixed; valueFraction uniform (1 0 0 1 0 1); }
}
"""


def test_three_values_read_back_as_a_scalar_list_and_three_tensors_as_tensors(tmp_path):
    path = tmp_path / "alpha.oil"
    path.write_text(FIELD)
    scalars = np.array([0.25, 1.0, 0.5])
    tensors = np.arange(18, dtype=float).reshape(3, 6) / 7.0
    with FoamFieldFile(path) as f:
        f.boundary_field["supply"]["value"] = placeholder("supply", "value")
        f.boundary_field["wall"]["valueFraction"] = placeholder("wall", "valueFraction")
    fill_placeholders(path, {placeholder("supply", "value"): scalars,
                             placeholder("wall", "valueFraction"): tensors})
    text = path.read_text()
    assert "nonuniform List<scalar> 3(" in text and "nonuniform List<symmTensor> 3(" in text
    with FoamFieldFile(path) as f:
        np.testing.assert_allclose(f.boundary_field["supply"]["value"], scalars)
        np.testing.assert_allclose(f.boundary_field["wall"]["valueFraction"], tensors)


def test_a_missing_placeholder_and_a_bad_shape_are_named(tmp_path):
    path = tmp_path / "alpha.oil"
    path.write_text(FIELD)
    with pytest.raises(RuntimeError, match="ehlfoamList_supply_value not written once"):
        fill_placeholders(path, {placeholder("supply", "value"): np.ones(3)})
    assert path.read_text() == FIELD   # nothing written on failure
    with pytest.raises(ValueError, match=r"shape \(3, 4\)"):
        list_text(np.ones((3, 4)))
