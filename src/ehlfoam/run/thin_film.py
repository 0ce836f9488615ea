"""Run a thin-film case (``scene = "thin-film"``, :mod:`ehlfoam.case.thin_film`) to its
balance and write ``DIR/metrics.json``: the gap-averaged model (:mod:`ehlfoam.thinfilm`)
marched in this process, no OpenFOAM.

The run is watched as the 3D runs are (:mod:`ehlfoam.run.monitor`): at each write
(``run.writes_per_transit`` a transit) it samples the flow pattern with the 3D cases'
topology code, keeps ``DIR/history.csv`` (the same columns) and ``DIR/log.thin-film`` (a line
a transit), and stops when the 3D runs' steady-state test passes over
``thin_film.steady_window`` transits while the mean outflow over them meets the supply within
``run.steady_tolerance`` (:func:`~ehlfoam.run.thin_film_record.thin_film_steady`). It ends
with ``DIR/state.npz`` (the model's state: it starts a 3D case, ``ehlfoam case SPEC
--start-from DIR/state.npz``, another thin-film case, or this one again) and the metrics
record. End reasons, as the 3D runs': ``steady``, ``end_time`` (``run.end_time`` or
``run.transits_max`` transits), ``wall_limit``, ``diverged`` (the march failed: the
traceback in the log, no state written) and ``interrupted`` (Ctrl-C or SIGTERM; the state
is written).

A case that ran before goes on from its ``state.npz`` (its earlier samples count for the
steady-state test); ``extend_transits`` marches that many transits past it whatever the
test says. The oil balance covers this run: from the state it started from to the end,
exact (the model conserves the oil to round-off).
"""

from __future__ import annotations

import math
import signal
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ehlfoam._io import atomic_write_json
from ehlfoam.case.bounds import check_extension
from ehlfoam.case.geometry import META, CaseGeometry, load_geometry, load_spec_of
from ehlfoam.case.ownership import hold_run_lock
from ehlfoam.case.thin_film import START
from ehlfoam.gap.field import GapField
from ehlfoam.metrics.record import MetricsRecord, read_metrics, write_metrics
from ehlfoam.run.fields import Sample
from ehlfoam.run.history import write_history
from ehlfoam.run.thin_film_record import (Accounts, earlier_samples, sample, thin_film_record,
                                          thin_film_steady)
from ehlfoam.run.warnings import enclosure_warnings
from ehlfoam.spec.case import CaseSpec
from ehlfoam.spec.stop import wall_speed_at
from ehlfoam.thinfilm.from_spec import problem_from_spec, scene_options
from ehlfoam.thinfilm.march import Marcher
from ehlfoam.thinfilm.solution import ThinFilmSolution
from ehlfoam.thinfilm.state import load_state, save_state

__all__ = ["FRAMES_DIR", "MARCH_ERRORS", "STATE_FILE", "advance", "open_march",
           "run_thin_film_case", "sigterm_interrupts", "signals_held", "start_of",
           "swapped_handlers"]

#: the state a thin-film run ends with, in the case folder
STATE_FILE = "state.npz"
#: the gas balance's budget a run with thin_film.bubble_gas = "balance" ends with
GAS_FILE = "gas.json"
#: the folder of a stopping run's frames (``stop.frame_interval``), a state each
FRAMES_DIR = "frames"
#: lines of the log a failed run's record keeps
LOG_TAIL_LINES = 20
#: end_reason of an earlier run whose process was killed (run.monitor's MONITOR_KILLED)
MONITOR_KILLED = "monitor_killed"

OnSample = Callable[[Sample, CaseGeometry], None]


def run_thin_film_case(case: str | Path, *, wall_limit: float | None = None,
                       on_sample: OnSample | None = None,
                       extend_transits: float | None = None,
                       crashed: Callable[[Path], MetricsRecord | None] | None = None,
                       on_note: Callable[[str], None] | None = None) -> MetricsRecord:
    """March the thin-film case in ``case`` to its balance (or a limit) and write its
    metrics.json, history.csv, state.npz and log. ``wall_limit`` [s]: by default the
    spec's ``run.wall_limit``; ``extend_transits``: march that many transits past the state
    the case has, whatever the steady-state test says. The case's run lock
    (:func:`ehlfoam.case.ownership.hold_run_lock`) is held throughout: another process
    running it raises :class:`~ehlfoam.case.ownership.CaseBusy`. ``crashed``: called with
    the case under the lock, the record of an earlier run that was killed (a ``running``
    metrics.json), which ``on_note`` is told of. An extension beyond ``run.max_steps`` is
    refused first (:class:`~ehlfoam.errors.SpecError`). Returns the record written."""
    if extend_transits is not None and not extend_transits > 0:
        raise ValueError(f"extend_transits = {extend_transits!r} transits: it must be > 0")
    path = Path(case).absolute()
    spec, geom = load_spec_of(path), load_geometry(path)
    if extend_transits is not None:   # within run.max_steps, before anything is written
        check_extension(spec, extend_transits, geom.transit_time, geom.max_delta_t)
    with hold_run_lock(path):
        if crashed is not None and crashed(path) is not None and on_note:
            on_note(f"the earlier run of {path} was killed before it ended (metrics.json "
                    f"said running, its run lock was free): marked interrupted "
                    f"({MONITOR_KILLED}); this run goes on from its state")
        return _run_locked(path, spec, geom, wall_limit or spec.run.wall_limit, on_sample,
                           extend_transits)


