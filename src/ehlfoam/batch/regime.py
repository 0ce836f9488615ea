"""Regime maps: flow pattern state I / II over speed and supply or temperature, transition
speeds with their uncertainty from the speed grid, hysteresis from speed ramps.

Input: the rows of a batch's results.csv (dicts; strings or typed values), keyed by the case
spec's dotted names in SI (``contact.speed`` [m/s], ...). Everything here is SI: speeds and
their differences in m/s (the keys say so: ``transition_m_s``). What a reader sees (text,
figures, display units) is made from it by :mod:`ehlfoam.report.regime`.

- **A line** is the sweep cases that differ in speed only (same temperature, load, supply and
  resolution). Its transition speed is the midpoint between the highest speed in state I and
  the lowest speed in state II above it; the uncertainty is half that gap. A line in state I
  (II) at every speed only bounds the transition from above (below). A line whose states do
  not go I...I II...II with speed is non-monotonic, with every switch listed.
- **A ramp** has an up branch and a down branch, each including the turning point it starts
  from. The up transition (I -> II) and the down transition (II -> I) are estimated on each
  branch as above; the hysteresis width is up minus down, its uncertainty the sum of the two
  half-gaps (the interval the grid allows), and hysteresis is *observed* when some speed was
  run on both branches with different states.

:func:`write_regime` writes ``regime/regime.json`` into a batch folder.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from ehlfoam._io import atomic_write_json
from ehlfoam.batch.plan import WHOLE_GAP_SUPPLIES, supply_label

__all__ = ["REGIME", "STATES", "analyse", "confirmations", "hysteresis", "point_state",
           "row_rung", "row_supply", "supply_sort", "transition", "write_regime"]

STATES = ("I", "II")
REGIME = "regime"
SPEED = "contact.speed"
#: what groups the cases of a line (besides the supply), and names its entry in regime.json
GROUP = ("contact.temperature", "contact.load", "rung")
#: notes without numbers (the report words those with numbers from the fields)
NO_CASE = "no finished case"
INVERTED = "state II only below state I (no I -> II with increasing speed): no transition"


# ------------------------------------------------------------------ row helpers
def _float(value: Any) -> float | None:
    if value is None or value == "":
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def row_supply(row: dict) -> str:
    """"flooded", "submerged", "2um" or "1+2um" (disc+ball) from a results row."""
    mode = row.get("supply.mode") or "?"
    d, b = _float(row.get("supply.disc_layer")), _float(row.get("supply.ball_layer"))
    if mode in WHOLE_GAP_SUPPLIES or d is None or b is None:
        return str(mode)
    return supply_label(mode, d, b)


def supply_sort(label: str) -> tuple:
    """Layers by their thickness, then the whole-gap supplies."""
    if label in WHOLE_GAP_SUPPLIES:
        return (1, WHOLE_GAP_SUPPLIES.index(label))
    try:
        return (0, sum(float(p) for p in label.removesuffix("um").split("+")))
    except ValueError:
        return (2, 0.0)


def point_state(row: dict) -> str:
    """"I", "II", "failed" or "pending" (anything not finished nor failed)."""
    status = row.get("status")
    if status == "finished" and row.get("state") in STATES:
        return row["state"]
    return "failed" if status == "failed" else "pending"


def _is_ramp(row: dict) -> bool:
    return row.get("ramp") not in (None, "")


def row_rung(row: dict) -> str:
    """The case's rung of the model ladder (its ``rung``: "thin-film-medium", "coarse",
    "resolved-medium"; a row of an older batch without one: its scene and mesh level, a row
    without a scene a 3D case)."""
    if row.get("rung"):
        return str(row["rung"])
    level = str(row.get("mesh.resolution"))
    return f"thin-film-{level}" if row.get("scene") == "thin-film" else level


def _group(row: dict) -> dict[str, Any]:
    return {"contact.temperature": _float(row.get("contact.temperature")),
            "contact.load": _float(row.get("contact.load")), "supply": row_supply(row),
            "mesh.resolution": str(row.get("mesh.resolution")), "rung": row_rung(row)}


# ------------------------------------------------------------------ transitions
def transition(speeds: Sequence[float], states: Sequence[str]) -> dict[str, Any]:
    """The I -> II transition of one line of (speed [m/s], state) points.

    Points not in state I or II are ignored. Returns {"transition_m_s", "uncertainty_m_s",
    "bracket_m_s": [highest I, lowest II above it], "bound": None | "above" | "below",
    "monotonic", "switches": [{"from", "to", "between_m_s"}], "note"} ("note": only the
    cases without numbers, :data:`NO_CASE` and :data:`INVERTED`).
    """
    pts = sorted((float(u), s) for u, s in zip(speeds, states) if s in STATES)
    out: dict[str, Any] = {"transition_m_s": None, "uncertainty_m_s": None,
                           "bracket_m_s": None, "bound": None, "monotonic": True,
                           "switches": [], "note": ""}
    if not pts:
        out["note"] = NO_CASE
        return out
    for (u0, s0), (u1, s1) in zip(pts, pts[1:]):
        if s0 != s1:
            out["switches"].append({"from": s0, "to": s1, "between_m_s": [u0, u1]})
    seq = [s for _, s in pts]
    first_ii = seq.index("II") if "II" in seq else len(seq)
    out["monotonic"] = "I" not in seq[first_ii:]
    i_speeds = [u for u, s in pts if s == "I"]
    ii_speeds = [u for u, s in pts if s == "II"]
    if not ii_speeds:
        out["bound"] = "above"
        return out
    if not i_speeds:
        out["bound"] = "below"
        return out
    top_i = max(i_speeds)
    above = [u for u in ii_speeds if u > top_i]
    if not above:
        out["note"] = INVERTED
        return out
    lo, hi = top_i, min(above)
    out.update(transition_m_s=0.5 * (lo + hi), uncertainty_m_s=0.5 * (hi - lo),
               bracket_m_s=[lo, hi])
    return out


def _points(rows: list[dict]) -> dict[str, Any]:
    speeds = [_float(r[SPEED]) for r in rows]
    states = [point_state(r) for r in rows]
    return {SPEED: speeds, "states": states, "case_ids": [r.get("case_id") for r in rows],
            **transition(speeds, states)}


def _lines(rows: Iterable[dict]) -> list[dict[str, Any]]:
    """Sweep rows grouped by everything but the speed, with their transitions (a 3D
    confirmation is no line of its own: :func:`confirmations` sets it beside its point)."""
    groups: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        if _is_ramp(r) or r.get("confirms") or _float(r.get(SPEED)) is None:
            continue
        groups[tuple(_group(r).values())].append(r)
    out = []
    for key, rs in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][1],
                                                          supply_sort(kv[0][2]), kv[0][4])):
        rs = sorted(rs, key=lambda r: _float(r[SPEED]))
        out.append({**_group(rs[0]), **_points(rs)})
    return out


def hysteresis(up: dict, down: dict) -> dict[str, Any]:
    """Width of the hysteresis loop (up transition - down transition) [m/s] with its
    uncertainty, and whether some speed run on both branches has different states."""
    shared: dict[float, dict[str, str]] = {}
    for u, s in zip(up[SPEED], up["states"]):
        shared.setdefault(u, {})["up"] = s
    for u, s in zip(down[SPEED], down["states"]):
        shared.setdefault(u, {})["down"] = s
    differ = sorted(u for u, d in shared.items()
                    if d.get("up") in STATES and d.get("down") in STATES and d["up"] != d["down"])
    out: dict[str, Any] = {"observed": bool(differ), "speeds_differing_m_s": differ,
                           "width_m_s": None, "uncertainty_m_s": None,
                           "width_bounds_m_s": None, "note": ""}
    if up["transition_m_s"] is None or down["transition_m_s"] is None:
        out["note"] = "no transition on a branch: width not determined"
        return out
    (lu, hu), (ld, hd) = up["bracket_m_s"], down["bracket_m_s"]
    out.update(width_m_s=up["transition_m_s"] - down["transition_m_s"],
               uncertainty_m_s=up["uncertainty_m_s"] + down["uncertainty_m_s"],
               width_bounds_m_s=[lu - hd, hu - ld])
    if not differ and out["width_m_s"] == 0:
        out["note"] = "both branches switch in the same speed interval: no hysteresis resolved"
    elif out["width_m_s"] < 0:
        out["note"] = "the down branch switches above the up branch (anomalous)"
    return out


def _ramps(rows: Iterable[dict]) -> list[dict[str, Any]]:
    by_name: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        if _is_ramp(r):
            by_name[str(r["ramp"])].append(r)
    out = []
    for name, rs in sorted(by_name.items()):
        rs = sorted(rs, key=lambda r: int(_float(r.get("ramp_step")) or 0))
        first = rs[0].get("ramp_direction")
        ups = [r for r in rs if r.get("ramp_direction") == "up"]
        downs = [r for r in rs if r.get("ramp_direction") == "down"]
        # each branch includes the turning point it starts from
        # a one-way ramp has one branch (the other would be its turning point alone)
        up = _points(([downs[-1]] if first == "down" and downs else []) + ups) if ups else None
        down = _points(([ups[-1]] if first == "up" and ups else []) + downs) if downs else None
        entry = {"name": name, **_group(rs[0]), "up": up, "down": down}
        if ups and downs:
            entry["hysteresis"] = hysteresis(up, down)
        out.append(entry)
    return out


def confirmations(rows: list[dict]) -> list[dict[str, Any]]:
    """Each confirming case beside the thin-film case it confirms: the speed [m/s], the
    thin-film case's group (temperature, load, its rung as ``rung``) and supply, the
    confirming rung (``confirm_rung``), both states, and whether they agree (None while
    either has no state)."""
    by_id = {r["case_id"]: r for r in rows}
    out = []
    for r in rows:
        tf = by_id.get(r.get("confirms") or "")
        if tf is None:
            continue
        states = (tf.get("state"), r.get("state"))
        agree = states[0] == states[1] if all(s in STATES for s in states) else None
        out.append({"case_id": r["case_id"], "confirms": tf["case_id"],
                    "contact.speed": float(r["contact.speed"]), **_group(tf),
                    "confirm_rung": row_rung(r),
                    "state": states[1], "thin_film_state": states[0], "agree": agree})
    return out


def analyse(rows: Iterable[dict]) -> dict[str, Any]:
    """Transitions of every sweep line and every ramp (see the module doc), and the 3D
    confirmations of thin-film points (:func:`confirmations`)."""
    rows = list(rows)
    return {"lines": _lines(rows), "ramps": _ramps(rows), "confirmations": confirmations(rows)}


def write_regime(batch_dir: str | Path, rows: Iterable[dict] | None = None) -> dict[str, Any]:
    """Analyse the batch's rows (default: its results.csv) and write ``regime/regime.json``.
    Returns the analysis."""
    batch_dir = Path(batch_dir)
    if rows is None:
        from ehlfoam.batch.results import read_results

        rows = read_results(batch_dir)
    result = analyse(rows)
    out = batch_dir / REGIME
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_json(out / "regime.json", result)
    return result
