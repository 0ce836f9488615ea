"""The cycle of passes of a thin-film case whose supply is the oil on the rig
(``supply.mode = "rig"``): the supply as an outcome.

Nobody sets the supply: the inlet of pass n + 1 takes in what pass n (and, on the disc,
the passes a revolution before) left on the tracks, levelled over a revolution
(:mod:`ehlfoam.tracks`). A pass is a ball revolution (a K-th of the disc's, K = round(r /
R), :mod:`ehlfoam.tracks.rig`); the contact's march goes on from its state through every
pass, its supply the tracks' layers on its rows. The cycle ends:

- ``periodic``: over the last max(K, 2) passes the supply the inlet took in and the oil in
  the contact's domain changed by less than ``cycle.tolerance`` (relative) from one pass to
  the next, the state stayed the same, and the contact laid back what it took in within
  it;
- ``limit_cycle``: not so, but the passes' supply, oil and state repeat with a period of 2
  to ``cycle.period_max`` passes within the tolerance, twice over (3 periods seen);
- ``passes_max`` (``cycle.passes_max``), ``wall_limit`` (``run.wall_limit``), ``diverged``
  (the march failed), ``interrupted`` (Ctrl-C, SIGTERM).

Every pass writes a row of ``DIR/cycle.csv`` (its supply, state, inlet meniscus, the film
it leaves the contact (``hc_over_hc_flooded``, :func:`ehlfoam.gap.starved.starved_film`), bubble,
the oil in the flooded region, the contact's domain and on each track, the rig's oil and
its balance), the contact's ``state.npz`` and the tracks' ``tracks.npz``: a cycle that is
stopped goes on from its last pass when run again, nothing lost (a pass cut short is made
again: its state is not written, so the contact's and the tracks' oil stay in step); one
that ended makes no more passes when run again (its record is written anew).
``metrics.json`` holds the settled flow pattern (the state of most of the last passes,
:func:`settled_pattern`), the cycle's summary (``cycle_*``, ``oil_rig_*`` keys) and the
contact's film at the settled passes' inlet meniscus (``hc_over_hc_flooded``,
:func:`settled_film`). Volumes are the whole contact's and the whole tracks' (twice the
half width marched).
"""

from __future__ import annotations

import csv
import io
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_text
from ehlfoam.case.geometry import META, CaseGeometry, load_geometry, load_spec_of
from ehlfoam.case.ownership import hold_run_lock
from ehlfoam.errors import SpecError
from ehlfoam.gap.starved import MENISCUS_RANGE, starved_film
from ehlfoam.metrics.record import MetricsRecord, write_metrics
from ehlfoam.run.fields import Sample
from ehlfoam.run.history import write_history
from ehlfoam.run.thin_film import (MARCH_ERRORS, STATE_FILE, advance, open_march,
                                   sigterm_interrupts, signals_held)
from ehlfoam.run.thin_film_record import Accounts, sample, thin_film_record
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.cycle import rig_layers
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.thinfilm.state import load_state, save_state
from ehlfoam.tracks.rig import Rig, Tracks, equivalent_band

__all__ = ["CYCLE_FILE", "START_TRACKS", "TRACKS_FILE", "cycle_end", "rig_of", "run_cycle_case",
           "settled_film", "settled_pattern", "settled_supply"]

#: in the case folder: a row a pass, and the tracks' layers after the last pass
CYCLE_FILE, TRACKS_FILE = "cycle.csv", "tracks.npz"
#: the fewest passes the settled state is read over (:func:`settled_pattern`)
WINDOW_MIN = 8
#: in the case's ehlfoam/: the tracks a cycle started from another's begins with
START_TRACKS = "start_tracks.npz"

OnPass = Callable[[dict], None]


def rig_of(spec: CaseSpec, m: Marcher) -> Rig:
    """The rig of a "rig" spec around the march ``m`` (its grid's rows and step)."""
    c, d = spec.cycle, m.grid.cell
    rows = len(m.grid.y)
    side = (c.side if c.side is not None else 3.0 * spec.domain.side) * spec.a
    return Rig(track_radius=spec.supply.track_radius, ball_radius=spec.contact.radius,
               speed=spec.speed, surface_tension=spec.physics.surface_tension,
               viscosity=spec.oil_viscosity, row=d, rows=rows,
               width_rows=max(rows, 3, int(round(side / d))), step=m.dt, refine=c.refine,
               precursor=c.precursor, reflow_steps=c.reflow_steps, centrifugal=c.centrifugal,
               density=spec.oil_density, disc_share=c.disc_share)