def start_of(path: Path) -> tuple[ThinFilmSolution | None, float, list[Sample], float | None]:
    """Where the run starts: (the state, its time [s], the samples before it, the oil at
    t = 0 [m3, whole contact] when an earlier run knew it). An earlier run's state.npz, else
    the state the case was written to start from, else the spec's puddle (None)."""
    if (path / STATE_FILE).is_file():
        sol = load_state(path / STATE_FILE)
        try:
            initial = read_metrics(path).get("oil_volume_initial_m3")
        except (OSError, ValueError):
            initial = None
        return sol, sol.time, [s for s in earlier_samples(path) if s.time <= sol.time], initial
    if (path / META / START).is_file():
        return load_state(path / META / START), 0.0, [], None
    return None, 0.0, [], None


def open_march(path: Path, spec: CaseSpec, geom: CaseGeometry
               ) -> tuple[Marcher, float, list[Sample], float | None]:
    """The case's march from where it starts (:func:`start_of`, read before metrics.json
    says running, which it then does): the marcher, the start's time [s], the samples before
    it and the oil at t = 0 [m3] when known."""
    start, t0, history, initial = start_of(path)
    write_metrics(path, MetricsRecord(status="running", cells=geom.cells))
    prob = problem_from_spec(spec, GapField.load(path / "precalc"), scene_options(spec))
    stop = spec.stop
    m = Marcher(prob, start=start, courant=spec.thin_film.courant,
                transit_length=spec.run.transit_length * spec.a,
                speed_at=None if stop.at is None else
                (lambda t: wall_speed_at(stop, spec.speed, t0 + t)))
    return m, t0, history, initial


class _Frames:
    """A stopping run's frames: its state every ``stop.frame_interval`` of run time from
    ``stop.frames_from`` before the stop on, as ``DIR/frames/NNNN.npz``
    (:func:`~ehlfoam.thinfilm.state.save_state`; the report's GIF). None of them without a
    stop."""

    def __init__(self, path: Path, spec: CaseSpec, t0: float):
        stop = spec.stop
        self.folder, self.t0 = path / FRAMES_DIR, t0
        self.on = stop.at is not None
        if not self.on:
            return
        self.every = stop.frame_interval
        first = max(0.0, stop.at - stop.frames_from)
        self.k = max(0, math.ceil((t0 - first) / self.every - 1e-9))
        self.first = first
        self.folder.mkdir(exist_ok=True)

    def after_step(self, m: Marcher) -> None:
        """Write a frame when the march reached the next frame's time."""
        if self.on and self.t0 + m.time >= self.first + self.k * self.every - 1e-12:
            save_state(m.solution(), self.folder / f"{self.k:04d}.npz")
            self.k += 1


