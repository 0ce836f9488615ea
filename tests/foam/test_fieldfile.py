"""A field file is read only once OpenFOAM has finished writing it (ehlfoam.foam.fieldfile):
foamlib's parser backtracks for minutes on a numeric list cut short, as a solver killed
while it writes leaves one."""

from __future__ import annotations

import numpy as np
import pytest
from foamlib import FoamFieldFile

from ehlfoam.foam.fieldfile import CLOSING, IncompleteField, field_file, is_complete

BANNER = "\n// " + "*" * 73 + " //\n"


def _field(path, n: int = 3000):
    """A nonuniform scalar field of ``n`` values with OpenFOAM's closing banner; its values."""
    values = np.random.default_rng(1).normal(size=n) * 1e-27
    FoamFieldFile(path).internal_field = values
    with open(path, "a") as fh:
        fh.write(BANNER)
    return values


def test_a_whole_field_is_read_and_a_cut_one_refused_before_parsing(tmp_path):
    whole = tmp_path / "alphaPhi0.oil"
    values = _field(whole)
    assert is_complete(whole) and CLOSING in whole.read_bytes()[-200:]
    assert np.asarray(field_file(whole).internal_field) == pytest.approx(values, rel=1e-6)
    cut = tmp_path / "cut"
    data = whole.read_bytes()
    cut.write_bytes(data[:len(data) * 6 // 10])         # mid-list, as a crash leaves it
    assert not is_complete(cut)
    with pytest.raises(IncompleteField, match="incomplete"):
        field_file(cut)
    with pytest.raises(ValueError):                       # the readers' retry catches it
        field_file(cut)
    assert not is_complete(tmp_path / "missing")
    with pytest.raises(FileNotFoundError):
        field_file(tmp_path / "missing")
