"""The regime map as a reader sees it: one line of text per sweep line and ramp, and the
pictures (state over speed and supply, over speed and temperature, the ramps' hysteresis),
from the batch's SI analysis (:mod:`ehlfoam.batch.regime`, ``regime/regime.json``), in the
display units of :mod:`ehlfoam.report.units`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ehlfoam._io import atomic_write
from ehlfoam.batch.regime import NO_CASE, SPEED, supply_sort
from ehlfoam.report import units

__all__ = ["FIGURES", "hysteresis_figure", "speed_supply_figure", "speed_temperature_figure",
           "summary_lines", "transition_text", "write_figures"]

#: why a 3D level opens a region the thin-film rung keeps closed (its films)
DRAINS = ("the 3D levels lay films 1.5-2 times the model's and drain a state I region: "
          "docs/ladder.md#why-the-3d-levels-drain-at-state-i")

_U = units.SPEC[SPEED]
_T = units.SPEC["contact.temperature"]
_F = units.SPEC["contact.load"]


def _u(v: float) -> float:
    """A speed [m/s] in its display unit."""
    return v * _U.scale


def _speeds(values: list[float]) -> str:
    return f"{', '.join(f'{_u(v):.4g}' for v in values)} {_U.unit}"


def _conditions(entry: dict) -> str:
    return (f"{_T.symbol} {entry['contact.temperature']:g} {_T.unit}, "
            f"{_F.symbol} {entry['contact.load']:g} {_F.unit}")


# ------------------------------------------------------------------ text
def transition_text(t: dict) -> str:
    """A line's or branch's transition in words, e.g. "I -> II at 14.5 +- 2.5 mm/s"."""
    speeds = [u for u, s in zip(t[SPEED], t["states"]) if s in ("I", "II")]
    if t["transition_m_s"] is not None:
        text = (f"I -> II at {_u(t['transition_m_s']):.3g} +- "
                f"{_u(t['uncertainty_m_s']):.2g} {_U.unit}")
        if not t["monotonic"]:
            top_i = t["bracket_m_s"][0]
            below = [u for u, s in zip(t[SPEED], t["states"]) if s == "II" and u < top_i]
            text += (f" (non-monotonic: state II also at {_speeds(sorted(below))} below the "
                     f"highest state I speed; transition taken above {_u(top_i):g} {_U.unit})")
        return text
    if t["bound"] == "above":
        return f"state I up to {_u(max(speeds)):g} {_U.unit}: transition above it"
    if t["bound"] == "below":
        return f"state II from {_u(min(speeds)):g} {_U.unit}: transition below it"
    return t["note"] or NO_CASE


def _hysteresis_text(h: dict) -> str:
    if h["width_m_s"] is not None:
        text = (f"hysteresis {'observed' if h['observed'] else 'not observed'}, width "
                f"{_u(h['width_m_s']):.3g} +- {_u(h['uncertainty_m_s']):.2g} {_U.unit}")
    else:
        text = f"hysteresis {'observed' if h['observed'] else 'not determined'}"
    if h["speeds_differing_m_s"]:
        text += f" (states differ at {_speeds(h['speeds_differing_m_s'])})"
    return text


def summary_lines(result: dict) -> list[str]:
    """One line per sweep line and per ramp of a regime analysis."""
    lines = [f"{_conditions(ln)}, {ln['supply']}, {_rung(ln)}: "
             f"{transition_text(ln)}" for ln in result.get("lines", [])]
    for rp in result.get("ramps", []):
        text = (f"ramp {rp['name']} ({rp['supply']}, {_T.symbol} "
                f"{rp['contact.temperature']:g} {_T.unit}): "
                + "; ".join(f"{d} {transition_text(rp[d])}" for d in ("up", "down") if rp[d]))
        if rp.get("hysteresis"):
            text += f"; {_hysteresis_text(rp['hysteresis'])}"
        lines.append(text)
    confs = result.get("confirmations", [])
    for c in confs:
        verdict = {True: "agrees", False: "disagrees", None: "no state yet"}[c["agree"]]
        if c["agree"] is False and (c["state"], c["thin_film_state"]) == ("II", "I"):
            verdict += f" ({DRAINS})"
        lines.append(f"3D confirmation ({_rung_text(c['confirm_rung'])}) of "
                     f"{_rung_text(c['rung'])} at {_u(c[SPEED]):.4g} {_U.unit}, "
                     f"{c['supply']}, {_conditions(c)}: state {c['state'] or '-'} against "
                     f"{c['thin_film_state'] or '-'}, {verdict}")
    if confs:
        agree = sum(c["agree"] is True for c in confs)
        lines.append(f"3D confirmations: {agree} of {len(confs)} agree with the thin-film state")
    return lines


# ------------------------------------------------------------------ figures
_STYLE = {"I": dict(marker="o", color="tab:blue", label="state I"),
          "II": dict(marker="^", color="tab:red", label="state II"),
          "failed": dict(marker="x", color="0.3", label="failed"),
          "pending": dict(marker="o", color="0.75", label="not run", mfc="none")}
_AXIS = f"rolling speed {units.short_label(SPEED)}"


def _plot_points(ax, speeds, y, states, seen: set) -> None:
    for u, s in zip(speeds, states):
        st = dict(_STYLE[s])
        label = st.pop("label")
        ax.plot([_u(u)], [y], linestyle="none", markersize=8,
                label=None if s in seen else label, **st)
        seen.add(s)


def _plot_transition(ax, t: dict, y: float, seen: set) -> None:
    if t["transition_m_s"] is None:
        return
    label = None if "t" in seen else "transition +- grid"
    seen.add("t")
    ax.errorbar([_u(t["transition_m_s"])], [y], xerr=[_u(t["uncertainty_m_s"])], fmt="|",
                color="k", markersize=14, capsize=4, label=label)


_RINGS = {True: dict(color="tab:green", label="3D agrees"),
          False: dict(color="tab:purple", label="3D disagrees")}


def _plot_confirmations(ax, confs: list[dict], y: float, seen: set) -> None:
    """A ring round each confirmed point: green where the 3D rung agrees on the state."""
    for c in confs:
        if c["agree"] is None:
            continue
        st = dict(_RINGS[c["agree"]])
        label = st.pop("label")
        ax.plot([_u(c[SPEED])], [y], linestyle="none", marker="o", markersize=15, mfc="none",
                mew=2, label=None if label in seen else label, **st)
        seen.add(label)


def _arrows(ax, speeds, y) -> None:
    for u0, u1 in zip(speeds, speeds[1:]):
        ax.annotate("", xy=(_u(u1), y), xytext=(_u(u0), y),
                    arrowprops=dict(arrowstyle="->", color="0.45", lw=1.0,
                                    shrinkA=6, shrinkB=6))


def _panel(ax, rows_y: list[tuple[str, dict, bool]], title: str,
           confs: list[dict] = ()) -> None:
    """rows_y: (label, line or branch, is a ramp branch); ``confs``: the 3D confirmations
    of the panel's lines (a ring on the line of their supply)."""
    seen: set = set()
    for y, (label, ln, ramp) in enumerate(rows_y):
        if ramp:
            _arrows(ax, ln[SPEED], y)
        _plot_points(ax, ln[SPEED], y, ln["states"], seen)
        _plot_transition(ax, ln, y, seen)
        if not ramp:
            _plot_confirmations(ax, [c for c in confs if c["supply"] == ln["supply"]], y, seen)
    ax.set_yticks(range(len(rows_y)), [r[0] for r in rows_y])
    ax.set_ylim(-0.6, len(rows_y) - 0.4)
    ax.set_xlabel(_AXIS)
    ax.set_title(title, fontsize=10)
    ax.grid(axis="x", alpha=0.3)
    ax.legend(fontsize=8, loc="best")


