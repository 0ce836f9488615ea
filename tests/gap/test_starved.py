"""The contact's film at an inlet meniscus a flow model found (ehlfoam.gap.starved, issue 75):
the starved EHL precalc, cached, its meniscus rounded and held within its range."""

from __future__ import annotations

import pytest

from ehlfoam.contact.spec import PrecalcSpec
from ehlfoam.gap.starved import MENISCUS_RANGE, solved_meniscus, starved_film
from tests.tiny import SMALL


@pytest.fixture(scope="module")
def cache(tmp_path_factory, request):
    mp = pytest.MonkeyPatch()
    mp.setenv("EHLFOAM_CACHE", str(tmp_path_factory.mktemp("cache")))
    request.addfinalizer(mp.undo)


def test_the_film_thins_as_the_meniscus_nears_the_contact(cache):
    """Far upstream the film is the flooded one; at the contact's rim it is thinner (Hamrock
    and Dowson's starvation); nearer than the range's end it is the end's film (one solve),
    and no meniscus gives no film."""
    contact = PrecalcSpec(**SMALL["contact"])
    far, near = starved_film(contact, 50.0), starved_film(contact, -0.4)
    assert far["starved_meniscus_over_a"] == MENISCUS_RANGE[1]
    assert near["starved_meniscus_over_a"] == MENISCUS_RANGE[0]
    assert far["hc_over_hc_flooded"] == pytest.approx(1.0, abs=0.01)
    assert 0.3 < near["hc_over_hc_flooded"] < 0.97 * far["hc_over_hc_flooded"]
    assert starved_film(contact, 0.01) == near                      # held at the range's end
    assert starved_film(contact, None) == {"hc_over_hc_flooded": None,
                                           "starved_meniscus_over_a": None}


def test_the_meniscus_is_held_within_the_range_and_rounded_coarser_far_out():
    assert solved_meniscus(-0.4) == solved_meniscus(0.01) == MENISCUS_RANGE[0]
    assert solved_meniscus(50.0) == MENISCUS_RANGE[1]
    assert solved_meniscus(0.52) == 0.5 and solved_meniscus(0.98) == 1.0
    assert solved_meniscus(1.6) == 1.5 and solved_meniscus(1.66) == 1.75
