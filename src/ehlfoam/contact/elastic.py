"""Elastic deformation of the contacting surfaces (dimensionless, Hertz-scaled).

Lengths are in units of the Hertzian radius ``a`` and pressures in units of the
Hertzian pressure ``pH``; the deformation is in units of ``a**2 / R`` so that

    W(X, Y) = 2 / pi**2 * integral P(X', Y') / sqrt((X - X')**2 + (Y - Y')**2) dX' dY'.

The pressure is piecewise constant on cells centred on the grid points, which gives the
closed-form influence coefficients of :func:`influence_coefficients`. The discrete
convolution is evaluated with a zero-padded FFT (DC-FFT, Liu, Wang & Liu 2000), exact for
the discrete sum and O(N log N); :func:`deformation_direct` is the O(N^2) reference.
"""

from __future__ import annotations

import numpy as np
import scipy.fft as sfft
from numba import njit, prange

ELASTIC_PREFACTOR = 2.0 / np.pi**2


def _primitive(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Antiderivative F(x, y) of 1/sqrt(x^2 + y^2) over x and y (zero-safe)."""
    r = np.sqrt(x * x + y * y)
    with np.errstate(divide="ignore", invalid="ignore"):
        fx = np.where(x != 0.0, x * np.log(np.where(r + y > 0, y + r, 1.0)), 0.0)
        fy = np.where(y != 0.0, y * np.log(np.where(r + x > 0, x + r, 1.0)), 0.0)
    return fx + fy


def influence_coefficients(dx: np.ndarray, dy: np.ndarray, hx: float, hy: float) -> np.ndarray:
    """Deformation at offset (dx, dy) from a unit pressure on one hx-by-hy cell.

    Args:
        dx, dy: offsets of the field point from the cell centre (units of a), broadcastable.
        hx, hy: cell sizes (units of a).
    Returns:
        The influence coefficient K(dx, dy) (units of a**2/R per unit P).
    """
    xp, xm = dx + 0.5 * hx, dx - 0.5 * hx
    yp, ym = dy + 0.5 * hy, dy - 0.5 * hy
    val = _primitive(xp, yp) - _primitive(xm, yp) - _primitive(xp, ym) + _primitive(xm, ym)
    return ELASTIC_PREFACTOR * val


def _even_extension(kernel: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """The kernel K(|d|) of a (ny, nx) grid as a circulant of ``size`` (at most 2n a side):
    entry m along an axis holds K(min(m, size - m)) (offsets d and d - size alias), zero
    where that offset is beyond the grid (m = n of a 2n circulant)."""
    padded = np.zeros((kernel.shape[0] + 1, kernel.shape[1] + 1))
    padded[:-1, :-1] = kernel
    iy = np.arange(size[0])
    ix = np.arange(size[1])
    iy = np.minimum(iy, size[0] - iy)
    ix = np.minimum(ix, size[1] - ix)
    return padded[iy[:, None], ix[None, :]]


class Deformation:
    """DC-FFT deformation operator on one uniform (ny, nx) grid.

    ``op(P)`` returns W on the same grid; the kernel spectrum is computed once. A pressure
    that vanishes on the first row and the first column (the solver's Dirichlet inlet and
    side boundary) needs a circulant of only 2(n - 1) points a side (offsets from -(n - 1)
    to n - 2 occur), a power of two (or three times one: 1536 on 769 points) on the
    solver's grids, sizes the FFT takes fast; any other pressure uses
    2n. The zero padding is skipped axis by axis (half the rows transformed), and the
    kernel's spectrum is real (the kernel is even). ``workers``: threads of scipy.fft.
    """

    def __init__(self, nx: int, ny: int, hx: float, hy: float, workers: int = 1):
        self.nx, self.ny, self.hx, self.hy = nx, ny, hx, hy
        self.workers = workers
        kx = np.arange(nx) * hx
        ky = np.arange(ny) * hy
        self.kernel = influence_coefficients(kx[None, :], ky[:, None], hx, hy)
        self._spectra: dict[tuple[int, int], np.ndarray] = {}

    def _spectrum(self, size: tuple[int, int]) -> np.ndarray:
        if size not in self._spectra:
            ext = _even_extension(self.kernel, size)
            self._spectra[size] = sfft.rfft2(ext, workers=self.workers).real.copy()
        return self._spectra[size]

    def __call__(self, p: np.ndarray) -> np.ndarray:
        """Deformation W (units a**2/R) of the pressure field ``p`` (units pH), shape (ny, nx)."""
        ny, nx, w = self.ny, self.nx, self.workers
        zero_edges = ny > 1 and nx > 1 and not (p[0, :].any() or p[:, 0].any())
        size = (2 * (ny - 1), 2 * (nx - 1)) if zero_edges else (2 * ny, 2 * nx)
        t = sfft.rfft(p, n=size[1], axis=1, workers=w)
        t = sfft.fft(t, n=size[0], axis=0, workers=w, overwrite_x=True)
        t *= self._spectrum(size)
        t = sfft.ifft(t, axis=0, workers=w, overwrite_x=True)[:ny]
        return sfft.irfft(t, n=size[1], axis=1, workers=w)[:, :nx]


@njit(parallel=True, cache=True)
def _direct_sum(p, kernel, out):
    ny, nx = p.shape
    for j in prange(ny):
        for i in range(nx):
            s = 0.0
            for l in range(ny):
                dl = abs(j - l)
                for k in range(nx):
                    pv = p[l, k]
                    if pv != 0.0:
                        s += kernel[dl, abs(i - k)] * pv
            out[j, i] = s


def deformation_direct(p: np.ndarray, hx: float, hy: float) -> np.ndarray:
    """Reference O(N^2) direct summation of the same discrete convolution as :class:`Deformation`."""
    ny, nx = p.shape
    kernel = influence_coefficients(
        (np.arange(nx) * hx)[None, :], (np.arange(ny) * hy)[:, None], hx, hy
    )
    out = np.empty_like(p, dtype=float)
    _direct_sum(np.ascontiguousarray(p, dtype=float), kernel, out)
    return out


def hertz_pressure(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Dimensionless Hertzian pressure sqrt(1 - r^2) (units pH), zero outside r = 1."""
    r2 = X**2 + Y**2
    return np.sqrt(np.clip(1.0 - r2, 0.0, None))


def hertz_deformation(X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """Analytic deformation of the Hertzian pressure (units a**2/R).

    Inside the contact W = 1 - r^2/2, outside W = ((2 - r^2) asin(1/r) + sqrt(r^2 - 1)) / pi.
    """
    r = np.sqrt(X**2 + Y**2)
    inside = 1.0 - 0.5 * r**2
    ro = np.maximum(r, 1.0)
    outside = ((2.0 - ro**2) * np.arcsin(1.0 / ro) + np.sqrt(ro**2 - 1.0)) / np.pi
    return np.where(r <= 1.0, inside, outside)
