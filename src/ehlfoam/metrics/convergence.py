"""Mesh convergence of a case's flow pattern over three meshes: the observed order, the
Richardson extrapolation and the grid convergence index (GCI) of Celik et al. 2008
(J. Fluids Eng. 130, 078001, the journal's procedure for discretisation uncertainty).

With h1 < h2 < h3 (index 1 the finest) and the changes e21 = f2 - f1, e32 = f3 - f2, R = e21 /
e32 says how a metric behaves: 0 < R < 1 monotone convergence (the changes shrink), -1 < R < 0
oscillatory convergence, |R| >= 1 divergence (no extrapolation, no index). For a converging
metric the order p solves p ln r21 = |ln|e32 / e21| + ln((r21^p - s) / (r32^p - s))| (s =
sign(e32 / e21)), the extrapolated value is (r21^p f1 - f2) / (r21^p - 1) and the fine mesh's
index GCI = 1.25 |e21 / f1| / (r21^p - 1). Two readings guard it: changes no bigger than the
metric's own jitter (twice the standard deviation of its last writes) say nothing ("within
noise"), and an order outside :data:`ASYMPTOTIC_ORDER` says the meshes are not in the
asymptotic range, where neither the extrapolation nor the index holds.

Used by the batch report (a batch that sweeps ``resolution``). :func:`rest_value` reads the
value a metric comes to rest at on one mesh from runs that have not got there yet, for meshes
too dear to run to rest.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ehlfoam.case.geometry import load_geometry, load_spec_of

#: The flow-pattern metrics read over the meshes (metrics.json / history.csv keys).
METRICS = ("inlet_meniscus_distance_over_a", "flooded_width_over_a", "flooded_length_over_a",
           "oil_volume_m3")
SAFETY = 1.25   # Celik et al.'s factor of safety for three meshes
#: Observed orders outside this range say the meshes are not in the asymptotic range (the
#: schemes are of order 1-2): the extrapolation and the index are then not to be trusted.
ASYMPTOTIC_ORDER = (0.5, 3.0)


def observed_order(h: tuple[float, float, float], f: tuple[float, float, float],
                   noise: float = 0.0, tol: float = 1e-10, max_iter: int = 200) -> dict:
    """Observed order, Richardson extrapolation and grid convergence index of a metric ``f``
    on three meshes of representative cell sizes ``h`` (any order, any one unit).

    Returns ``behaviour`` ("monotone", "oscillatory", "divergent", "unchanged", or "within
    noise" where both changes are at most ``noise``, the metric's own jitter in the units of
    ``f``: then the changes say nothing about the order) and ``R = e21 / e32``; for a
    converging metric also ``order`` p, ``extrapolated`` (the Richardson value),
    ``gci_fine`` (the fine mesh's relative uncertainty band, with safety factor 1.25),
    ``error_fine`` (|f1 - f_ext| / |f_ext|) and ``asymptotic`` (p within
    :data:`ASYMPTOTIC_ORDER`: otherwise neither the extrapolation nor the index holds).
    Index 1 is the finest. Raises ValueError unless the sizes are three different positive
    values.
    """
    (h1, f1), (h2, f2), (h3, f3) = sorted(zip(h, f))
    if not (0 < h1 < h2 < h3):
        raise ValueError(f"sizes: need three different positive cell sizes, got {h}")
    r21, r32 = h2 / h1, h3 / h2
    e21, e32 = f2 - f1, f3 - f2
    out: dict = {"sizes": [h1, h2, h3], "values": [f1, f2, f3], "r21": r21, "r32": r32}
    if max(abs(e21), abs(e32)) <= noise:
        return out | {"behaviour": "within noise", "R": e21 / e32 if e32 else None,
                      "spread": max(f) - min(f)}
    if e21 == 0.0 and e32 == 0.0:
        return out | {"behaviour": "unchanged", "R": None, "order": None,
                      "extrapolated": f1, "gci_fine": 0.0, "error_fine": 0.0}
    if e32 == 0.0:
        return out | {"behaviour": "divergent", "R": None}
    R = e21 / e32
    out["R"] = R
    if abs(R) >= 1.0:
        return out | {"behaviour": "divergent"}
    if e21 == 0.0:   # converged on the two finest: no order to read
        return out | {"behaviour": "monotone", "order": None, "extrapolated": f1,
                      "gci_fine": 0.0, "error_fine": 0.0}
    s = math.copysign(1.0, e32 / e21)
    p = abs(math.log(abs(e32 / e21))) / math.log(r21)
    for _ in range(max_iter):
        q = math.log((r21 ** p - s) / (r32 ** p - s))
        p_new = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
        if abs(p_new - p) < tol:
            p = p_new
            break
        p = p_new
    ext = (r21 ** p * f1 - f2) / (r21 ** p - 1.0)
    lo, hi = ASYMPTOTIC_ORDER
    return out | {"behaviour": "monotone" if R > 0 else "oscillatory", "order": p,
                  "asymptotic": lo <= p <= hi, "extrapolated": ext,
                  "gci_fine": SAFETY * abs(e21 / f1) / (r21 ** p - 1.0),
                  "error_fine": abs((f1 - ext) / ext) if ext else None}


def history_number(value: str | None) -> float | None:
    """A history.csv cell as a number, None where the metric was undefined ("", "None")."""
    return None if value in (None, "", "None") else float(value)


def jitter(rows: list[dict], keys: tuple[str, ...] = METRICS) -> dict[str, float]:
    """Per metric (``keys``: history.csv columns), the standard deviation over history.csv
    ``rows`` (0 for fewer than two values)."""
    out = {}
    for k in keys:
        vals = np.array([v for r in rows if (v := history_number(r.get(k))) is not None])
        out[k] = float(vals.std()) if vals.size > 1 else 0.0
    return out


def read_history_rows(case: Path) -> list[dict]:
    """The case's history.csv as dicts of strings (empty without one)."""
    path = Path(case) / "history.csv"
    if not path.is_file():
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def window_mean(case: Path, t_end: float | None = None, span: float = 1.0,
                keys: tuple[str, ...] = METRICS) -> dict | None:
    """Each metric's mean (``keys``: history.csv columns) over the writes of history.csv
    within ``span`` transits up to ``t_end`` [s] (default: the last write; one write alone
    carries the meniscus's cell-to-cell jitter and, on a resolved inlet, the drops that merge
    into it), that jitter, the time [s] and state of the window's last write, the states the
    window saw (sorted) and the writes averaged; None without a history or without a write in
    the window."""
    rows = read_history_rows(case)
    if t_end is not None:
        rows = [r for r in rows if float(r["time_s"]) <= t_end * (1 + 1e-9)]
    if not rows:
        return None
    t_last = float(rows[-1]["time_s"])
    last = [r for r in rows
            if float(r["time_s"]) >= t_last - span * load_geometry(case).transit_time]
    means = {}
    for k in keys:
        vals = [v for r in last if (v := history_number(r.get(k))) is not None]
        means[k] = sum(vals) / len(vals) if vals else None
    return means | {"time_s": t_last, "state": rows[-1]["state"],
                    "states": sorted({r["state"] for r in last}), "writes_averaged": len(last),
                    "jitter": jitter(last, keys)}


def last_transit(case: Path) -> dict | None:
    """The case's last state: :func:`window_mean` over the last transit of its history."""
    return window_mean(case)


def level_size(case: Path) -> float:
    """The in-plane cell size far from the contact (units of a) a case's mesh was built with:
    the level's ``size_far`` with the spec's overrides, where the menisci sit. The levels
    scale every size by the same ratio, so it stands for the whole mesh."""
    return float(load_spec_of(case).mesh.level()["size_far"])


def over_cases(cases: list[Path], sizes: list[float] | None = None) -> dict:
    """observed_order of every metric over three cases at their last transit; ``sizes``
    default to :func:`level_size`. The noise is twice the largest jitter of the three."""
    if len(cases) != 3:
        raise ValueError(f"cases: need three, got {len(cases)}")
    states = [last_transit(c) for c in cases]
    if any(s is None for s in states):
        raise ValueError("cases: each needs a history.csv")
    sizes = list(sizes) if sizes is not None else [level_size(c) for c in cases]
    out = {}
    for k in METRICS:
        vals = [s[k] for s in states]
        if None in vals:
            continue
        noise = 2 * max(s["jitter"][k] for s in states)
        out[k] = observed_order(tuple(sizes), tuple(vals), noise=noise)
    return out


def _relaxation_fit(runs: list[tuple[np.ndarray, np.ndarray]]) -> dict:
    """Least-squares fit of f_i(t) = rest + (f_i0 - rest) exp(-(t - t_i0) / tau) to the runs:
    one rest value and one relaxation time tau [transits] for all, each run its own start
    value f_i0. Returns {"rest", "rest_sd", "tau", "tau_sd", "rms"}."""
    from scipy.optimize import least_squares

    def residual(x: np.ndarray) -> np.ndarray:
        rest, tau = x[0], x[1]
        return np.concatenate([rest + (f0 - rest) * np.exp(-(t - t[0]) / tau) - f
                               for (t, f), f0 in zip(runs, x[2:])])

    n = sum(len(t) for t, _ in runs)
    span = max(t[-1] - t[0] for t, _ in runs)
    x0 = np.array([np.mean([f[-1] for _, f in runs]), max(span, 1e-6)] +
                  [f[0] for _, f in runs])
    lower = np.r_[-np.inf, 1e-3 * x0[1], np.full(len(runs), -np.inf)]
    fit = least_squares(residual, x0, bounds=(lower, np.inf))
    dof = max(n - len(x0), 1)
    try:
        cov = np.linalg.inv(fit.jac.T @ fit.jac) * np.sum(fit.fun ** 2) / dof
        sd = np.sqrt(np.abs(np.diag(cov)))
    except np.linalg.LinAlgError:
        sd = np.full(len(x0), np.inf)
    return {"rest": float(fit.x[0]), "rest_sd": float(sd[0]), "tau": float(fit.x[1]),
            "tau_sd": float(sd[1]), "rms": float(np.sqrt(np.sum(fit.fun ** 2) / n))}


def fixes_a_rest(fit: dict, span: float) -> bool:
    """True when a relaxation fit (:func:`rest_value`'s "rest", "rest_sd", "tau", "tau_sd")
    of runs spanning ``span`` transits fixes its rest: its relaxation time comes out to better
    than half of itself and the runs span at least half of it. A run still on a straight
    line, whose curve gives no rest, does not."""
    return bool(math.isfinite(fit["rest_sd"]) and fit["tau_sd"] < 0.5 * fit["tau"]
                and fit["tau"] <= 2 * span)


def rest_value(runs: list[tuple[np.ndarray, np.ndarray]], rate_window: float = 0.036) -> dict:
    """The value a metric comes to rest at on one mesh, read off runs that approach it (say one
    from above and one from below) before any of them gets there.

    Each run is a pair (times [transits], values). Fitted jointly by least squares: f_i(t) =
    f_rest + (f_i0 - f_rest) exp(-(t - t_i0) / tau), one rest value f_rest and one relaxation
    time tau [transits] for all runs, each run its own start value f_i0 (t_i0 its first
    time). The model-free reading beside it: a run that ends rising and one that ends
    falling bracket the rest value between their last values, if neither overshoots it.
    Where there is more than one run, each run with at least four writes is also fitted
    alone. A run fixes a rest of its own ("fixed") when its relaxation time comes out to
    better than half of itself and the run spans at least half of it: a run that is still
    on a straight line, whose curve gives no rest, does not. The joint fit is
    ``consistent`` when the own rests of the runs that fix one agree within twice their
    combined standard deviation (and a relative 1e-6, the fit's own precision): one
    relaxation describes them all. With fewer than two such runs that is not known (None),
    and the joint rest stands on the model alone.

    Returns {"rest", "rest_sd", "tau", "tau_sd", "rms" (the fit's residual), "bracket" ([low,
    high] or None), "consistent" (bool, or None with fewer than two runs that fix a rest of
    their own), "runs": [{"first", "last", "t_first", "t_last", "rate" (the slope over the
    last ``rate_window`` transits, per transit), "writes", "alone" (that run's own fit with
    "fixed", or None)}]}. Raises ValueError when the runs hold fewer writes than the model
    has unknowns plus one.
    """
    runs = [(np.asarray(t, dtype=float), np.asarray(f, dtype=float)) for t, f in runs]
    n = sum(len(t) for t, _ in runs)
    if not runs or n < len(runs) + 3 or any(len(t) < 2 for t, _ in runs):
        raise ValueError(f"runs: need at least two writes a run and {len(runs) + 3} in all, "
                         f"got {[len(t) for t, _ in runs]}")
    summary = []
    for t, f in runs:
        last = t >= t[-1] - rate_window * (1 + 1e-9)
        rate = float(np.polyfit(t[last], f[last], 1)[0]) if last.sum() > 1 else 0.0
        alone = None
        if len(runs) > 1 and len(t) >= 4:
            alone = _relaxation_fit([(t, f)])
            alone["fixed"] = fixes_a_rest(alone, t[-1] - t[0])
        summary.append({"first": float(f[0]), "last": float(f[-1]), "t_first": float(t[0]),
                        "t_last": float(t[-1]), "rate": rate, "writes": int(len(t)),
                        "alone": alone})
    joint = _relaxation_fit(runs)
    rising = [s["last"] for s in summary if s["rate"] > 0]
    falling = [s["last"] for s in summary if s["rate"] < 0]
    bracket = ([max(rising), min(falling)] if rising and falling and max(rising) <= min(falling)
               else None)
    alone = [s["alone"] for s in summary if s["alone"] is not None and s["alone"]["fixed"]]
    consistent = None
    if len(alone) > 1:
        consistent = all(abs(a["rest"] - b["rest"]) <=
                         2 * math.hypot(a["rest_sd"], b["rest_sd"]) + 1e-6 * abs(a["rest"])
                         for k, a in enumerate(alone) for b in alone[k + 1:])
    return {**joint, "bracket": bracket, "consistent": consistent, "runs": summary}
