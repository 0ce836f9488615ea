"""The oil share of an inlet face, against areas worked out by hand."""

from __future__ import annotations

import numpy as np
import pytest

from ehlfoam.case import face_oil

UM = 1e-6


def _quad(y0, y1, lo0, hi0, lo1, hi1):
    """A face between columns at y0 and y1, from lo to hi [m] on each: (y, z) in order."""
    return np.array([[y0, lo0], [y1, lo1], [y1, hi1], [y0, hi0]])


def test_a_face_under_a_ball_that_climbs_more_than_its_height_gets_its_share():
    """Ball from 100 to 104 um across the face (y 0 -> 100 um), face 1 um below it (99-100
    at y = 0, 103-104 at y = 100 um), ball layer 2 um: all oil. A face 2-3 um below the ball:
    half oil (the layer's edge runs along the face's middle). Sorting the corners' heights
    would make both 4-5 um tall faces straddling the layer's edge."""
    ball = (np.array([0.0, 100 * UM]), np.array([100 * UM, 104 * UM]))
    top = _quad(0.0, 100 * UM, 99 * UM, 100 * UM, 103 * UM, 104 * UM)
    assert face_oil.oil_fraction(top, ball, 3 * UM, 2 * UM, (0.0, 1.0)) == pytest.approx(1.0)
    mid = _quad(0.0, 100 * UM, 97.5 * UM, 98.5 * UM, 101.5 * UM, 102.5 * UM)
    assert face_oil.oil_fraction(mid, ball, 3 * UM, 2 * UM, (0.0, 1.0)) == pytest.approx(0.5)


def test_the_disc_layer_the_track_edge_and_its_dry_middle_cut_the_face():
    """A flat gap of 50 um, a face from z = 0 to 4 um over y 0-100 um, a 3 um disc layer:
    3/4 oil; a track edge at y = 60 um keeps 60 % of that; a dry middle out to 20 um takes
    a quarter of what is left; flooded, the face is all oil on the track."""
    ball = (np.array([0.0, 50 * UM]), np.array([100 * UM, 50 * UM]))
    face = _quad(0.0, 100 * UM, 0.0, 4 * UM, 0.0, 4 * UM)
    frac = face_oil.oil_fraction
    assert frac(face, ball, 3 * UM, 3 * UM, (0.0, 1.0)) == pytest.approx(0.75)
    assert frac(face, ball, 3 * UM, 3 * UM, (0.0, 60 * UM)) == pytest.approx(0.75 * 0.6)
    assert frac(face, ball, 3 * UM, 3 * UM, (20 * UM, 60 * UM)) == pytest.approx(0.75 * 0.4)
    assert frac(face, ball, 3 * UM, 3 * UM, (0.0, 60 * UM), flooded=True) == pytest.approx(0.6)
    # the face's corners in the other order, and one on the y < 0 side: the same shares
    assert frac(face[::-1], ball, 3 * UM, 3 * UM, (0.0, 60 * UM)) == pytest.approx(0.45)
    mirrored = face * [-1.0, 1.0]
    ball_m = (ball[0] * [-1.0, 1.0], ball[1] * [-1.0, 1.0])
    assert frac(mirrored, ball_m, 3 * UM, 3 * UM, (0.0, 60 * UM)) == pytest.approx(0.45)


def test_layers_thicker_than_the_gap_fill_it_once():
    """Disc and ball layers of 30 um each in a 50 um gap: the face is all oil, not more."""
    ball = (np.array([0.0, 50 * UM]), np.array([100 * UM, 50 * UM]))
    face = _quad(0.0, 100 * UM, 0.0, 50 * UM, 0.0, 50 * UM)
    assert face_oil.oil_fraction(face, ball, 30 * UM, 30 * UM, (0.0, 1.0)) == pytest.approx(1.0)
