"""Dry (unlubricated) circular contact: the limit lambda -> 0 of the EHL problem.

Solves P >= 0, H >= 0, P H = 0 with h^2 sum(P) = 2 pi / 3 and H = H0 + (X^2 + Y^2)/2 + W(P)
by the conjugate-gradient method of Polonsky & Keer (Wear 231, 1999) on the same
DC-FFT deformation operator as the EHL solver. The exact answer is Hertz: P = sqrt(1 - r^2),
H0 = -1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ehlfoam.contact.elastic import Deformation
from ehlfoam.contact.multigrid import LOAD_TARGET


@dataclass
class DryResult:
    x: np.ndarray
    y: np.ndarray
    P: np.ndarray
    H0: float
    load_error: float
    iterations: int
    converged: bool


def solve_dry(n: int = 257, half_width: float = 1.5, tol: float = 1e-10,
              max_iter: int = 2000) -> DryResult:
    """Dry contact on an n x n grid over [-half_width, half_width]^2 (units of a)."""
    x = np.linspace(-half_width, half_width, n)
    h = x[1] - x[0]
    X, Y = np.meshgrid(x, x)
    rigid = 0.5 * (X**2 + Y**2)
    deform = Deformation(n, n, h, h)
    area = h * h
    P = np.full((n, n), LOAD_TARGET / (area * n * n))
    t = np.zeros_like(P)
    G_old, delta = 1.0, 0.0
    converged = False
    it = 0
    H0 = 0.0
    for it in range(1, max_iter + 1):
        g = deform(P) + rigid
        contact = P > 0.0
        g_mean = g[contact].mean()
        g = g - g_mean
        G = float(np.sum(g[contact] ** 2))
        t = np.where(contact, g + delta * (G / G_old) * t, 0.0)
        G_old = G
        r = deform(t)
        r = r - r[contact].mean()
        tau = float(np.sum(g[contact] * t[contact]) / np.sum(r[contact] * t[contact]))
        P_old = P.copy()
        P = np.where(contact, P - tau * t, 0.0)
        P = np.maximum(P, 0.0)
        overlap = (P == 0.0) & (g < 0.0)
        if np.any(overlap):
            P[overlap] -= tau * g[overlap]
            delta = 0.0
        else:
            delta = 1.0
        P *= LOAD_TARGET / (area * P.sum())
        H0 = -g_mean
        err = area * np.abs(P - P_old).sum() / LOAD_TARGET
        if err < tol:
            converged = True
            break
    load_error = abs(area * P.sum() - LOAD_TARGET) / LOAD_TARGET
    return DryResult(x=x, y=x.copy(), P=P, H0=H0, load_error=load_error, iterations=it,
                     converged=converged)