def run_cycle_case(case: str | Path, *, wall_limit: float | None = None,
                   on_sample: Callable[[Sample, CaseGeometry], None] | None = None,
                   on_pass: OnPass | None = None,
                   crashed: Callable[[Path], MetricsRecord | None] | None = None,
                   on_note: Callable[[str], None] | None = None,
                   extend_transits: float | None = None) -> MetricsRecord:
    """Run the cycle of the "rig" thin-film case in ``case`` (module docstring) under its
    run lock; ``on_sample`` gets each pass's last sample, ``on_pass`` its row of
    cycle.csv, ``crashed`` and ``on_note`` as :func:`ehlfoam.run.thin_film.
    run_thin_film_case`'s. ``extend_transits`` is refused (:class:`SpecError`): a cycle
    goes on by its passes (raise ``cycle.passes_max`` and run it again). Returns the record
    written."""
    if extend_transits is not None:
        raise SpecError(f"extend_transits = {extend_transits:g} does not apply to a cycle of "
                        "passes (supply.mode = \"rig\"): raise cycle.passes_max and run it "
                        "again, it goes on from its last pass")
    path = Path(case).absolute()
    spec, geom = load_spec_of(path), load_geometry(path)
    with hold_run_lock(path):
        if crashed is not None and crashed(path) is not None and on_note:
            on_note(f"the earlier cycle of {path} was killed before it ended: marked "
                    "interrupted; this run goes on from its last pass")
        return _cycle(path, spec, geom, wall_limit or spec.run.wall_limit, on_sample,
                      on_pass)


def _cycle(path: Path, spec: CaseSpec, geom: CaseGeometry, wall_limit: float,
           on_sample, on_pass) -> MetricsRecord:
    m, t0, history, initial = open_march(path, spec, geom)
    rig = rig_of(spec, m)
    rows = _read_rows(path / CYCLE_FILE)
    if (path / TRACKS_FILE).is_file() and rows:
        tracks = Tracks.load(path / TRACKS_FILE)
        rig_initial = float(rows[0]["oil_rig_initial_m3"])
    else:
        tracks = _start_tracks(path, spec, rig)
        rows, history = [], []
        rig_initial = 2.0 * (sum(tracks.oil(rig)) + m.oil())
    first = before = Accounts.of(m, t0)
    oil_start = m.oil()
    reason, failure, period = None, None, None
    t_wall = time.monotonic()
    if rows:   # an ended cycle run again: no more passes
        reason, period = cycle_end(rows, rig.arcs, spec.cycle.tolerance,
                                   spec.cycle.period_max)
    try:
        with sigterm_interrupts():
            while reason is None and tracks.passes < spec.cycle.passes_max:
                t_pass = time.monotonic()
                inlet = tracks.inlet(rig)
                m.set_supply(inlet)
                m.oil_out_rows[:] = 0.0
                took, side0 = m.oil_in, m.oil_out_side
                try:
                    advance(m, rig.pass_steps)
                except MARCH_ERRORS as err:
                    failure = err
                    break
                took, side = m.oil_in - took, m.oil_out_side - side0
                s, before = sample(m, t0, geom, before)
                film = starved_film(spec.contact, _film_meniscus(s.pattern))
                with signals_held():   # a pass is booked whole: its tracks, row and files
                    history.append(s)
                    arc = tracks.next_arc
                    tracks.lay(rig, m.oil_out_rows, side)
                    row = _row(tracks, rig, m, s, arc, took, float(m.oil_out_rows.sum()) + side,
                               rig_initial, time.monotonic() - t_pass, inlet)
                    row["hc_over_hc_flooded"] = film["hc_over_hc_flooded"]
                    rows.append(row)
                    _save(path, rows, tracks, m)
                    write_history(path, history)
                if on_sample:
                    on_sample(s, geom)
                if on_pass:
                    on_pass(row)
                reason, period = cycle_end(rows, rig.arcs, spec.cycle.tolerance,
                                           spec.cycle.period_max)
                if reason:
                    break
                if time.monotonic() - t_wall > wall_limit:
                    reason = "wall_limit"
                    break
    except KeyboardInterrupt:   # the last pass's state and tracks stay: it goes on from them
        reason = "interrupted"
    wall = time.monotonic() - t_wall
    if failure is not None:
        reason = "diverged"
    reason = reason or "passes_max"
    status = {"diverged": "failed", "interrupted": "interrupted"}.get(reason, "finished")
    if not history:
        s, before = sample(m, t0, geom, before)
        history.append(s)
    record = thin_film_record(
        geom, history, status=status, reason=reason, steady_kind=None, start=first,
        end=Accounts.of(m, t0), oil_start=oil_start, oil_end=m.oil(),
        oil_initial=initial if initial is not None else 2.0 * oil_start, steps=m.steps,
        dt=m.dt, wall_s=wall)
    last = rows[-1] if rows else {}
    disc, ball = tracks.oil(rig)
    rig_now = 2.0 * (disc + ball + m.oil())
    record = record.updated(**settled_pattern(history[-len(rows):] if rows else [], rig.arcs))
    record = record.updated(
        steady=reason == "periodic", cycle_end_reason=reason, cycle_passes=len(rows),
        cycle_period_passes=period, cycle_pass_time_s=rig.pass_time,
        cycle_arcs=rig.arcs, cycle_inlet_supply_m3_s=last.get("inlet_supply_m3_s"),
        oil_disc_track_m3=2.0 * disc, oil_ball_track_m3=2.0 * ball, oil_rig_m3=rig_now,
        oil_rig_initial_m3=rig_initial,
        oil_rig_balance_error=abs(rig_now - rig_initial) / rig_initial)
    if reason not in ("diverged", "interrupted"):
        record = record.updated(**settled_film(spec, rows, rig.arcs))
    if failure is not None:
        record = record.updated(reason="the march failed: " + " ".join(
            f"{type(failure).__name__}: {failure}".split())[:500])
    write_metrics(path, record)
    return record


