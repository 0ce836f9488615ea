"""The contact's film when the oil around it starves it: the starved EHL precalc at the inlet
meniscus the flow model found.

A flow model around the contact (the thin-film scene, a cycle of passes) finds where the
inlet meniscus stands; the EHL precalc with its ``inlet_meniscus`` option (the pressure held
at zero upstream of it, :mod:`ehlfoam.contact.inlet`) gives the film that meniscus lets the
contact build, against the fully flooded film on the same grid (hc / hc,ff). Each meniscus is
solved once per machine (the precalc cache); the meniscus is rounded to
:data:`MENISCUS_STEP` for it (an eighth of the thin-film model's coarse cell, which places
the meniscus no better), to :data:`MENISCUS_FAR_STEP` beyond 1 a (so that the passes of a
cycle and the points of a map share their solves), and held within :data:`MENISCUS_RANGE`: nearer than its lower
end (at or inside the contact's rim, where a thin-film cell cannot place it better) the film
is that of the lower end, farther than the upper end the film is the flooded one within
0.1 % at the reference conditions (Hamrock and Dowson's onset is at m* - 1 ~ 0.2-0.6 a).
SI units; distances upstream of the contact's leading edge x = -a, in a.
"""

from __future__ import annotations

import json
from typing import Any

from ehlfoam.contact.spec import PrecalcSpec
from ehlfoam.gap.source import PrecalcFailed, precalc_dir

__all__ = ["MENISCUS_FAR", "MENISCUS_FAR_STEP", "MENISCUS_RANGE", "MENISCUS_STEP",
           "solved_meniscus", "starved_film"]

#: The meniscus distances [a] the starved solve is made at: nearer or farther ones are held
#: at these ends (module docstring).
MENISCUS_RANGE = (0.05, 3.0)
#: The starved solves' meniscus distances are rounded to this [a] (one solve each) below
#: :data:`MENISCUS_FAR`, to :data:`MENISCUS_FAR_STEP` beyond it (where the film hardly
#: depends on the meniscus: within 0.2 % of the flooded one from 1.5 a to 3 a at the
#: reference conditions).
MENISCUS_STEP, MENISCUS_FAR, MENISCUS_FAR_STEP = 0.05, 1.0, 0.25


def solved_meniscus(meniscus_over_a: float) -> float:
    """The meniscus distance [a] the starved solve is made at for ``meniscus_over_a`` [a]:
    held within :data:`MENISCUS_RANGE`, rounded to :data:`MENISCUS_STEP` below
    :data:`MENISCUS_FAR` and to :data:`MENISCUS_FAR_STEP` beyond."""
    lo, hi = MENISCUS_RANGE
    d = min(max(float(meniscus_over_a), lo), hi)
    step = MENISCUS_STEP if d < MENISCUS_FAR else MENISCUS_FAR_STEP
    return round(round(d / step) * step, 6)


def starved_film(contact: PrecalcSpec, meniscus_over_a: float | None) -> dict[str, Any]:
    """The film of ``contact`` with its inlet meniscus ``meniscus_over_a`` [a] upstream of
    x = -a: ``hc_over_hc_flooded`` (the central film over the flooded one on the same grid)
    and the distance the solve was made at (``starved_meniscus_over_a``, rounded and held within
    :data:`MENISCUS_RANGE`). All None where there is no meniscus (None, not finite) or the
    starved solve did not converge (the precalc's folder kept in the cache)."""
    none = {"hc_over_hc_flooded": None, "starved_meniscus_over_a": None}
    if meniscus_over_a is None or not abs(meniscus_over_a) < float("inf"):
        return none
    d = solved_meniscus(meniscus_over_a)
    spec = contact.model_copy(update={"inlet_meniscus": d, "inlet_layer": None})
    try:
        folder = precalc_dir(spec)
    except PrecalcFailed:
        return {**none, "starved_meniscus_over_a": d}
    s = json.loads((folder / "summary.json").read_text())
    return {"hc_over_hc_flooded": s.get("hc_over_hc_flooded"), "starved_meniscus_over_a": d}