def _run_locked(path: Path, spec: CaseSpec, geom: CaseGeometry, wall_limit: float,
                on_sample: OnSample | None, extend: float | None) -> MetricsRecord:
    m, t0, history, initial = open_march(path, spec, geom)
    end_time = t0 + extend * geom.transit_time if extend else spec.end_time
    n_steps = max(0, math.ceil((end_time - t0) / m.dt - 1e-6))
    write_every = max(1, round(m.steps_per_transit / spec.run.writes_per_transit))
    window = spec.thin_film.steady_window * geom.transit_time
    log = _Log(path / geom.log_name, spec, geom, m, t0)
    frames = _Frames(path, spec, t0)
    frames.after_step(m)      # the start, when it is a frame's time
    stopping = spec.stop.at is not None   # runs to its end: no steady-state test
    first = before = Accounts.of(m, t0)
    oil_start = m.oil()
    reason, kind, failure = None, None, None
    enclosure: list = []
    t_wall = time.monotonic()
    try:
        with sigterm_interrupts():
            while m.steps < n_steps:
                try:
                    advance(m)
                except MARCH_ERRORS as err:
                    failure = err
                    break
                frames.after_step(m)
                if m.steps % write_every == 0 or m.steps == n_steps:
                    s, before = sample(m, t0, geom, before)
                    history.append(s)
                    if on_sample:
                        on_sample(s, geom)
                    kind = None if extend or stopping else thin_film_steady(
                        history, window, spec.run.steady_tolerance, spec.run.transit_length)
                    if kind and not m.gas_settled(spec.run.steady_tolerance,
                                                  spec.thin_film.steady_window):
                        kind = None       # the bubble's gas still filling or emptying
                if m.steps % m.steps_per_transit == 0:
                    log.transit(m, t0, history[-1] if history else None)
                    write_history(path, history)
                if kind:
                    reason = "steady"
                    break
                if time.monotonic() - t_wall > wall_limit:
                    reason = "wall_limit"
                    break
    except KeyboardInterrupt:
        reason = "interrupted"
    wall = time.monotonic() - t_wall
    if failure is not None:
        reason, tail = "diverged", log.failure(failure)
    else:
        reason, tail = reason or "end_time", None
        if not history or history[-1].time < t0 + m.time * (1 - 1e-9):
            s, before = sample(m, t0, geom, before)
            history.append(s)
        final = m.solution(reason == "steady")
        save_state(final, path / STATE_FILE)
        enclosure = enclosure_warnings(history[-1].pattern, final.cavity)
    write_history(path, history)
    if m.gas is not None:
        _write_gas(path, m)
    log.end(reason, wall)
    status = {"diverged": "failed", "interrupted": "interrupted"}.get(reason, "finished")
    record = thin_film_record(
        geom, history, status=status, reason=reason, steady_kind=kind, start=first,
        end=Accounts.of(m, t0), oil_start=oil_start, oil_end=m.oil(),
        oil_initial=initial if initial is not None else 2.0 * oil_start, steps=m.steps,
        dt=m.dt, wall_s=wall, log_tail=tail, notices=enclosure)
    if failure is not None:   # the one line a failed run's record gives (as the 3D runs')
        record = record.updated(reason="the march failed: " + " ".join(
            f"{type(failure).__name__}: {failure}".split())[:500])
    write_metrics(path, record)
    return record


def _write_gas(path: Path, m: Marcher) -> None:
    """``DIR/gas.json``: the gas balance's budget over the march [mol, whole contact], what
    the cavities hold at the end, the budget's residual, and each transit's gas pressure of
    the largest cavity [Pa, absolute], the held air and the budget so far [mol, whole
    contact]. A run that goes on from its state takes its cavities' air from it; its budget
    covers this run (``held_at_start_mol``)."""
    g = m.gas
    rows = [(r["time_s"], r["gas_pressure_Pa"] if math.isfinite(r["gas_pressure_Pa"])
             else None, 2.0 * r["gas_held_mol"]) for r in m.history]
    atomic_write_json(path / GAS_FILE, {
        "constants": {"solubility_ostwald": g.k.solubility,
                      "diffusivity_m2_s": g.k.diffusivity, "temperature_K": g.k.temperature,
                      "saturation_pressure_Pa": g.k.ambient,
                      "release_pressure_Pa": g.k.release},
        "budget_mol": {k: 2.0 * v for k, v in g.budget.items()},
        "held_mol": 2.0 * g.held(), "held_at_start_mol": 2.0 * g.start,
        "residual_mol": 2.0 * g.budget_residual(),
        "largest_cavity": {k: (2.0 * v if k != "pressure_Pa" else v)
                           for k, v in g.last.items()},
        "per_transit": {"time_s": [r[0] for r in rows], "pressure_Pa": [r[1] for r in rows],
                        "held_mol": [r[2] for r in rows],
                        **{k: [2.0 * r[k] for r in m.history] for k in g.budget}}})


#: what a failing march raises (the run ends ``diverged``)
MARCH_ERRORS = (ArithmeticError, RuntimeError, ValueError, np.linalg.LinAlgError)


def advance(m: Marcher, steps: int = 1) -> None:
    """``steps`` steps of the march ``m``; FloatingPointError if its oil content is then no
    longer finite (with :data:`MARCH_ERRORS`, what a failing march raises)."""
    for _ in range(steps):
        m.step()
        if _CAUGHT:
            raise KeyboardInterrupt
    if not np.isfinite(m.c).all():
        raise FloatingPointError("the oil content is no longer finite")


