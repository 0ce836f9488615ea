"""Regime maps: flow pattern state I / II over speed and supply or temperature, transition
speeds with their uncertainty from the speed grid, hysteresis from speed ramps.

Input: the rows of a batch's results.csv (dicts; strings or typed values). Speeds in mm/s, as
in the batch spec.

- **A line** is the sweep cases that differ in speed only (same temperature, load, supply and
  resolution). Its transition speed is the midpoint between the highest speed in state I and
  the lowest speed in state II above it; the uncertainty is half that gap. A line in state I
  (II) at every speed only bounds the transition from above (below). A line whose states do
  not go I...I II...II with speed is reported as non-monotonic, with every switch listed.
- **A ramp** has an up branch and a down branch, each including the turning point it starts
  from. The up transition (I -> II) and the down transition (II -> I) are estimated on each
  branch as above; the hysteresis width is up minus down, its uncertainty the sum of the two
  half-gaps (the interval the grid allows), and hysteresis is *observed* when some speed was
  run on both branches with different states.

:func:`write_regime` writes ``regime/regime.json`` and the PNGs into a batch folder.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from ehlfoam._io import atomic_write, atomic_write_json

STATES = ("I", "II")
REGIME = "regime"


# ------------------------------------------------------------------ row helpers
def _float(value: Any) -> float | None:
    if value is None or value == "":
        return None
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def supply_label(row: dict) -> str:
    """"flooded", "2um" or "1+2um" (disc+ball) from a results row."""
    if row.get("supply") == "flooded":
        return "flooded"
    d, b = _float(row.get("disc_layer_um")), _float(row.get("ball_layer_um"))
    if d is None or b is None:
        return str(row.get("supply") or "?")
    return f"{d:g}um" if d == b else f"{d:g}+{b:g}um"


def _supply_sort(label: str) -> tuple:
    if label == "flooded":
        return (1, math.inf)
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


# ------------------------------------------------------------------ transitions
def transition(speeds: Sequence[float], states: Sequence[str]) -> dict[str, Any]:
    """The I -> II transition of one line of (speed [mm/s], state) points.

    Points not in state I or II are ignored. Returns {"transition_mm_s", "uncertainty_mm_s",
    "bracket": [highest I, lowest II above it], "bound": None | "above" | "below",
    "monotonic", "switches": [{"from", "to", "between"}], "note"}.
    """
    pts = sorted((float(u), s) for u, s in zip(speeds, states) if s in STATES)
    out: dict[str, Any] = {"transition_mm_s": None, "uncertainty_mm_s": None, "bracket": None,
                           "bound": None, "monotonic": True, "switches": [], "note": ""}
    if not pts:
        out["note"] = "no finished case"
        return out
    for (u0, s0), (u1, s1) in zip(pts, pts[1:]):
        if s0 != s1:
            out["switches"].append({"from": s0, "to": s1, "between": [u0, u1]})
    seq = [s for _, s in pts]
    first_ii = seq.index("II") if "II" in seq else len(seq)
    out["monotonic"] = "I" not in seq[first_ii:]
    i_speeds = [u for u, s in pts if s == "I"]
    ii_speeds = [u for u, s in pts if s == "II"]
    if not ii_speeds:
        out.update(bound="above", note=f"state I up to {max(i_speeds):g} mm/s: "
                                        f"transition above it")
        return out
    if not i_speeds:
        out.update(bound="below", note=f"state II from {min(ii_speeds):g} mm/s: "
                                        f"transition below it")
        return out
    top_i = max(i_speeds)
    above = [u for u in ii_speeds if u > top_i]
    if not above:
        out["note"] = ("state II only below state I (no I -> II with increasing speed): "
                       "no transition")
        return out
    lo, hi = top_i, min(above)
    out.update(transition_mm_s=0.5 * (lo + hi), uncertainty_mm_s=0.5 * (hi - lo),
               bracket=[lo, hi])
    if not out["monotonic"]:
        below = [u for u in ii_speeds if u < top_i]
        out["note"] = (f"non-monotonic: state II also at {', '.join(f'{u:g}' for u in below)} "
                       f"mm/s below the highest state I speed; transition taken above "
                       f"{top_i:g} mm/s")
    return out


def _lines(rows: Iterable[dict]) -> list[dict[str, Any]]:
    """Sweep rows grouped by everything but the speed, with their transitions."""
    groups: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        if _is_ramp(r) or _float(r.get("speed_mm_s")) is None:
            continue
        key = (_float(r.get("temperature_C")), _float(r.get("load_N")), supply_label(r),
               str(r.get("resolution")))
        groups[key].append(r)
    out = []
    for (T, F, supply, res), rs in sorted(groups.items(),
                                          key=lambda kv: (kv[0][0], kv[0][1],
                                                          _supply_sort(kv[0][2]), kv[0][3])):
        rs = sorted(rs, key=lambda r: _float(r["speed_mm_s"]))
        speeds = [_float(r["speed_mm_s"]) for r in rs]
        states = [point_state(r) for r in rs]
        out.append({"temperature_C": T, "load_N": F, "supply": supply, "resolution": res,
                    "speeds_mm_s": speeds, "states": states,
                    "case_ids": [r.get("case_id") for r in rs], **transition(speeds, states)})
    return out


def _branch(rows: list[dict], direction: str, start: dict | None) -> dict[str, Any]:
    rs = ([start] if start else []) + [r for r in rows if r.get("ramp_direction") == direction]
    speeds = [_float(r["speed_mm_s"]) for r in rs]
    states = [point_state(r) for r in rs]
    return {"speeds_mm_s": speeds, "states": states, "case_ids": [r.get("case_id") for r in rs],
            **transition(speeds, states)}


def hysteresis(up: dict, down: dict) -> dict[str, Any]:
    """Width of the hysteresis loop (up transition - down transition) with its uncertainty,
    and whether some speed run on both branches has different states."""
    shared = {}
    for u, s in zip(up["speeds_mm_s"], up["states"]):
        shared.setdefault(u, {})["up"] = s
    for u, s in zip(down["speeds_mm_s"], down["states"]):
        shared.setdefault(u, {})["down"] = s
    differ = sorted(u for u, d in shared.items()
                    if d.get("up") in STATES and d.get("down") in STATES and d["up"] != d["down"])
    out: dict[str, Any] = {"observed": bool(differ), "speeds_differing_mm_s": differ,
                           "width_mm_s": None, "uncertainty_mm_s": None, "width_bounds_mm_s": None,
                           "note": ""}
    if up["transition_mm_s"] is None or down["transition_mm_s"] is None:
        missing = [n for n, b in (("up", up), ("down", down)) if b["transition_mm_s"] is None]
        out["note"] = (f"no transition on the {' and '.join(missing)} branch "
                       f"({'; '.join(b['note'] for b in (up, down) if b['note'])}): "
                       "width not determined")
        return out
    (lu, hu), (ld, hd) = up["bracket"], down["bracket"]
    out.update(width_mm_s=up["transition_mm_s"] - down["transition_mm_s"],
               uncertainty_mm_s=up["uncertainty_mm_s"] + down["uncertainty_mm_s"],
               width_bounds_mm_s=[lu - hd, hu - ld])
    if not differ and out["width_mm_s"] == 0:
        out["note"] = "both branches switch in the same speed interval: no hysteresis resolved"
    elif out["width_mm_s"] < 0:
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
        up = _branch(rs, "up", downs[-1] if first == "down" and downs else None) if ups else None
        down = _branch(rs, "down", ups[-1] if first == "up" and ups else None) if downs else None
        r0 = rs[0]
        entry = {"name": name, "temperature_C": _float(r0.get("temperature_C")),
                 "load_N": _float(r0.get("load_N")), "supply": supply_label(r0),
                 "resolution": str(r0.get("resolution")), "up": up, "down": down}
        if ups and downs:
            entry["hysteresis"] = hysteresis(up, down)
        out.append(entry)
    return out


def _fmt_t(t: dict) -> str:
    if t["transition_mm_s"] is not None:
        text = f"I -> II at {t['transition_mm_s']:.3g} +- {t['uncertainty_mm_s']:.2g} mm/s"
        return text + (" (non-monotonic)" if not t["monotonic"] else "")
    return t["note"] or "no transition"


def summary_lines(result: dict) -> list[str]:
    """One line per sweep line and per ramp."""
    lines = []
    for ln in result["lines"]:
        lines.append(f"T {ln['temperature_C']:g} C, F {ln['load_N']:g} N, {ln['supply']}, "
                     f"{ln['resolution']}: {_fmt_t(ln)}")
    for rp in result["ramps"]:
        text = (f"ramp {rp['name']} ({rp['supply']}, T {rp['temperature_C']:g} C): "
                + "; ".join(f"{d} {_fmt_t(rp[d])}" for d in ("up", "down") if rp[d]))
        h = rp.get("hysteresis")
        if h:
            if h["width_mm_s"] is not None:
                text += (f"; hysteresis {'observed' if h['observed'] else 'not observed'}, "
                         f"width {h['width_mm_s']:.3g} +- {h['uncertainty_mm_s']:.2g} mm/s")
            else:
                text += f"; hysteresis {'observed' if h['observed'] else 'not determined'}"
            if h["speeds_differing_mm_s"]:
                text += (" (states differ at "
                         f"{', '.join(f'{u:g}' for u in h['speeds_differing_mm_s'])} mm/s)")
        lines.append(text)
    return lines


def analyse(rows: Iterable[dict]) -> dict[str, Any]:
    """Transitions of every sweep line and every ramp (see the module doc)."""
    rows = list(rows)
    result = {"lines": _lines(rows), "ramps": _ramps(rows)}
    result["summary"] = summary_lines(result)
    return result


# ------------------------------------------------------------------ figures
_STYLE = {"I": dict(marker="o", color="tab:blue", label="state I"),
          "II": dict(marker="^", color="tab:red", label="state II"),
          "failed": dict(marker="x", color="0.3", label="failed"),
          "pending": dict(marker="o", color="0.75", label="not run", mfc="none")}


def _plot_points(ax, speeds, y, states, seen: set) -> None:
    for u, s in zip(speeds, states):
        st = dict(_STYLE[s])
        label = st.pop("label")
        ax.plot([u], [y], linestyle="none", markersize=8, label=None if s in seen else label,
                **st)
        seen.add(s)


def _plot_transition(ax, t: dict, y: float, seen: set) -> None:
    if t["transition_mm_s"] is None:
        return
    label = None if "t" in seen else "transition +- grid"
    seen.add("t")
    ax.errorbar([t["transition_mm_s"]], [y], xerr=[t["uncertainty_mm_s"]], fmt="|",
                color="k", markersize=14, capsize=4, label=label)


def _arrows(ax, speeds, y) -> None:
    for u0, u1 in zip(speeds, speeds[1:]):
        ax.annotate("", xy=(u1, y), xytext=(u0, y),
                    arrowprops=dict(arrowstyle="->", color="0.45", lw=1.0,
                                    shrinkA=6, shrinkB=6))


def _panel(ax, rows_y: list[tuple[str, dict, bool]], title: str) -> None:
    """rows_y: (label, line or branch, is a ramp branch)."""
    seen: set = set()
    for y, (label, ln, ramp) in enumerate(rows_y):
        if ramp:
            _arrows(ax, ln["speeds_mm_s"], y)
        _plot_points(ax, ln["speeds_mm_s"], y, ln["states"], seen)
        _plot_transition(ax, ln, y, seen)
    ax.set_yticks(range(len(rows_y)), [r[0] for r in rows_y])
    ax.set_ylim(-0.6, len(rows_y) - 0.4)
    ax.set_xlabel("rolling speed u [mm/s]")
    ax.set_title(title, fontsize=10)
    ax.grid(axis="x", alpha=0.3)
    ax.legend(fontsize=8, loc="best")


def _figure(panels: list[tuple[str, list]], ylabel: str, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(panels)
    height = max(2.5, 0.45 * max(len(p[1]) for p in panels) + 1.6)
    fig, axes = plt.subplots(n, 1, figsize=(8.5, height * n), squeeze=False)
    for ax, (title, rows_y) in zip(axes[:, 0], panels):
        _panel(ax, rows_y, title)
        ax.set_ylabel(ylabel)
    fig.tight_layout()
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110))
    plt.close(fig)


def _ramp_rows(result: dict, T: float, F: float, res: str) -> list[tuple[str, dict, bool]]:
    out = []
    for rp in result["ramps"]:
        if (rp["temperature_C"], rp["load_N"], rp["resolution"]) != (T, F, res):
            continue
        for direction in ("up", "down"):
            branch = rp[direction]
            if branch and len(branch["speeds_mm_s"]) > (1 if direction == "down" else 0):
                arrow = "->" if direction == "up" else "<-"
                out.append((f"{rp['supply']} ramp {rp['name']} {direction} {arrow}",
                            _directed(branch, direction), True))
    return out


def _directed(branch: dict, direction: str) -> dict:
    """A branch with its points in run order (speeds increase up, decrease down)."""
    order = sorted(range(len(branch["speeds_mm_s"])), key=lambda k: branch["speeds_mm_s"][k],
                   reverse=direction == "down")
    return {**branch, "speeds_mm_s": [branch["speeds_mm_s"][k] for k in order],
            "states": [branch["states"][k] for k in order]}


def speed_supply_figure(result: dict, path: Path) -> bool:
    """State over (speed, supply), one panel per temperature/load/resolution, ramp branches
    as rows of their own with arrows. False if there is nothing to draw."""
    keys = sorted({(ln["temperature_C"], ln["load_N"], ln["resolution"])
                   for ln in result["lines"]} |
                  {(rp["temperature_C"], rp["load_N"], rp["resolution"])
                   for rp in result["ramps"]}, key=str)
    panels = []
    for T, F, res in keys:
        lines = sorted((ln for ln in result["lines"]
                        if (ln["temperature_C"], ln["load_N"], ln["resolution"]) == (T, F, res)),
                       key=lambda ln: _supply_sort(ln["supply"]))
        rows_y = [(ln["supply"], ln, False) for ln in lines] + _ramp_rows(result, T, F, res)
        if rows_y:
            panels.append((f"T = {T:g} C, F = {F:g} N, {res} mesh", rows_y))
    if not panels:
        return False
    _figure(panels, "oil supply (layer on disc and ball)", path)
    return True


def speed_temperature_figure(result: dict, path: Path) -> bool:
    """State over (speed, temperature), one panel per supply/load/resolution."""
    keys = sorted({(ln["supply"], ln["load_N"], ln["resolution"]) for ln in result["lines"]},
                  key=lambda k: (_supply_sort(k[0]), k[1], k[2]))
    panels = []
    for supply, F, res in keys:
        lines = sorted((ln for ln in result["lines"]
                        if (ln["supply"], ln["load_N"], ln["resolution"]) == (supply, F, res)),
                       key=lambda ln: ln["temperature_C"])
        panels.append((f"supply {supply}, F = {F:g} N, {res} mesh",
                       [(f"{ln['temperature_C']:g} C", ln, False) for ln in lines]))
    if not panels:
        return False
    _figure(panels, "temperature", path)
    return True


def hysteresis_figure(result: dict, path: Path) -> bool:
    """Per ramp: state against speed, up branch and down branch with arrows."""
    ramps = [rp for rp in result["ramps"] if rp.get("hysteresis")]
    if not ramps:
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(ramps), 1, figsize=(8.5, 3.2 * len(ramps)), squeeze=False)
    level = {"I": 0.0, "II": 1.0, "failed": 0.5, "pending": 0.5}
    for ax, rp in zip(axes[:, 0], ramps):
        seen: set = set()
        for direction, dy, colour in (("up", 0.04, "tab:purple"), ("down", -0.04, "tab:green")):
            b = _directed(rp[direction], direction)
            ys = [level[s] + dy for s in b["states"]]
            ax.plot(b["speeds_mm_s"], ys, "-", color=colour, lw=1.2, alpha=0.7,
                    label=f"ramp {direction}")
            for (u0, y0), (u1, y1) in zip(zip(b["speeds_mm_s"], ys),
                                          zip(b["speeds_mm_s"][1:], ys[1:])):
                ax.annotate("", xy=(u1, y1), xytext=(u0, y0),
                            arrowprops=dict(arrowstyle="->", color=colour, lw=1.4,
                                            shrinkA=5, shrinkB=5))
            for u, s, y in zip(b["speeds_mm_s"], b["states"], ys):
                st = dict(_STYLE[s])
                lab = st.pop("label")
                ax.plot([u], [y], linestyle="none", markersize=8,
                        label=None if s in seen else lab, **st)
                seen.add(s)
            t = rp[direction]
            if t["bracket"]:
                ax.axvspan(*t["bracket"], color=colour, alpha=0.12)
        h = rp["hysteresis"]
        width = (f"width {h['width_mm_s']:.3g} +- {h['uncertainty_mm_s']:.2g} mm/s"
                 if h["width_mm_s"] is not None else "width not determined")
        ax.set_title(f"ramp {rp['name']}: {rp['supply']}, T = {rp['temperature_C']:g} C, "
                     f"F = {rp['load_N']:g} N; hysteresis "
                     f"{'observed' if h['observed'] else 'not observed'}, {width}", fontsize=10)
        ax.set_yticks([0, 1], ["state I", "state II"])
        ax.set_ylim(-0.4, 1.4)
        ax.set_xlabel("rolling speed u [mm/s]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="center left")
    fig.tight_layout()
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110))
    plt.close(fig)
    return True


def write_regime(batch_dir: str | Path, rows: Iterable[dict] | None = None) -> dict[str, Any]:
    """Analyse the batch's rows (default: its results.csv) and write ``regime/regime.json``,
    ``regime/speed_supply.png``, ``regime/speed_temperature.png`` and
    ``regime/hysteresis.png`` (those with something to draw). Returns the analysis."""
    batch_dir = Path(batch_dir)
    if rows is None:
        from ehlfoam.batch.results import read_results

        rows = read_results(batch_dir)
    result = analyse(rows)
    out = batch_dir / REGIME
    out.mkdir(parents=True, exist_ok=True)
    figures = []
    for name, draw in (("speed_supply.png", speed_supply_figure),
                       ("speed_temperature.png", speed_temperature_figure),
                       ("hysteresis.png", hysteresis_figure)):
        if draw(result, out / name):
            figures.append(f"{REGIME}/{name}")
    result["figures"] = figures
    atomic_write_json(out / "regime.json", result)
    return result