def settled_pattern(passes: list[Sample], arcs: int) -> dict:
    """The flow pattern a cycle settled in, from its passes' samples (a pass each): the state
    of most of the last max(2 K, 8) passes (the last pass's on a tie) and the pattern of the
    last pass in that state; ``cycle_state_II_share``, the share of those passes in state
    II. Near the transition the state flips from pass to pass (the region's rear pinches
    within a cell); the last pass's state alone would be a draw."""
    window = [s for s in passes[-max(2 * arcs, WINDOW_MIN):] if s.pattern.get("state")]
    if not window:
        return {}
    states = [s.pattern["state"] for s in window]
    share = states.count("II") / len(states)
    state = "II" if share > 0.5 else "I" if share < 0.5 else states[-1]
    pick = next(s for s in reversed(window) if s.pattern["state"] == state)
    return {**pick.pattern, "cycle_state_II_share": share,
            "cycle_state_window_passes": len(window)}


def settled_film(spec: CaseSpec, rows: list[dict], arcs: int) -> dict:
    """The contact's film at the inlet meniscus of the cycle's last max(K, 2) passes (their
    mean; :func:`ehlfoam.gap.starved.starved_film` on the contact's grid: hc / hc,ff on 257^2
    is within 1.2 % of the default grid's at the reference conditions, docs/models/
    supply-cycle.md)."""
    last = [_film_meniscus(r) for r in rows[-max(arcs, 2):]]
    last = [float(d) for d in last if d not in (None, "")]
    return starved_film(spec.contact, float(np.mean(last)) if last else None)


def _film_meniscus(pattern: dict) -> float | str | None:
    """The inlet meniscus distance [a] a pass's starved film is solved at: the pattern's; the
    far end of the starved solves' range where the oil reaches the domain's inlet edge (a
    state, no meniscus: the inlet is flooded); None without a state."""
    d = pattern.get("inlet_meniscus_distance_over_a")
    if d in (None, "") and pattern.get("state") in ("I", "II"):
        return MENISCUS_RANGE[1]
    return d


def settled_supply(case: str | Path) -> dict[str, float]:
    """The supply a cycle's case settled on, as the 3D scenes' "layers" supply (dotted
    case-spec keys, SI): the layers the tracks bring the contact's rows next pass (its state's
    rows), as the uniform band that carries their oil (:func:`ehlfoam.tracks.rig.
    equivalent_band`: a dry middle where the tracks have one). OSError, ValueError where the
    case has not run a pass."""
    case = Path(case)
    tracks, grid = Tracks.load(case / TRACKS_FILE), load_state(case / STATE_FILE).grid
    rows = len(grid.y)
    return equivalent_band(tracks.disc[tracks.next_arc, :rows], tracks.ball[:rows], grid.cell)