@contextmanager
def swapped_handlers(signals: tuple[int, ...], handler: Callable) -> Iterator[bool]:
    """Within the block ``handler`` handles ``signals``; the handlers before are put back
    after it. Yields whether they were swapped: not where handlers cannot be set (not the
    main thread), and then nothing changes."""
    try:
        old = {sig: signal.signal(sig, handler) for sig in signals}
    except ValueError:
        yield False
        return
    try:
        yield True
    finally:
        for sig, previous in old.items():
            signal.signal(sig, previous)


#: SIGTERM / SIGINT caught within :func:`sigterm_interrupts`, not yet acted on
_CAUGHT: list[int] = []


@contextmanager
def signals_held(noted: list[int] | None = None) -> Iterator[None]:
    """Within the block SIGTERM and SIGINT are noted in ``noted`` (a list of their numbers),
    not raised; at its end a noted one interrupts (KeyboardInterrupt), unless the block
    raised. Their Python handlers are swapped for the block, not the signals masked: a mask
    holds them in this thread only, and the numba and FFT threads can take them; nothing
    changes where handlers cannot be set (not the main thread)."""
    noted = [] if noted is None else noted

    def note(signum: int, frame: object) -> None:
        noted.append(signum)
    with swapped_handlers((signal.SIGTERM, signal.SIGINT), note):
        try:
            yield
        finally:
            caught = bool(noted)
            noted.clear()
    if caught:
        raise KeyboardInterrupt


@contextmanager
def sigterm_interrupts() -> Iterator[None]:
    """Within the block SIGTERM and SIGINT interrupt the march between two steps:
    :func:`advance` raises KeyboardInterrupt after the step it was in (the run ends
    ``interrupted``, its state written whole), or the block's end does when no step came
    after (:func:`signals_held`). Raised the moment the signal came, the interrupt could
    land inside a step, or in a numba kernel's return, where it became a SystemError (an
    internal error)."""
    _CAUGHT.clear()
    with signals_held(_CAUGHT):
        yield


class _Log:
    """``log.thin-film``: what was marched (a header), a line a transit, how it ended. An
    earlier run's log is kept, renamed with its time."""

    def __init__(self, path: Path, spec: CaseSpec, geom: CaseGeometry, m: Marcher,
                 t0: float):
        if path.exists():
            path.rename(path.with_name(f"{path.name}.{int(time.time())}"))
        self.path, self.transit_s = path, geom.transit_time
        p_cav = m.prob.cavitation_pressure
        self._write(f"ehlfoam thin-film run of {spec.name}: {len(m.grid.x)} x "
                    f"{len(m.grid.y)} cells of {m.grid.cell / geom.a:g} a ({geom.cells} outside "
                    f"the island), step {m.dt:.4g} s ({m.steps_per_transit} a transit), "
                    f"cavitation pressure {'none' if p_cav is None else f'{p_cav:g} Pa gauge'}, "
                    f"from t = {t0:.6g} s")

    def _write(self, line: str) -> None:
        with open(self.path, "a") as fh:
            fh.write(line + "\n")

    def transit(self, m: Marcher, t0: float, s: Sample | None) -> None:
        rec = m.history[-1]
        p = s.pattern if s else {}

        def fmt(v):
            return "-" if v is None else f"{v:.2f}"
        self._write(f"transit {(t0 + m.time) / self.transit_s:7.2f}: t = {t0 + m.time:.6g} s, "
                    f"oil {2e12 * rec['oil_m3']:.2f} nl in the region, out / in "
                    f"{rec['outflow_over_supply']:.3f}, state {p.get('state')}, inlet "
                    f"{fmt(p.get('inlet_meniscus_distance_over_a'))} a, width "
                    f"{fmt(p.get('flooded_width_over_a'))} a, bubble "
                    f"{fmt(p.get('bubble_length_over_a'))} a, {rec['cavity_cells']} cavity "
                    f"cells, {rec['cells_opened_to_gas']} opened to gas, "
                    f"{rec['cells_opened_dry']} ran dry, walls at {m.speed * 1e3:.4g} mm/s"
                    + (f", gas {rec['gas_pressure_Pa'] / 1e3:.2f} kPa, "
                       f"{2.0 * rec['gas_held_mol']:.3g} mol" if "gas_held_mol" in rec else ""))

    def failure(self, err: BaseException) -> list[str]:
        """Log the traceback; the log's last lines."""
        self._write("".join(traceback.format_exception(err)).rstrip())
        return self.path.read_text(errors="replace").splitlines()[-LOG_TAIL_LINES:]

    def end(self, reason: str, wall: float) -> None:
        self._write(f"end: {reason} after {wall:.1f} s")