def _save(fig, path: Path) -> None:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    atomic_write(path, lambda fh: fig.savefig(fh, format="png", dpi=110))
    plt.close(fig)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _figure(panels: list[tuple], ylabel: str, path: Path) -> None:
    """panels: (title, rows_y) or (title, rows_y, confirmations)."""
    plt = _pyplot()
    n = len(panels)
    height = max(2.5, 0.45 * max(len(p[1]) for p in panels) + 1.6)
    fig, axes = plt.subplots(n, 1, figsize=(8.5, height * n), squeeze=False)
    for ax, (title, rows_y, *confs) in zip(axes[:, 0], panels):
        _panel(ax, rows_y, title, *confs)
        ax.set_ylabel(ylabel)
    _save(fig, path)


def _rung(entry: dict) -> str:
    """The entry's rung ("coarse", "thin-film-medium"; older analyses: the mesh level)."""
    return entry.get("rung") or entry["mesh.resolution"]


def _rung_text(rung: str) -> str:
    """"thin-film medium", "resolved medium", "coarse mesh"."""
    if " " in rung:                          # an older analysis's "thin-film medium"
        return rung
    family, _, level = rung.rpartition("-")
    return f"{family} {level}" if family else f"{rung} mesh"


def _key(entry: dict) -> tuple:
    return entry["contact.temperature"], entry["contact.load"], _rung(entry)


def _directed(branch: dict, direction: str) -> dict:
    """A branch with its points in run order (speeds increase up, decrease down)."""
    order = sorted(range(len(branch[SPEED])), key=lambda k: branch[SPEED][k],
                   reverse=direction == "down")
    return {**branch, SPEED: [branch[SPEED][k] for k in order],
            "states": [branch["states"][k] for k in order]}


def _ramp_rows(result: dict, key: tuple) -> list[tuple[str, dict, bool]]:
    out = []
    for rp in result["ramps"]:
        if _key(rp) != key:
            continue
        for direction in ("up", "down"):
            branch = rp[direction]
            if branch and len(branch[SPEED]) > (1 if direction == "down" else 0):
                arrow = "->" if direction == "up" else "<-"
                out.append((f"{rp['supply']} ramp {rp['name']} {direction} {arrow}",
                            _directed(branch, direction), True))
    return out


