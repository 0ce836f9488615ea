"""Dry (unlubricated) contact against the exact Hertz solution: P = sqrt(1 - r^2), H0 = -1."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ehlfoam.contact.dry import solve_dry
from ehlfoam.contact.elastic import deformation_direct


@pytest.fixture(scope="module")
def dry():
    return solve_dry(129)


@pytest.fixture(scope="module")
def grid(dry):
    X, Y = np.meshgrid(dry.x, dry.y)
    return X, Y, np.hypot(X, Y)


def test_dry_converged_and_load(dry):
    h = dry.x[1] - dry.x[0]
    assert dry.converged
    assert dry.load_error < 1e-4
    # independent load balance: integral of P equals that of the Hertz pressure, 2 pi / 3
    assert h * h * dry.P.sum() == pytest.approx(2 * math.pi / 3, rel=1e-4)


def test_dry_pressure_is_hertzian(dry, grid):
    X, Y, r = grid
    exact = np.sqrt(np.clip(1 - r**2, 0, None))
    assert np.abs(dry.P - exact)[r < 0.9].max() < 1e-3
    j, i = np.argmin(np.abs(dry.y)), np.argmin(np.abs(dry.x))
    assert dry.P[j, i] == pytest.approx(1.0, abs=1e-3)
    assert np.all(dry.P >= 0.0)
    assert np.all(dry.P[r > 1.05] == 0.0)  # contact radius = a


def test_dry_film_constant_and_complementarity(dry, grid):
    X, Y, r = grid
    assert dry.H0 == pytest.approx(-1.0, abs=1e-3)
    h = dry.x[1] - dry.x[0]
    gap = dry.H0 + 0.5 * r**2 + deformation_direct(dry.P, h, h)
    # closed (gap ~ 0) where pressed, open (gap >= 0) elsewhere
    assert np.abs(gap[dry.P > 0]).max() < 1e-3
    assert gap[dry.P == 0].min() > -1e-3
    assert gap[r > 1.2].min() > 0.0
