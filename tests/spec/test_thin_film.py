"""The thin-film scene's part of the case spec (ehlfoam.spec.thin_film): its cell from the
level or the override, the keys only the 3D scenes read refused by name, value and default,
the values the model cannot take refused with their range, and the 3D scenes untouched by
its table."""

from __future__ import annotations

import pytest

from ehlfoam.errors import SpecError
from ehlfoam.spec.case import make_case_spec
from ehlfoam.spec.thin_film import (THIN_FILM_CELLS, THREE_D_ONLY, ThinFilm, thin_film_cell,
                                    thin_film_cells)
from ehlfoam.thinfilm.from_spec import scene_options


def thin(**overrides):
    return make_case_spec({"scene": "thin-film"}, **overrides)


@pytest.mark.parametrize("level", ["coarse", "medium", "fine"])
def test_the_cell_is_the_levels_unless_given(level):
    spec = thin(**{"mesh.resolution": level})
    assert thin_film_cell(spec) == THIN_FILM_CELLS[level]
    assert thin_film_cell(thin(**{"mesh.resolution": level, "thin_film.cell": 0.3})) == 0.3
    d = spec.domain
    assert thin_film_cells(spec) == round((d.upstream + d.downstream) / THIN_FILM_CELLS[level]) \
        * round(d.side / THIN_FILM_CELLS[level])


@pytest.mark.parametrize("key, value, words", [
    ("thin_film.cell", 0.0, "thin_film.cell = 0.0: Input should be greater than or equal to 0.01 "
                            "(valid range 0.01 <= thin_film.cell <= 10 a)"),
    ("thin_film.cell", 10.0, "thin_film.cell = 10 a is out of range: must be in [0.01, 3.25] a"),
    ("thin_film.cell", 0.012, "thin_film.cell = 0.012 a gives 1,445,389 cells over the domain, "
                               "more than 1,000,000"),
    ("mesh.size_rim", 0.1, 'mesh.size_rim = 0.1 does not apply to scene = "thin-film"'),
    ("mesh.polar_radius", None, 'mesh.polar_radius = None does not apply to scene = '
                                '"thin-film" (the model\'s grid is square cells of '
                                "thin_film.cell or the level's; leave it at 'auto')"),
    ("run.n_procs", 2, 'run.n_procs = 2 does not apply to scene = "thin-film"'),
    ("run.max_courant", 0.5, "leave it at 1.0"),
    ("physics.interface_compression", 0.0, "physics.interface_compression = 0.0 does not apply"),
    ("physics.gas_release_rate", 0.01, "physics.gas_release_rate = 0.01 does not apply"),
    ("supply.initial_bubble", 1.0, "supply.initial_bubble = 1.0 does not apply"),
    ("supply.mode", "submerged", 'supply.mode = "submerged" does not apply to scene = '
                                 '"thin-film" (valid: "layers", "flooded" or "rig"'),
    ("domain.symmetry", "full", 'domain.symmetry = "full" does not apply'),
    ("walls_moving", False, "walls_moving = false does not apply"),
    ("physics.contact_angle", 95.0, "physics.contact_angle = 95 deg is out of range for scene = "
                                    '"thin-film": must be in [0, 90) deg'),
    ("physics.cavitation_pressure", 1e5, None),
    ("thin_film.normal_length", 0.01, "thin_film.normal_length = 0.01 a is out of range: must "
                                      "be none or in [0.1, 3.25] a"),
    ("physics.advancing_angle", 95.0, "physics.advancing_angle = 95 deg is out of range for "
                                      'scene = "thin-film": must be none or in [15, 90) deg'),
    ("physics.receding_angle", 5.0, "physics.receding_angle = 5.0 does not apply"),
    ("thin_film.advancing_angle", 40.0, "advancing_angle has moved to "
                                        "physics.advancing_angle"),
    ("thin_film.receding_meniscus", 3.0, 'must be "static", "bretherton" or a factor in '
                                         "[0.5, 2]"),
])
def test_a_thin_film_spec_the_model_cannot_take_is_refused_by_key_value_and_range(key, value,
                                                                               words):
    overrides = {key: value}
    if key == "physics.cavitation_pressure":     # at ambient: the oil gives up no gas
        overrides["physics.ambient_pressure"] = 1e5
        words = ("physics.cavitation_pressure = 100000 Pa must be below "
                 "physics.ambient_pressure = 100000 Pa")
    with pytest.raises(SpecError) as err:
        thin(**overrides)
    message = str(err.value)
    assert message.startswith("invalid case spec: ") and "\n" not in message
    assert words in message


