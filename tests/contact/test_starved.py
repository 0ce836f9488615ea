"""The starved inlet of the precalc (issue 75.5): known answers of the film content and of the
moved meniscus, and the refusal of bad input."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.contact.formulas import contact_from_moes
from ehlfoam.contact.solver import solve
from ehlfoam.contact.spec import make_spec
from ehlfoam.errors import SpecError

GRID = 65


def moes_spec(M: float, L: float, **kw) -> dict:
    c = contact_from_moes(M, L)
    return dict(load=c.load, speed=c.speed, radius=c.radius, modulus=c.modulus,
                lubricant="custom", eta0=c.eta0, alpha=c.alpha, rho0=870.0, grid=GRID,
                viscosity="barus", density="incompressible", **kw)


@pytest.fixture(scope="module")
def layers():
    """The flooded contact at (M, L) = (100, 5) and the same contact fed by layers of
    50, 1, 0.5 and 0.2 times its flooded central film."""
    base = moes_spec(100.0, 5.0)
    flooded = solve(make_spec(**base))
    assert flooded.converged
    h_ff = flooded.H_central * flooded.contact.film_scale
    out = {}
    for r in (50.0, 1.0, 0.5, 0.2):
        res = solve(make_spec(**base, inlet_layer=r * h_ff), flooded=flooded)
        assert res.converged, res.mg.failure
        out[r] = res
    return flooded, h_ff, out


def test_a_thick_layer_gives_the_flooded_film(layers):
    flooded, _, res = layers
    s = res[50.0].summary()
    assert s["hc_over_hc_flooded"] == pytest.approx(1.0, abs=2e-3)
    assert s["hmin_over_hmin_flooded"] == pytest.approx(1.0, abs=2e-3)
    mg = res[50.0].mg
    # past the inlet column the gap is full where the contact draws its oil from
    assert np.all(mg.theta[np.abs(mg.y) <= 1.0, 1:] == 1.0)


def test_the_oil_is_conserved_through_the_unpressurised_inlet(layers):
    """Upstream of the meniscus, away from any pressure, rho theta H u is the flux carried in:
    theta H = h_oil (rho = 1) at every such point, to round-off."""
    _, h_ff, res = layers
    for r in (1.0, 0.5, 0.2):
        mg = res[r].mg
        H_oil = r * h_ff / res[r].contact.film_scale
        P = mg.P
        quiet = np.zeros_like(P, dtype=bool)  # P = 0 at the point and its four neighbours
        quiet[1:-1, 1:-1] = ((P[1:-1, 1:-1] == 0) & (P[:-2, 1:-1] == 0) & (P[2:, 1:-1] == 0)
                             & (P[1:-1, :-2] == 0) & (P[1:-1, 2:] == 0))
        quiet &= (mg.x[None, :] < -1.05) & (mg.theta < 1.0)
        assert quiet.sum() > 20
        flux = mg.theta[quiet] * mg.H[quiet]
        assert np.max(np.abs(flux - H_oil)) < 1e-9 * H_oil


def test_a_thin_layer_gives_a_film_below_the_layer_and_the_film_grows_with_it(layers):
    _, h_ff, res = layers
    hc = {r: res[r].H_central * res[r].contact.film_scale for r in res}
    assert hc[0.2] <= 0.2 * h_ff * (1 + 1e-6)  # mass: no more oil leaves than came in
    assert hc[0.5] <= 0.5 * h_ff * (1 + 1e-6)
    assert hc[0.2] < hc[0.5] < hc[1.0] < hc[50.0]
    assert res[0.2].summary()["hc_over_hc_flooded"] < 0.3


def test_the_meniscus_moves_downstream_as_the_layer_thins(layers):
    _, _, res = layers
    dist = [res[r].summary()["inlet_meniscus_over_a"] for r in (50.0, 1.0, 0.5, 0.2)]
    assert dist[0] is not None and dist[0] >= 0.5  # flooded: the whole domain's inlet
    # strongly starved, the pressure starts inside the Hertzian circle (a distance < 0)
    assert dist[0] > dist[1] > dist[2] >= dist[3] > -0.5


def test_a_prescribed_meniscus_starves_the_film_more_the_closer_it_is():
    base = moes_spec(100.0, 5.0)
    flooded = solve(make_spec(**base))
    ratios = []
    for dist in (2.0, 0.3, 0.05):
        res = solve(make_spec(**base, inlet_meniscus=dist), flooded=flooded)
        assert res.converged
        s = res.summary()
        assert s["inlet_meniscus_over_a"] == pytest.approx(dist, abs=res.domain.h)
        assert np.all(res.mg.P[:, res.mg.x < -1.0 - dist] == 0.0)
        ratios.append(s["hc_over_hc_flooded"])
    assert 1.0 >= ratios[0] > 0.97 and ratios[0] > ratios[1] > ratios[2] > 0.2


@pytest.mark.parametrize("kw, words", [
    (dict(inlet_layer=-1e-8), ["inlet_layer", "-1e-08", "0 < inlet_layer <= 0.001 m"]),
    (dict(inlet_layer=0.0), ["inlet_layer", "0 < inlet_layer"]),
    (dict(inlet_meniscus=-0.5), ["inlet_meniscus = -0.5", "x = -0.5 a", "0 < inlet_meniscus"]),
    (dict(inlet_meniscus=0.5, inlet_layer=1e-8), ["both set", "inlet_layer", "inlet_meniscus"]),
    (dict(inlet_layer=1e-8, cavitation="twophase"), ["complementarity", "inlet_layer"]),
])
def test_bad_supply_is_refused_naming_key_value_and_range(kw, words):
    with pytest.raises(SpecError) as err:
        make_spec(**moes_spec(100.0, 5.0), **kw)
    for w in words:
        assert w in str(err.value), str(err.value)
