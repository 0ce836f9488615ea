"""`ehlfoam case` on a thin-film spec (issue 74): bad specs refused with exit 2 and one line
naming the key, its value and what is valid, before anything is written (no OpenFOAM, no
precalc needed to refuse them), the bounds on the work (mesh.max_cells on the model's grid,
run.max_steps on its steps) among them."""

from __future__ import annotations

import pytest

from ehlfoam.cli.main import main


@pytest.mark.parametrize("sets, words", [
    (["thin_film.cell=0"], "thin_film.cell = 0: Input should be greater than or equal to 0.01"),
    (["thin_film.cell=10"], "thin_film.cell = 10 a is out of range: must be in [0.01, 3.25] a"),
    (["mesh.size_rim=0.1"], 'mesh.size_rim = 0.1 does not apply to scene = "thin-film"'),
    (["run.n_procs=2"], 'run.n_procs = 2 does not apply to scene = "thin-film"'),
    (["physics.isotropic_compression=1.0"], "physics.isotropic_compression = 1.0 does not "
                                            "apply"),
    (["supply.mode=\"submerged\""], 'supply.mode = "submerged" does not apply'),
    (["physics.contact_angle=95"], "physics.contact_angle = 95 deg is out of range"),
    (["thin_film.courant=2"], "thin_film.courant = 2: Input should be less than or equal to 1"),
    # main's bounds on the work (issue 73) hold for the model's grid and steps too
    (["mesh.max_cells=1000"], "mesh.max_cells = 1,000: the thin-film grid would have 5,200 "
                              "cells"),
    (["run.max_steps=100"], "run.max_steps = 100: reaching the end time"),
])
def test_a_bad_thin_film_spec_is_refused_before_anything_is_written(tmp_path, capsys,
                                                                     monkeypatch, sets, words):
    monkeypatch.setenv("EHLFOAM_FOAM", "prefix")
    monkeypatch.setenv("EHLFOAM_FOAM_PREFIX", "/bin/false")
    out = tmp_path / "case"
    args = ["case", "--out", str(out), "--set", 'scene="thin-film"']
    for item in sets:
        args += ["--set", item]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err
    assert err.startswith("ehlfoam case: invalid case spec: ") and err.count("\n") == 1
    assert not out.exists() and not list(tmp_path.iterdir())