def test_every_3d_key_set_is_named_in_one_message():
    with pytest.raises(SpecError) as err:
        thin(**{"mesh.n_layers": 5, "run.alpha_subcycles": 3, "physics.air_viscosity": 1e-5})
    message = str(err.value)
    for key in ("mesh.n_layers = 5", "run.alpha_subcycles = 3", "physics.air_viscosity = 1e-05"):
        assert key in message


def test_the_3d_only_keys_are_keys_of_their_tables():
    spec = thin()
    for table, (names, _) in THREE_D_ONLY.items():
        for name in names:
            assert name in type(getattr(spec, table)).model_fields, f"{table}.{name}"


def test_the_keys_it_reads_and_a_3d_default_restated_are_taken():
    spec = thin(**{"contact.speed": 0.017, "supply.mode": "layers", "supply.disc_layer": 4e-6,
                   "physics.cavitation_pressure": 9e4, "physics.contact_angle": 20.0,
                   "domain.side": 11.0, "run.transits_max": 100.0, "run.wall_limit": 60.0,
                   "mesh.resolution": "coarse", "mesh.polar_radius": "auto",
                   "thin_film.receding_meniscus": 1.2, "physics.advancing_angle": 40.0})
    assert spec.solver == "thin-film"
    assert spec.thin_film.receding_meniscus == 1.2
    assert scene_options(spec).advancing_angle == 40.0


def test_the_3d_scenes_ignore_the_thin_film_table():
    spec = make_case_spec({"scene": "interface", "thin_film": {"cell": 0.05, "courant": 0.1},
                           "mesh": {"size_rim": 0.1}})
    assert spec.thin_film == ThinFilm(cell=0.05, courant=0.1)


def test_the_thin_film_scene_looks_at_its_oil_twice_a_transit_unless_told():
    from ehlfoam.spec.case import make_case_spec
    from ehlfoam.spec.thin_film import THIN_FILM_WRITES_PER_TRANSIT

    assert make_case_spec({"scene": "thin-film"}).run.writes_per_transit == \
        THIN_FILM_WRITES_PER_TRANSIT == 2
    assert make_case_spec({"scene": "thin-film", "run": {"transits_max": 50.0}}) \
        .run.writes_per_transit == 2
    assert make_case_spec({"scene": "thin-film", "run": {"writes_per_transit": 8}}) \
        .run.writes_per_transit == 8
    assert make_case_spec({}).run.writes_per_transit == 10          # the 3D scenes' default
    assert make_case_spec(None, scene="thin-film").run.writes_per_transit == 2


def test_the_gas_balance_takes_its_solubility_and_diffusivity_and_only_it_does():
    """thin_film.bubble_gas = "balance" reads physics.air_solubility and
    thin_film.gas_diffusivity; with the release pressure's bubble both are refused when set,
    by key and value, in one message."""
    spec = thin(**{"thin_film.bubble_gas": "balance", "physics.air_solubility": 0.08,
                   "thin_film.gas_diffusivity": 2e-9})
    assert spec.thin_film.bubble_gas == "balance" and spec.physics.air_solubility == 0.08
    with pytest.raises(SpecError) as err:
        thin(**{"physics.air_solubility": 0.08, "thin_film.gas_diffusivity": 2e-9})
    message = str(err.value)
    for words in ("physics.air_solubility = 0.08 applies only with thin_film.bubble_gas = "
                  '"balance"', "thin_film.gas_diffusivity = 2e-09 applies only"):
        assert words in message
    with pytest.raises(SpecError, match="bubble_gas"):
        thin(**{"thin_film.bubble_gas": "ideal"})
