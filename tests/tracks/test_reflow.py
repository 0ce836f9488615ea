"""The reflow of a layer across its track (ehlfoam.tracks.reflow): capillary levelling
against linear theory (a sinusoid's decay rate, a small ridge's kernel and its t^(1/4)
spreading), the volume kept to round-off, the centrifugal drift's direction, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.tracks.reflow import levelling_rate, levelling_time, reflow

SIGMA, ETA, H0 = 0.03, 0.0216, 2e-6     # HVI60 at 40 C on a 2 um layer
D = SIGMA * H0**3 / (3 * ETA)          # the linear equation's h_t = -D h_yyyy [m4/s]


@pytest.mark.parametrize("waves", [1, 2])
def test_a_small_sinusoid_decays_at_the_linear_rate(waves):
    """h0 + eps cos(k y) with k = 2 pi waves / L on closed ends decays at sigma h0^3 k^4 /
    (3 eta): after one e-folding time the amplitude is e^-1 within 0.3 % (backward Euler's
    own error at 400 steps, 0.1 %, and the 100-cell wave's)."""
    n, length = 200, 400e-6
    dy = length / n
    y = (np.arange(n) + 0.5) * dy
    k = 2 * np.pi * waves / length
    eps = 1e-3 * H0
    t = 1.0 / levelling_rate(H0, k, SIGMA, ETA)
    out = reflow(H0 + eps * np.cos(k * y), dy, t, SIGMA, ETA, steps=400, growth=1.0,
                 precursor=0.0)
    amplitude = 2.0 / n * np.sum((out.h - H0) * np.cos(k * y))
    assert amplitude / eps == pytest.approx(np.exp(-1.0), rel=3e-3)
    assert out.volume_error < 1e-13


def _kernel(y: np.ndarray, t: float, amp: float, w: float) -> np.ndarray:
    """The linear equation's answer for amp exp(-y^2 / w^2) at t = 0: the cosine transform
    A w sqrt(pi) exp(-k^2 w^2 / 4) damped by exp(-D k^4 t), transformed back."""
    k = np.linspace(0.0, 12.0 / w, 8001)
    spectrum = amp * w * np.sqrt(np.pi) * np.exp(-k * k * w * w / 4 - D * k**4 * t) / np.pi
    return np.trapezoid(spectrum[None, :] * np.cos(np.outer(y, k)), k, axis=1)


def test_a_small_ridge_spreads_as_the_linear_kernel_with_width_t_to_a_quarter():
    """A ridge of 0.1 % of the layer on it (the thin-ridge limit) follows the linear
    equation's solution within 0.5 % of its peak at t = tau and 16 tau (tau = w^4 / D), and
    its half-height width grows as t^(1/4) (x 2 from tau to 16 tau) within 5 %."""
    w, amp = 40e-6, 1e-3 * H0
    n, width = 200, 1e-3
    dy = width / n
    y = (np.arange(n) + 0.5) * dy
    h = H0 + amp * np.exp(-(y / w) ** 2)
    tau = levelling_time(H0, w, SIGMA, ETA)             # w^4 / D
    assert tau == pytest.approx(w**4 / D)
    halves = []
    for t in (tau, 16 * tau):
        out = reflow(h, dy, t, SIGMA, ETA, steps=200, growth=1.02, precursor=0.0)
        ridge = out.h - H0
        exact = _kernel(y, t, amp, w)
        assert np.abs(ridge - exact).max() <= 5e-3 * exact.max()
        half = np.interp(0.5, (ridge / ridge[0])[::-1][-40:], y[::-1][-40:])
        halves.append(half)
    assert halves[1] / halves[0] == pytest.approx(2.0, rel=0.05)


def test_a_ridge_on_dry_ground_keeps_its_volume_and_stays_positive():
    """A 10 um ridge beside dry wall (a precursor of 1 nm) levels for a revolution: its
    volume to round-off, no cell below zero, its peak down and its foot out."""
    n, dy = 300, 5e-6
    y = (np.arange(n) + 0.5) * dy
    h = np.where(np.abs(y - 4e-4) < 1e-4, 10e-6 * (1 - ((y - 4e-4) / 1e-4) ** 2), 0.0)
    out = reflow(h, dy, 30.0, SIGMA, ETA, precursor=1e-9)
    assert out.volume_error < 1e-12
    assert (out.h >= 0).all()
    assert out.h.max() < 0.9 * h.max()
    assert np.count_nonzero(out.h > 1e-8) > np.count_nonzero(h > 1e-8)


def test_the_centrifugal_force_drifts_the_layer_outward():
    """With rho u^2 / r along +y the layer's centroid moves to +y; without it, not at all;
    the volume is kept either way."""
    n, dy = 200, 5e-6
    y = (np.arange(n) + 0.5) * dy - n * dy / 2
    h = 5e-6 * np.exp(-(y / 5e-5) ** 2)
    still = reflow(h, dy, 1.0, SIGMA, ETA)
    spun = reflow(h, dy, 1.0, SIGMA, ETA, body_force=2e5)
    centroid = [float(np.sum(y * r.h) / np.sum(r.h)) for r in (still, spun)]
    assert abs(centroid[0]) < 1e-9
    assert centroid[1] > 1e-7
    assert spun.volume_error < 1e-12


@pytest.mark.parametrize("kw, name", [({"dy": 0.0}, "dy"), ({"duration": -1.0}, "duration"),
                                      ({"sigma": 0.0}, "sigma"), ({"steps": 0}, "steps"),
                                      ({"h": np.array([1e-6, -1e-6, 1e-6])}, "h")])
def test_bad_arguments_are_named(kw, name):
    args = {"h": np.full(10, 1e-6), "dy": 1e-5, "duration": 1.0, "sigma": SIGMA, "eta": ETA}
    args.update({k: v for k, v in kw.items() if k in args})
    extra = {k: v for k, v in kw.items() if k not in args}
    with pytest.raises(ValueError, match=rf"^{name} = .* out of range"):
        reflow(**args, **extra)
