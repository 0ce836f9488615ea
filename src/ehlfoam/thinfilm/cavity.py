"""The thin-film model's outlet: gas out of the oil where its pressure would fall below the
cavitation (gas-release) pressure, mass-conserving (Elrod and Adams's film content).

Every cell that is not flooded holds gas in the middle of its gap. The gas of an open cell
that reaches the domain's open edges through other open cells (4-neighbours: the upstream
column, the outlet column and the side row) is the **outer air**, at ambient pressure, and
meets the flooded region in menisci at Young-Laplace's pressure. The gas of an open cell
that the flooded region (with the island and the symmetry plane y = 0) encloses is a
**cavity**: gas the oil gave up, at the cavitation pressure p_cav (gauge, < 0), whatever
made it. Through a cavity the walls carry the oil a cell holds, its film content c < h, on
at their speed u, all of it: striations or films, as Elrod and Adams's cavitated region
(Jakobsson, Floberg and Olsson's conditions), not the Landau-Levich films a receding air
meniscus lays. A cavity fills again where that oil meets the flooded region downstream
(the reformation boundary).

The switch is Elrod-Adams's complementarity, solved each step by an active set: the flooded
cells' pressure is solved with every cavity's boundary at p_cav and every meniscus's pressure
floored at p_cav (the oil cannot hold a tension below it at an air meniscus either: it
gives its gas to the air); a flooded cell below p_cav opens (its oil is still all there, as
film content) and the pressure is solved again, until none is below. A cell opened so
beside the outer air joins it: the meniscus moves in. A cavity that grows to reach the
outer air becomes outer air: the wake opens (state II). Gas release kinetics and the
dissolved air's budget are not modelled here: the gas comes out the moment the pressure falls
below p_cav, as much as the oil's room needs (docs/models/thin-film.md#the-outlet), unless
the problem has a gas balance (:mod:`ehlfoam.thinfilm.gas`): then each cavity's pressure is
that of the air it holds, and its menisci are Young-Laplace's below it.
"""

from __future__ import annotations

import numpy as np

from ehlfoam.thinfilm.kernels import edge_connected, edge_connected_from
from ehlfoam.thinfilm.pass_kernels import open_cells

__all__ = ["cavities", "cavities_and_outer_air", "outer_air"]


def outer_air(gas: np.ndarray, closed_side: bool = False,
              before: np.ndarray | None = None) -> np.ndarray:
    """The cells of ``gas`` (bool, ny x nx: the open cells) connected through other gas cells
    (4-neighbours) to the domain's open edges: the upstream column, the outlet column and,
    unless ``closed_side``, the side row y = y_max (row 0 is the symmetry plane y = 0).
    ``before``: the outer air of a gas that ``gas`` holds (the open cells before some
    flooded ones opened), grown from rather than found anew."""
    gas = np.ascontiguousarray(gas, dtype=np.bool_)
    if before is None:
        return edge_connected(gas, closed_side)
    return edge_connected_from(gas, closed_side, np.ascontiguousarray(before, dtype=np.bool_))


def cavities(flooded: np.ndarray, island: np.ndarray, closed_side: bool = False,
             before: np.ndarray | None = None) -> np.ndarray:
    """The open cells whose gas the flooded region encloses (bool, ny x nx): not flooded, not
    island, and not connected to the outer air (:func:`outer_air`; ``before``: the outer
    air of a flooded set that held this one)."""
    return cavities_and_outer_air(flooded, island, closed_side, before)[0]


def cavities_and_outer_air(flooded: np.ndarray, island: np.ndarray, closed_side: bool = False,
                           before: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`cavities` and the outer air they were told from (:func:`outer_air`): the
    open cells are the two together."""
    flooded = np.ascontiguousarray(flooded, dtype=np.bool_)
    island = np.ascontiguousarray(island, dtype=np.bool_)
    if before is None:
        return open_cells(flooded, island, closed_side, flooded, False)
    return open_cells(flooded, island, closed_side,
                      np.ascontiguousarray(before, dtype=np.bool_), True)
