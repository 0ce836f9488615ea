"""The tiny case the OpenFOAM tests share: coarse mesh, 3 cells across the gap, a cheap
precalc (the gap outside the island hardly depends on the film's last digits), 1 ms of flow
from a puddle of 3 a around the contact. Builds in seconds, runs in seconds."""

SMALL = {
    "name": "test",
    "contact": {"speed": 0.02, "grid": 129, "tol_residual": 1e-4},
    "mesh": {"resolution": "coarse", "size_rim": 0.25, "size_far": 1.2, "n_layers": 3,
             "wall_grading": 3.0},
    "domain": {"upstream": 5.0, "downstream": 7.0, "side": 5.0},
    "supply": {"mode": "layers", "disc_layer": 3e-6, "ball_layer": 3e-6,
               "track_half_width": 2.5e-4, "initial_puddle": 3.0},
    "run": {"end_time": 1e-3, "writes_per_transit": 1000},
}
