"""Hertz theory, Moes groups, film-thickness formulas and lubricant laws of ehlfoam.contact.

The expected values are the reference numbers of the project (van Emden 2017: 20 N,
R = 9.525 mm, E' = 1.11e11 Pa, HVI60 at 40 C, 10 mm/s -> a = 0.137 mm, pH = 0.509 GPa,
M = 3900, L = 1.9), published identities (Hertz, Moes/Venner-Lubrecht), and the published
asymptotes and regression formulas written out here independently.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ehlfoam.contact.formulas import (Contact, contact_from_moes, hamrock_dowson, moes_to_hertz_film, nijenbanning_moes_hc)
from ehlfoam.contact.lubricant import OIL_TABLES, Lubricant, PressureLaws, lubricant_from_table, table_range
from ehlfoam.contact.spec import make_spec

F_REF, R_REF, E_REF = 20.0, 9.525e-3, 1.11e11


@pytest.fixture(scope="module")
def nominal() -> Contact:
    return make_spec(load=20, speed=0.01, temperature=40, lubricant="HVI60").contact()


# --- Hertz ------------------------------------------------------------------------------------

def test_hertz_reference_numbers():
    c = Contact(load=F_REF, radius=R_REF, modulus=E_REF, speed=0.01, eta0=0.0216, alpha=2.13e-8)
    assert c.a == pytest.approx(0.137e-3, rel=0.01)
    assert c.p_hertz == pytest.approx(0.509e9, rel=0.01)


@pytest.mark.parametrize("F, R, E", [(20.0, 9.525e-3, 1.11e11), (1.0, 0.01, 2.26e11),
                                     (500.0, 0.05, 1e9)])
def test_hertz_identities(F, R, E):
    c = Contact(load=F, radius=R, modulus=E, speed=1.0, eta0=0.01, alpha=2e-8)
    # Johnson: a^3 = 3 F R / (4 E*) with E* = E'/2; load = integral of the Hertz pressure
    assert c.a**3 == pytest.approx(3 * F * R / (4 * (E / 2)), rel=1e-12)
    assert 2 * math.pi / 3 * c.p_hertz * c.a**2 == pytest.approx(F, rel=1e-12)
    # p0 = 2 a E* / (pi R) (Johnson eq. 4.25 with E* = E'/2)
    assert c.p_hertz == pytest.approx(2 * c.a * (E / 2) / (math.pi * R), rel=1e-12)
    assert c.film_scale == pytest.approx(c.a**2 / R, rel=1e-12)


# --- Moes groups ------------------------------------------------------------------------------

def test_moes_reference_numbers(nominal):
    assert nominal.M == pytest.approx(3900, rel=0.015)
    assert nominal.L == pytest.approx(1.9, rel=0.015)


def test_groups_from_their_definitions(nominal):
    eta0, alpha = 21.6e-3, 2.13e-8  # HVI60 at 40 C (table)
    U = eta0 * 0.01 / (E_REF * R_REF)
    W = F_REF / (E_REF * R_REF**2)
    G = alpha * E_REF
    assert nominal.U == pytest.approx(U, rel=1e-12)
    assert nominal.W == pytest.approx(W, rel=1e-12)
    assert nominal.G == pytest.approx(G, rel=1e-12)
    assert nominal.M == pytest.approx(W * (2 * U) ** -0.75, rel=1e-12)
    assert nominal.L == pytest.approx(G * (2 * U) ** 0.25, rel=1e-12)


@pytest.mark.parametrize("M, L", [(20.0, 10.0), (3886.0, 1.89), (1.0, 0.0), (1e4, 25.0)])
def test_lambda_and_alpha_bar_identities(M, L):
    """Venner & Lubrecht (2000): lambda = (128 pi^3 / (3 M^4))^(1/3), alpha pH = L/pi (3M/2)^(1/3)."""
    c = contact_from_moes(M, L)
    assert c.lam == pytest.approx((128 * math.pi**3 / (3 * M**4)) ** (1 / 3), rel=1e-10)
    assert c.alpha * c.p_hertz == pytest.approx(L / math.pi * (1.5 * M) ** (1 / 3), rel=1e-10,
                                                abs=1e-300)


@pytest.mark.parametrize("M, L", [(20.0, 10.0), (3886.0, 1.89), (0.5, 0.0), (1e5, 30.0)])
def test_contact_from_moes_reproduces_groups(M, L):
    c = contact_from_moes(M, L)
    assert c.M == pytest.approx(M, rel=1e-12)
    assert c.L == pytest.approx(L, rel=1e-12, abs=1e-12)
    assert c.load > 0 and c.speed > 0 and c.alpha >= 0
    assert (c.alpha == 0.0) == (L == 0.0)


@pytest.mark.parametrize("h", [1e-9, 8.7e-9, 3e-7])
def test_moes_to_hertz_film_inverts_moes_film(nominal, h):
    c2 = contact_from_moes(20, 10)
    for c in (nominal, c2):
        H_moes = c.moes_film(h)
        assert H_moes == pytest.approx(h / c.radius * (2 * c.U) ** -0.5, rel=1e-12)
        assert moes_to_hertz_film(H_moes, c.M) * c.film_scale == pytest.approx(h, rel=1e-12)


# --- Hamrock-Dowson ---------------------------------------------------------------------------

def test_hamrock_dowson_published_form(nominal):
    c = nominal
    k = 1.0
    hc = 2.69 * c.U**0.67 * c.G**0.53 * c.W**-0.067 * (1 - 0.61 * math.exp(-0.73 * k)) * c.radius
    hmin = 3.63 * c.U**0.68 * c.G**0.49 * c.W**-0.073 * (1 - math.exp(-0.68 * k)) * c.radius
    got = hamrock_dowson(c)
    assert got[0] == pytest.approx(hc, rel=1e-12)
    assert got[1] == pytest.approx(hmin, rel=1e-12)
    assert 1e-9 < got[1] < got[0] < 1e-7


def test_nvm_and_hamrock_dowson_agree_at_reference(nominal):
    """Two independent regressions agree within 10 % at the reference operating point."""
    c = nominal
    nvm = moes_to_hertz_film(nijenbanning_moes_hc(c.M, c.L), c.M) * c.film_scale
    hd = hamrock_dowson(c)[0]
    assert nvm == pytest.approx(hd, rel=0.10)


# --- Nijenbanning-Venner-Moes asymptotes (circular contact, D = 1) --------------------------------

B1 = 1.63  # b(D = 1) = 1 + 0.006 ln 1 + 0.63


def h_ri(M):
    return 145.0 * (1.796) ** (-15 / 7) * M**-2.0


def h_ei(M):
    return 3.18 * B1 ** (-14 / 25) * M ** (-2 / 15)


def h_rp(L):
    return 1.29 * (1.691) ** (-2 / 3) * L ** (2 / 3)


def h_ep(M, L):
    return 1.48 * B1**-0.35 * M ** (-1 / 12) * L**0.75


def _rel(a, b):
    return abs(a / b - 1.0)


def test_nvm_rigid_isoviscous_asymptote():
    errs = [_rel(nijenbanning_moes_hc(M, 0.0), h_ri(M)) for M in (0.1, 0.01, 1e-3)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3


def test_nvm_elastic_isoviscous_asymptote():
    errs = [_rel(nijenbanning_moes_hc(M, 0.0), h_ei(M)) for M in (1e2, 1e4, 1e6)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3


def test_nvm_rigid_piezoviscous_asymptote():
    errs = [_rel(nijenbanning_moes_hc(1.0, L), h_rp(L)) for L in (1e2, 1e3, 1e5)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3


def test_nvm_elastic_piezoviscous_asymptote():
    # deep in EP: M >> L (h_ep << h_rp) and L large (h_ep >> h_ei)
    pts = [(1e4, 10.0), (1e6, 30.0), (1e8, 100.0)]
    errs = [_rel(nijenbanning_moes_hc(M, L), h_ep(M, L)) for M, L in pts]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 5e-3


def test_nvm_monotone_in_M_and_L():
    Ms = np.geomspace(1, 1e4, 25)
    Ls = np.linspace(0, 20, 21)
    H = np.array([[nijenbanning_moes_hc(M, L) for L in Ls] for M in Ms])
    assert np.all(np.diff(H, axis=0) < 0)  # more load (or less speed) -> thinner film
    assert np.all(np.diff(H, axis=1) > 0)  # more piezoviscous -> thicker film
    assert nijenbanning_moes_hc(50.0, 1e-9) == pytest.approx(nijenbanning_moes_hc(50.0, 0.0),
                                                             rel=1e-4)


# --- lubricant ----------------------------------------------------------------------------------

@pytest.mark.parametrize("T, eta0, alpha", [(25.0, 44.7e-3, 2.25e-8), (40.0, 21.6e-3, 2.13e-8),
                                            (60.0, 10.2e-3, 1.97e-8)])
def test_hvi60_table_points(T, eta0, alpha):
    oil = lubricant_from_table("HVI60", T)
    assert oil.eta0 == pytest.approx(eta0, rel=1e-12)
    assert oil.alpha == pytest.approx(alpha, rel=1e-12)
    assert oil.rho0 == 870.0
    assert oil.name == "HVI60"


def test_hvi60_interpolation():
    assert table_range("HVI60") == (25.0, 60.0)
    # ln(eta0) and alpha linear in T between the table points (documented rule)
    mid = lubricant_from_table("HVI60", 32.5)
    assert mid.eta0 == pytest.approx(math.sqrt(44.7e-3 * 21.6e-3), rel=1e-12)
    assert mid.alpha == pytest.approx(0.5 * (2.25e-8 + 2.13e-8), rel=1e-12)
    oil = lubricant_from_table("HVI60", 55.0)
    assert oil.eta0 == pytest.approx(21.6e-3 ** 0.25 * 10.2e-3 ** 0.75, rel=1e-12)
    T = np.linspace(25, 60, 141)
    etas = np.array([lubricant_from_table("HVI60", t).eta0 for t in T])
    alphas = np.array([lubricant_from_table("HVI60", t).alpha for t in T])
    assert np.all(np.diff(etas) < 0)
    assert np.all(np.diff(alphas) < 0)
    assert etas.min() >= 10.2e-3 * (1 - 1e-12) and etas.max() <= 44.7e-3 * (1 + 1e-12)
    assert set(OIL_TABLES) >= {"HVI60"}


@pytest.fixture(scope="module")
def laws():
    oil = Lubricant(eta0=21.6e-3, alpha=2.13e-8, rho0=870.0)
    return {v: PressureLaws(p_hertz=0.5e9, lubricant=oil, viscosity=v) for v in ("barus", "roelands")}


def test_barus_viscosity(laws):
    P = np.array([0.0, 0.3, 1.0, 1.5])
    assert np.allclose(laws["barus"].eta(P), np.exp(2.13e-8 * 0.5e9 * P), rtol=1e-12)


def test_roelands_viscosity_published_form(laws):
    p0, ln_eta_inf = 1.96e8, math.log(6.31e-5)
    ln_eta0 = math.log(21.6e-3)
    z = 2.13e-8 * p0 / (ln_eta0 - ln_eta_inf)
    P = np.array([0.0, 0.2, 1.0, 2.0])
    p = P * 0.5e9
    expected = np.exp((ln_eta0 - ln_eta_inf) * ((1 + p / p0) ** z - 1))
    assert np.allclose(laws["roelands"].eta(P), expected, rtol=2e-3)  # ln(6.31e-5) = -9.6709
    # initial slope d ln(eta)/dp = alpha (Barus limit at low pressure)
    dP = 1e-7
    slope = math.log(float(laws["roelands"].eta(np.array([dP]))[0])) / (dP * 0.5e9)
    assert slope == pytest.approx(2.13e-8, rel=1e-4)
    # Roelands grows slower than Barus at high pressure; sub-ambient pressure uses eta0
    assert laws["roelands"].eta(np.array([2.0]))[0] < laws["barus"].eta(np.array([2.0]))[0]
    assert laws["roelands"].eta(np.array([-0.5]))[0] == 1.0


def test_dowson_higginson_density():
    oil = Lubricant(eta0=21.6e-3, alpha=2.13e-8, rho0=870.0)
    law = PressureLaws(p_hertz=0.5e9, lubricant=oil)
    P = np.array([0.0, 0.5, 2.0, 1e4])
    rho, drho = law.rho(P)
    p = P * 0.5e9
    assert np.allclose(rho, (5.9e8 + 1.34 * p) / (5.9e8 + p), rtol=1e-12)
    assert rho[0] == 1.0 and rho[-1] == pytest.approx(1.34, rel=1e-4)
    eps = 1e-6
    fd = (law.rho(P + eps)[0] - law.rho(P - eps)[0]) / (2 * eps)  # central, P > 0
    assert np.allclose(drho[1:3], fd[1:3], rtol=1e-5)
    fd0 = (law.rho(np.array([eps]))[0][0] - 1.0) / eps  # one-sided at ambient
    assert drho[0] == pytest.approx(fd0, rel=1e-4)
    inc = PressureLaws(p_hertz=0.5e9, lubricant=oil, density="incompressible")
    r2, d2 = inc.rho(P)
    assert np.all(r2 == 1.0) and np.all(d2 == 0.0)


def test_twophase_density_below_ambient():
    oil = Lubricant(eta0=21.6e-3, alpha=2.13e-8, rho0=870.0)
    ps = 1e4
    law = PressureLaws(p_hertz=0.5e9, lubricant=oil, density="incompressible",
                       twophase_p_scale=ps)
    P = np.array([-1e-4, -1e-5, -1e-12, 0.0, 0.1])
    rho, drho = law.rho(P)
    # mixture density proportional to the absolute pressure p_s + p, zero at p = -p_s
    assert np.allclose(rho[:3], np.maximum(1.0 + P[:3] * 0.5e9 / ps, 0.0), rtol=1e-12)
    assert rho[0] == 0.0  # below vacuum: no mass
    assert rho[2] == pytest.approx(1.0, rel=1e-6)  # continuous at ambient
    assert np.all(rho[3:] == 1.0)
    assert np.allclose(drho[:3], 0.5e9 / ps, rtol=1e-12)
