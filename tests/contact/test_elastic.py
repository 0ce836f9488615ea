"""Elastic deformation kernel of ehlfoam.contact against independent references.

References used here (none of them is the code's own output):
  * the closed-form integral of 1/r over a rectangle (self-influence of a cell) and
    numerical quadrature of 1/r over a cell (other cells), with the Boussinesq prefactor
    2/pi^2 of the Hertz-scaled problem;
  * a brute-force numpy double sum of the discrete convolution;
  * the Hertz deformation of Johnson, Contact Mechanics (1985), eq. 3.42, rewritten here in
    units of a^2/R.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from ehlfoam.contact.elastic import (Deformation, deformation_direct, hertz_deformation, hertz_pressure, influence_coefficients)

PREFACTOR = 2.0 / math.pi**2  # w = 2/(pi E') int p/r dA  ->  W = 2/pi^2 int P/R dA (Hertz units)


def johnson_hertz_deformation(r: np.ndarray) -> np.ndarray:
    """Sum of the normal displacements of both bodies under p = pH sqrt(1 - r^2/a^2).

    Johnson eq. 3.42 per body: u = (1-nu^2)/E * pi p0 (2a^2 - r^2) / (4a) inside and
    (1-nu^2)/E * p0/(2a) [(2a^2 - r^2) asin(a/r) + a sqrt(r^2 - a^2)] outside. Summed over
    both bodies (2/E' = sum (1-nu^2)/E), with p0 = E' a / (pi R), divided by a^2/R.
    """
    r = np.asarray(r, dtype=float)
    out = np.empty_like(r)
    inside = r <= 1.0
    out[inside] = (2.0 - r[inside] ** 2) / 2.0
    ro = r[~inside]
    out[~inside] = ((2.0 - ro**2) * np.arcsin(1.0 / ro) + np.sqrt(ro**2 - 1.0)) / math.pi
    return out


def rectangle_self_integral(a: float, b: float) -> float:
    """int_{-a}^{a} int_{-b}^{b} dx dy / sqrt(x^2 + y^2) (closed form)."""
    d = math.hypot(a, b)
    return 4.0 * (a * math.log((b + d) / a) + b * math.log((a + d) / b))


def cell_integral(dx: float, dy: float, hx: float, hy: float) -> float:
    """int over the cell centred at (0, 0) of 1/|(dx, dy) - (x', y')| by adaptive quadrature."""
    val, _ = integrate.dblquad(
        lambda y, x: 1.0 / math.hypot(dx - x, dy - y),
        -0.5 * hx, 0.5 * hx, -0.5 * hy, 0.5 * hy, epsabs=1e-13, epsrel=1e-11)
    return val


# --- influence coefficients ------------------------------------------------------------------

@pytest.mark.parametrize("hx, hy", [(0.1, 0.1), (0.05, 0.08)])
def test_self_influence_equals_closed_form(hx, hy):
    k = influence_coefficients(np.array(0.0), np.array(0.0), hx, hy)
    expected = PREFACTOR * rectangle_self_integral(0.5 * hx, 0.5 * hy)
    assert float(k) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("ix, iy", [(1, 0), (0, 1), (1, 1), (2, 3), (-4, 1), (7, -5)])
def test_influence_matches_quadrature(ix, iy):
    hx, hy = 0.05, 0.08
    dx, dy = ix * hx, iy * hy
    k = influence_coefficients(np.array(dx), np.array(dy), hx, hy)
    assert float(k) == pytest.approx(PREFACTOR * cell_integral(dx, dy, hx, hy), rel=1e-9)


def test_influence_far_field_is_point_load():
    hx, hy = 0.05, 0.08
    r = np.array([20.0, 50.0, 200.0])
    k = influence_coefficients(r / math.sqrt(2), r / math.sqrt(2), hx, hy)
    point = PREFACTOR * hx * hy / r
    rel = np.abs(k / point - 1.0)
    # the correction to a point load is O((h / r)^2)
    assert np.all(rel < 0.1 * ((hx**2 + hy**2) / r**2))
    assert rel[0] > rel[1] > rel[2]


# --- DC-FFT against direct summation ------------------------------------------------------------

def brute_force_deformation(p: np.ndarray, hx: float, hy: float) -> np.ndarray:
    """W_ij = sum_kl K(x_i - x_k, y_j - y_l) p_kl by explicit broadcasting (tiny grids only)."""
    ny, nx = p.shape
    x = np.arange(nx) * hx
    y = np.arange(ny) * hy
    dx = x[None, :, None, None] - x[None, None, None, :]  # (1, nx, 1, nx)
    dy = y[:, None, None, None] - y[None, None, :, None]  # (ny, 1, ny, 1)
    K = influence_coefficients(dx, dy, hx, hy)  # (ny, nx, ny, nx): field (j, i), source (l, k)
    return np.einsum("jilk,lk->ji", K, p)


def test_direct_summation_equals_brute_force():
    rng = np.random.default_rng(1)
    p = rng.random((9, 13))
    ref = brute_force_deformation(p, 0.11, 0.07)
    assert np.max(np.abs(deformation_direct(p, 0.11, 0.07) - ref)) < 1e-13 * np.max(np.abs(ref))


@pytest.mark.parametrize("ny, nx, hx, hy", [(33, 33, 0.1, 0.1), (24, 41, 0.07, 0.12),
                                            (17, 16, 0.2, 0.05)])
def test_dcfft_equals_direct_summation(ny, nx, hx, hy):
    rng = np.random.default_rng(ny * nx)
    p = rng.random((ny, nx))
    p[rng.random((ny, nx)) < 0.3] = 0.0  # zeros as in a cavitated region
    w_fft = Deformation(nx, ny, hx, hy)(p)
    w_dir = deformation_direct(p, hx, hy)
    assert w_fft.shape == (ny, nx)
    assert np.max(np.abs(w_fft - w_dir)) <= 1e-12 * np.max(np.abs(w_dir))


def test_dcfft_is_linear_and_reusable():
    rng = np.random.default_rng(7)
    op = Deformation(20, 30, 0.1, 0.1)
    p1, p2 = rng.random((30, 20)), rng.random((30, 20))
    w12 = op(2.0 * p1 - 3.0 * p2)
    assert np.allclose(w12, 2.0 * op(p1) - 3.0 * op(p2), rtol=0, atol=1e-12 * np.abs(w12).max())


# --- Hertz ---------------------------------------------------------------------------------------

def test_hertz_helpers_match_johnson():
    X, Y = np.meshgrid(np.linspace(-3, 3, 121), np.linspace(-2.5, 2.5, 101))
    r = np.hypot(X, Y)
    assert np.allclose(hertz_deformation(X, Y), johnson_hertz_deformation(r), rtol=0, atol=1e-13)
    assert np.allclose(hertz_pressure(X, Y), np.sqrt(np.clip(1 - r**2, 0, None)), atol=0)
    # continuity of the analytic deformation at the contact edge (both branches give 1/2)
    assert johnson_hertz_deformation(np.array([1.0 + 1e-12]))[0] == pytest.approx(0.5, abs=1e-6)


def _hertz_errors(n: int) -> tuple[float, float, float]:
    x = np.linspace(-1.5, 1.5, n)
    h = x[1] - x[0]
    X, Y = np.meshgrid(x, x)
    r = np.hypot(X, Y)
    W = Deformation(n, n, h, h)(hertz_pressure(X, Y))
    err = np.abs(W - johnson_hertz_deformation(r))
    H = 0.5 * r**2 + W  # rigid + elastic: flat (= 1, i.e. H0 = -1) inside the Hertz contact
    flat = np.abs(H[r < 0.9] - 1.0).max()
    return err[r < 1.0].max(), err[r > 1.0].max(), flat


@pytest.fixture(scope="module")
def hertz_errors():
    return {n: _hertz_errors(n) for n in (65, 129, 257)}


@pytest.mark.parametrize("region", [0, 1], ids=["inside", "outside"])
def test_hertz_deformation_converges(hertz_errors, region):
    e = [hertz_errors[n][region] for n in (65, 129, 257)]
    assert e[0] < 5e-3
    assert e[1] < 0.75 * e[0]
    assert e[2] < 0.75 * e[1]
    assert e[2] < 5e-4


def test_hertz_film_is_flat_inside_contact(hertz_errors):
    flat = [hertz_errors[n][2] for n in (65, 129, 257)]
    assert flat[1] < 1e-3  # within the discretisation error of the 129 grid
    assert flat[2] < flat[0]
