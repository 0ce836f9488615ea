"""The benchmarks' ``--edit FILE:KEY/SUBKEY=VALUE`` (bench/common.py): what it writes into a
case file is what OpenFOAM reads, schemes with numbers in them included."""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import pytest
from foamlib import FoamFile

from bench.common import apply_edits, edit_value_text, foam_edit

TEMPLATE = Path(__file__).resolve().parents[2] / "src" / "ehlfoam" / "case" / "templates" / "interface"


def test_a_scheme_with_numbers_is_written_as_openfoam_reads_it(tmp_path):
    case = tmp_path / "case"
    shutil.copytree(TEMPLATE / "system", case / "system")
    edits = [foam_edit("fvSchemes:divSchemes/div(phirb,alpha)=Gauss limitedLinear01 1"),
             foam_edit("fvSchemes:divSchemes/div(phi,alpha)="
                       "Gauss CoBlended 0.001 vanLeer01 0.005 linear"),
             foam_edit("fvSchemes:gradSchemes/nHat=pointCellsLeastSquares"),
             foam_edit("fvSolution:PIMPLE/nCorrectors=4")]
    assert edits[0] == ("fvSchemes", ("divSchemes", "div(phirb,alpha)"),
                        ("Gauss", "limitedLinear01", 1))
    # as the static bench names the record's edit and the case folder
    assert edit_value_text(edits[0][2]) == "Gauss limitedLinear01 1"
    assert edit_value_text(edits[0][2], "") == "GausslimitedLinear011"
    assert edit_value_text(edits[3][2]) == "4"
    apply_edits(case, edits)
    with FoamFile(case / "system" / "fvSchemes") as f:
        assert f["divSchemes"]["div(phirb,alpha)"] == ("Gauss", "limitedLinear01", 1)
        assert f["divSchemes"]["div(phi,alpha)"] == (
            "Gauss", "CoBlended", 0.001, "vanLeer01", 0.005, "linear")
        assert f["gradSchemes"]["nHat"] == "pointCellsLeastSquares"
    text = (case / "system" / "fvSchemes").read_text()
    assert "div(phirb,alpha) Gauss limitedLinear01 1;" in text
    with FoamFile(case / "system" / "fvSolution") as f:
        assert f["PIMPLE"]["nCorrectors"] == 4


@pytest.mark.parametrize("bad", ["fvSchemes:divSchemes", "divSchemes/x=1", "fvSchemes:=1"])
def test_a_malformed_edit_is_refused_with_its_text(bad):
    with pytest.raises(argparse.ArgumentTypeError, match="FILE:KEY/SUBKEY=VALUE"):
        foam_edit(bad)


def test_start_from_names_a_level_of_the_tag_or_any_finished_case(tmp_path, monkeypatch):
    """bench/case_bench.py --start-from: a level already run under the tag wins; else a path
    from the working directory, made absolute so that joining it to the tag's folder (as
    ``one`` does) gives that case; the older form relative to the new case's folder still
    works."""
    monkeypatch.syspath_prepend(str(Path(__file__).resolve().parents[2] / "bench"))
    from case_bench import start_case

    tag = tmp_path / "work" / "tag"
    (tag / "medium").mkdir(parents=True)
    other = tmp_path / "elsewhere" / "fine"
    other.mkdir(parents=True)
    monkeypatch.chdir(tmp_path)
    assert start_case(tag, "medium") == "medium"
    assert (tag / start_case(tag, "elsewhere/fine")).resolve() == other.resolve()
    assert Path(start_case(tag, "elsewhere/fine")).is_absolute()
    assert (tag / start_case(tag, "../../elsewhere/fine")).resolve() == other.resolve()


def test_a_record_saved_without_its_suffix_gets_it(tmp_path, monkeypatch):
    """``bench.common.save`` (the records' writer, beside the edits): a ``--save NAME`` given
    without ``.json`` still writes ``NAME.json``, which the charts and readers look for."""
    import json

    import bench.common as common

    monkeypatch.setattr(common, "RESULTS", tmp_path)
    bare = common.save("outline_run", {"width": 14.868})
    suffixed = common.save("rest.json", {"width": 14.868})
    assert bare == tmp_path / "outline_run.json" and suffixed == tmp_path / "rest.json"
    assert json.loads(bare.read_text()) == {"width": 14.868}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["outline_run.json", "rest.json"]