def _start_tracks(path: Path, spec: CaseSpec, rig: Rig) -> Tracks:
    """The tracks the cycle starts from: those of the cycle it was started from (a ramp's
    previous step, at another speed: the layers and the arc met next kept, the passes counted
    anew), else the spec's uniform layers. ValueError if the carried tracks do not fit this
    rig (another contact grid or track radius)."""
    carried = path / META / START_TRACKS
    if not carried.is_file():
        return Tracks.uniform(rig, *rig_layers(spec), spec.supply.track_half_width)
    tracks = Tracks.load(carried)
    want = (rig.arcs, rig.width_rows)
    if tracks.disc.shape != want or tracks.ball.shape != want[1:]:
        raise ValueError(f"the tracks this cycle starts from ({carried}) hold "
                         f"{tracks.disc.shape[0]} arcs x {tracks.disc.shape[1]} rows, this "
                         f"rig {want[0]} x {want[1]}: a cycle carries its tracks only to one "
                         "of the same contact grid, track radius and cycle.side")
    tracks.passes = 0
    return tracks


def cycle_end(rows: list[dict], arcs: int, tol: float, period_max: int
              ) -> tuple[str | None, int | None]:
    """How the cycle's passes ``rows`` (cycle.csv's) end: ("periodic", 1), ("limit_cycle",
    period) or (None, None) to go on (module docstring)."""
    def series(key: str) -> np.ndarray:
        return np.array([float(r[key]) for r in rows])

    n = len(rows)
    need = max(arcs, 2)
    if n < need + 1:
        return None, None
    took, oil, laid = series("inlet_m3"), series("oil_domain_m3"), series("laid_m3")
    states = [r["state"] for r in rows]
    scale_t = max(np.abs(took[-need - 1:]).max(), 1e-300)
    scale_o = max(np.abs(oil[-need - 1:]).max(), 1e-300)
    steady = (np.abs(np.diff(took[-need - 1:])).max() <= tol * scale_t
              and np.abs(np.diff(oil[-need - 1:])).max() <= tol * scale_o
              and abs(laid[-1] - took[-1]) <= tol * scale_t
              and len(set(states[-need - 1:])) == 1)
    if steady:
        return "periodic", 1
    for p in range(2, period_max + 1):
        if n < 3 * p:
            break
        a, b = slice(n - 2 * p, n), slice(n - 3 * p, n - p)
        if (np.abs(took[a] - took[b]).max() <= tol * scale_t
                and np.abs(oil[a] - oil[b]).max() <= tol * scale_o
                and states[a] == states[b]):
            return "limit_cycle", p
    return None, None


def _row(tracks: Tracks, rig: Rig, m: Marcher, s: Sample, arc: int, took: float,
         laid: float, rig_initial: float, wall: float, inlet) -> dict:
    """cycle.csv's row of the pass just made (whole contact, whole tracks)."""
    disc, ball = tracks.oil(rig)
    p = s.pattern
    rig_now = 2.0 * (disc + ball + m.oil())
    width = rig.row * float(np.count_nonzero(inlet[0] + inlet[1]))
    return {
        "pass": tracks.passes, "time_s": s.time, "disc_arc": arc,
        "inlet_supply_m3_s": 2.0 * took / rig.pass_time, "inlet_m3": 2.0 * took,
        "inlet_disc_layer_mean_m": float(inlet[0].sum()) * rig.row / width if width else 0.0,
        "inlet_ball_layer_mean_m": float(inlet[1].sum()) * rig.row / width if width else 0.0,
        "laid_m3": 2.0 * laid, "state": p.get("state"),
        "inlet_meniscus_distance_over_a": p.get("inlet_meniscus_distance_over_a"),
        "inlet_meniscus_shape": p.get("inlet_meniscus_shape"),
        "flooded_width_over_a": p.get("flooded_width_over_a"),
        "bubble_length_over_a": p.get("bubble_length_over_a"),
        "wake_open": p.get("wake_open"),
        "oil_region_m3": 2.0 * m.history[-1]["oil_m3"] if m.history else None,
        "oil_domain_m3": 2.0 * m.oil(), "oil_disc_track_m3": 2.0 * disc,
        "oil_ball_track_m3": 2.0 * ball, "oil_rig_m3": rig_now,
        "oil_rig_initial_m3": rig_initial,
        "oil_rig_balance_error": abs(rig_now - rig_initial) / rig_initial,
        "wall_s": wall}


def _save(path: Path, rows: list[dict], tracks: Tracks, m: Marcher) -> None:
    """cycle.csv, the tracks and the contact's state after a pass, each atomically."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    tracks.save(path / TRACKS_FILE)
    save_state(m.solution(), path / STATE_FILE)
    atomic_write_text(path / CYCLE_FILE, buf.getvalue())


def _read_rows(path: Path) -> list[dict]:
    """The rows of an earlier cycle.csv (none without one)."""
    if not path.is_file():
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))
