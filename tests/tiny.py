"""The tiny case the OpenFOAM tests share: coarse mesh, 3 cells across the gap, a cheap
precalc (the gap outside the island hardly depends on the film's last digits), 1 ms of flow
from a puddle of 3 a around the contact. Builds in seconds, runs in seconds. And the numbers
of a made-up case (:func:`tiny_geometry`) for code that only reads a case's geometry."""

from ehlfoam.case.geometry import CaseGeometry

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


def tiny_geometry(**kw) -> CaseGeometry:
    """A :class:`CaseGeometry` of a made-up case (a = 0.1 mm, transit 0.1 s, 3 cells),
    ``kw`` overriding any field."""
    base = dict(a=1e-4, radius=0.01, speed=0.01, x_min=-1e-3, x_max=1e-3, y_max=1e-3,
                island_radius=1.5e-4, symmetric=True, n_layers=4, cells=3, transit_time=0.1,
                end_time=0.1, write_interval=0.01, max_delta_t=1e-4, capillary_limit="none",
                min_cell_size=1e-5, island_gap=1e-6, hc=1e-8, contact_flow=0.0,
                gap_mismatch=0.0, oil_viscosity=0.02, oil_density=870.0,
                solver="interPhaseChangeFoam")
    return CaseGeometry(**(base | kw))


def small_contact():
    """The tiny case's spec, its gap h(x, y) [m] and its Hertzian radius a [m] (the precalc
    solved once per machine, then reused)."""
    from ehlfoam.gap.source import load_gap
    from ehlfoam.spec.case import make_case_spec

    spec = make_case_spec(SMALL)
    return spec, load_gap(spec.contact)[0], spec.a


def as_toml(spec: dict) -> str:
    """A spec dict (scalars and one level of tables, as :data:`SMALL`) as TOML text."""
    import json

    top = [f"{k} = {json.dumps(v)}" for k, v in spec.items() if not isinstance(v, dict)]
    tables = [f"[{k}]\n" + "\n".join(f"{kk} = {json.dumps(vv)}" for kk, vv in v.items())
              for k, v in spec.items() if isinstance(v, dict)]
    return "\n".join(top + tables) + "\n"