def _title(key: tuple) -> str:
    T, F, res = key
    return f"{_T.symbol} = {T:g} {_T.unit}, {_F.symbol} = {F:g} {_F.unit}, {_rung_text(res)}"


def speed_supply_figure(result: dict, path: Path) -> bool:
    """State over (speed, supply), one panel per temperature/load/resolution, ramp branches
    as rows of their own with arrows. False if there is nothing to draw."""
    keys = sorted({_key(e) for e in result["lines"] + result["ramps"]},   # thin-film first
                  key=lambda k: (not str(k[2]).startswith("thin-film"), str(k)))
    panels = []
    for key in keys:
        lines = sorted((ln for ln in result["lines"] if _key(ln) == key),
                       key=lambda ln: supply_sort(ln["supply"]))
        rows_y = [(ln["supply"], ln, False) for ln in lines] + _ramp_rows(result, key)
        confs = [c for c in result.get("confirmations", []) if _key(c) == key]
        if rows_y:
            panels.append((_title(key), rows_y, confs))
    if not panels:
        return False
    _figure(panels, "oil supply (layer on disc and ball)", path)
    return True


def speed_temperature_figure(result: dict, path: Path) -> bool:
    """State over (speed, temperature), one panel per supply/load/resolution."""
    keys = sorted({(ln["supply"], ln["contact.load"], _rung(ln)) for ln in result["lines"]},
                  key=lambda k: (supply_sort(k[0]), k[1], k[2]))
    panels = []
    for supply, F, res in keys:
        lines = sorted((ln for ln in result["lines"]
                        if (ln["supply"], ln["contact.load"], _rung(ln)) == (supply, F, res)),
                       key=lambda ln: ln["contact.temperature"])
        panels.append((f"supply {supply}, {_F.symbol} = {F:g} {_F.unit}, {_rung_text(res)}",
                       [(f"{ln['contact.temperature']:g} {_T.unit}", ln, False)
                        for ln in lines]))
    if not panels:
        return False
    _figure(panels, "temperature", path)
    return True


def _hysteresis_panel(ax, rp: dict) -> None:
    level = {"I": 0.0, "II": 1.0, "failed": 0.5, "pending": 0.5}
    seen: set = set()
    for direction, dy, colour in (("up", 0.04, "tab:purple"), ("down", -0.04, "tab:green")):
        b = _directed(rp[direction], direction)
        us = [_u(v) for v in b[SPEED]]
        ys = [level[s] + dy for s in b["states"]]
        ax.plot(us, ys, "-", color=colour, lw=1.2, alpha=0.7, label=f"ramp {direction}")
        for (u0, y0), (u1, y1) in zip(zip(us, ys), zip(us[1:], ys[1:])):
            ax.annotate("", xy=(u1, y1), xytext=(u0, y0),
                        arrowprops=dict(arrowstyle="->", color=colour, lw=1.4,
                                        shrinkA=5, shrinkB=5))
        for u, s, y in zip(us, b["states"], ys):
            st = dict(_STYLE[s])
            lab = st.pop("label")
            ax.plot([u], [y], linestyle="none", markersize=8,
                    label=None if s in seen else lab, **st)
            seen.add(s)
        bracket = rp[direction]["bracket_m_s"]
        if bracket:
            ax.axvspan(*(_u(v) for v in bracket), color=colour, alpha=0.12)
    h = rp["hysteresis"]
    width = (f"width {_u(h['width_m_s']):.3g} +- {_u(h['uncertainty_m_s']):.2g} {_U.unit}"
             if h["width_m_s"] is not None else "width not determined")
    ax.set_title(f"ramp {rp['name']}: {rp['supply']}, {_conditions(rp)}; hysteresis "
                 f"{'observed' if h['observed'] else 'not observed'}, {width}", fontsize=10)
    ax.set_yticks([0, 1], ["state I", "state II"])
    ax.set_ylim(-0.4, 1.4)
    ax.set_xlabel(_AXIS)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="center left")


def hysteresis_figure(result: dict, path: Path) -> bool:
    """Per ramp: state against speed, up branch and down branch with arrows."""
    ramps = [rp for rp in result["ramps"] if rp.get("hysteresis")]
    if not ramps:
        return False
    plt = _pyplot()
    fig, axes = plt.subplots(len(ramps), 1, figsize=(8.5, 3.2 * len(ramps)), squeeze=False)
    for ax, rp in zip(axes[:, 0], ramps):
        _hysteresis_panel(ax, rp)
    _save(fig, path)
    return True


#: The regime pictures: file name -> what draws it.
FIGURES = {"regime_speed_supply.png": speed_supply_figure,
           "regime_speed_temperature.png": speed_temperature_figure,
           "regime_hysteresis.png": hysteresis_figure}


def write_figures(result: dict[str, Any], out: Path) -> list[Path]:
    """The regime pictures with something to draw, written into the folder ``out``
    (created if needed)."""
    out.mkdir(parents=True, exist_ok=True)
    return [out / name for name, draw in FIGURES.items() if draw(result, out / name)]

