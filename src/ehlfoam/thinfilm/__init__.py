"""The gap-averaged (thin-film) model of the oil around the contact: Reynolds flow inside
capillary menisci, marched to its balance in seconds to minutes (:mod:`.march`), its states
on disc (:mod:`.state`), its bubble's gas balance (:mod:`.gas`), and the rigid-gap Reynolds solution of the single-phase check
(:mod:`.rigid`).

    prob = ThinFilmProblem(gap=..., speed=0.008, ...)
    sol = solve_thin_film(prob)
    sol.metrics(a)
"""

from ehlfoam.thinfilm.gas import GasBalance
from ehlfoam.thinfilm.march import solve_thin_film
from ehlfoam.thinfilm.problem import Grid, ThinFilmProblem, landau_levich
from ehlfoam.thinfilm.solution import ThinFilmSolution, connected_region, region_metrics
from ehlfoam.thinfilm.state import load_state, save_state

__all__ = [
    "GasBalance",
    "Grid",
    "ThinFilmProblem",
    "ThinFilmSolution",
    "connected_region",
    "landau_levich",
    "load_state",
    "region_metrics",
    "save_state",
    "solve_thin_film",
]
