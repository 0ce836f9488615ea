"""The model ladder's key (issue 74, point 3): one ``rung`` picks the model of a point."""

from __future__ import annotations

import pytest

from ehlfoam.errors import SpecError
from ehlfoam.spec.case import CaseSpec, make_case_spec, thin_film_counterpart
from ehlfoam.spec.ladder import RESOLVED_SLIP_RATIO, RUNGS, cox_voinov
from tests.tiny import SMALL


@pytest.mark.parametrize("rung", RUNGS)
def test_every_rung_sets_its_scene_and_level_and_reads_back(rung):
    spec = make_case_spec(SMALL | {"mesh": {}}, rung=rung)
    level = rung.rsplit("-", 1)[-1]
    assert spec.rung == rung and spec.mesh.resolution == level
    assert (spec.scene == "thin-film") == rung.startswith("thin-film")
    assert (spec.mesh.follow is not None) == rung.startswith("resolved")
    assert CaseSpec.model_validate_json(spec.model_dump_json()) == spec   # spec.json


def test_a_spec_without_a_rung_is_given_the_one_its_scene_and_level_are():
    assert make_case_spec(SMALL).rung == "coarse"
    assert make_case_spec(SMALL | {"mesh": {"resolution": "fine"}}).rung == "fine"
    tf = make_case_spec(SMALL | {"scene": "thin-film", "mesh": {"resolution": "medium"}})
    assert tf.rung == "thin-film-medium"


def test_the_resolved_rungs_generalise_the_converged_family():
    """nominal_resolved's settings at any point: slip, schemes, side band from the track's
    edge, a thin-film start, and the wall at the Cox-Voinov angle of the rolling speed."""
    slow = make_case_spec({"rung": "resolved-medium", "contact": {"speed": 0.008}})
    fast = make_case_spec({"rung": "resolved-medium", "contact": {"speed": 0.017}})
    p = slow.physics
    assert (p.wall_slip_length, p.interface_schemes, p.isotropic_compression) == \
        (1e-6, "balanced", 1.0)
    assert slow.run.start == "thin-film" and slow.domain.side == 10.0
    assert slow.mesh.follow.sides.y_min == pytest.approx(slow.supply.track_half_width / slow.a,
                                                         abs=1e-3)
    ca = slow.oil_viscosity * slow.speed / slow.physics.surface_tension
    assert p.contact_angle == pytest.approx(cox_voinov(15.0, ca, RESOLVED_SLIP_RATIO), abs=0.01)
    assert 38 < p.contact_angle < 45 < fast.physics.contact_angle   # 43 deg held at 8 mm/s
    own = make_case_spec({"rung": "resolved-medium", "physics": {"contact_angle": 43.0,
                                                                "wall_slip_length": 2e-6}})
    assert (own.physics.contact_angle, own.physics.wall_slip_length) == (43.0, 2e-6)


def test_the_gas_release_scene_s_resolved_rungs_compress_along_the_face_flux():
    """interPhaseChangeFoam diverges in the thin films with the isotropic compression: the
    gas-release scene's resolved rungs take it from the face flux, and the scene refuses any
    other; the interface scene keeps the converged family's, and a value the spec sets
    wins there."""
    def compression(scene, **physics):
        spec = make_case_spec({"rung": "resolved-coarse", "scene": scene,
                               "physics": physics})
        return spec.physics.isotropic_compression

    assert compression("gas-release") == 0.0 and compression("interface") == 1.0
    with pytest.raises(SpecError, match="physics.isotropic_compression = 0.5 does not apply "
                       'to scene = "gas-release"'):
        compression("gas-release", isotropic_compression=0.5)
    assert compression("interface", isotropic_compression=0.0) == 0.0
    gas = make_case_spec({"rung": "resolved-coarse", "scene": "gas-release"})
    assert (gas.physics.interface_schemes, gas.physics.wall_slip_length) == ("balanced", 1e-6)
    assert make_case_spec({"scene": "gas-release"}).physics.isotropic_compression == 0.0


@pytest.mark.parametrize("data, words", [
    ({"rung": "coarse", "mesh": {"resolution": "fine"}},
     "rung = 'coarse' and mesh.resolution = 'fine' disagree"),
    ({"rung": "medium", "scene": "thin-film"}, "is a 3D rung and scene = \"thin-film\""),
    ({"rung": "thin-film-huge"}, "rung = 'thin-film-huge'"),
    ({"rung": "resolved-medium", "supply": {"mode": "submerged"}},
     'run.start = "thin-film": the thin-film model has no counterpart'),
])
def test_a_rung_that_cannot_be_is_refused_naming_the_keys(data, words):
    with pytest.raises(SpecError, match="invalid case spec") as info:
        make_case_spec(data)
    assert words in str(info.value)


def test_the_thin_film_counterpart_keeps_the_point_and_drops_the_3d_keys():
    spec = make_case_spec(SMALL | {"rung": "resolved-coarse", "mesh": {},
                                   "thin_film": {"cell": 0.5}})
    tf = thin_film_counterpart(spec)
    assert (tf.scene, tf.rung, tf.thin_film.cell) == ("thin-film", "thin-film-medium", 0.5)
    assert tf.contact == spec.contact and tf.supply == spec.supply and tf.domain == spec.domain
    assert tf.physics.wall_slip_length == 0.0 and tf.physics.contact_angle == 15.0
    assert tf.run.transits_max == 150.0 and tf.run.wall_limit == spec.run.wall_limit


def test_the_ladder_reads_the_case_specs_scenes_and_default():
    """The ladder fills a rung in before the case spec validates, so it reads the scene
    itself: its scenes are the spec's, the first its default."""
    from typing import get_args

    from ehlfoam.spec import ladder
    from ehlfoam.spec.case import CaseSpec

    field = CaseSpec.model_fields["scene"]
    assert set(ladder._SCENES) == set(get_args(field.annotation))
    assert ladder._scene({}) == field.default == "interface"
