"""Run a generated case to steady state and write ``DIR/metrics.json``.

interFoam runs as a child process (through :mod:`ehlfoam.foam.runtime`). Function objects fail in
Debian 13's OpenFOAM build, so the monitor watches from outside: it reads every time folder
the solver writes (oil volume, oil fluxes through the open boundaries, the flow pattern on the
mid-gap surface), keeps ``DIR/history.csv``, and stops the solver through controlDict when the
oil volume and the meniscus positions have changed by less than the tolerance over one transit
time. The steady-state test is applied to every write in turn, and a steady run ends at the
next scheduled write time (controlDict's ``endTime`` set to it): its last write, and the
metrics read from it, do not depend on the wall clock. A wall limit or an interrupt stops the
solver at once (``stopAt writeNow``). End reasons:

- ``steady``: a steady-state test passed (``steady_test`` in metrics.json: "last write", the
  last write within the tolerance of the one a transit earlier, or "window mean", the means
  over the last two transits within it: a statistically steady flow), and the oil volume's
  least-squares trend over the last transit is within the tolerance too;
- ``end_time``: the simulated time limit was reached first;
- ``wall_limit``: the wall-clock limit was reached first;
- ``diverged``: the solver failed after its first time step (a floating-point trap, a fatal
  error) or its time step collapsed; the logs stay and metrics.json says ``status: failed``;
- ``crashed``: the solver was killed after its first time step by another signal (a
  segmentation fault, a bus error, an out-of-memory kill): not the numerics; ``reason``
  names the signal, the logs stay, ``status: failed``. Also a solver the watch found hung
  (:data:`~ehlfoam.run.watch.HANG_POLLS`) and killed, its signal named where its log has
  one (a floating-point trap: ``diverged``);
- ``start_failed``: the run failed before its first time step (decomposition, OpenFOAM
  refusing the case's path, a solver that cannot start); ``reason`` has the log's words
  (:mod:`ehlfoam.run.start`);
- ``case_removed``: the case folder was removed (or replaced) while it ran; the solver is
  stopped and nothing is written (there is no folder to write to);
- ``monitor_error``: the monitor itself failed; the solver is stopped, ``reason`` says why;
- ``interrupted``: Ctrl-C or SIGTERM; the solver is stopped with a final write;
- ``monitor_killed`` (status ``interrupted``): found by the next run (or report, or batch): a
  metrics.json left ``running`` by a monitor that was killed (SIGKILL), its run lock free.

The modules doing the work: :mod:`ehlfoam.run.watch` (the solver's run, watched),
:mod:`ehlfoam.run.finish` (what it leaves), :mod:`ehlfoam.run.killed` (a killed run settled).

One run per case: the run holds the case's run lock (``ehlfoam/run.lock``,
:mod:`ehlfoam.case.ownership`) and hands the lock's descriptor to its solver, so the lock stays
held while any process of the run lives; the solver dies with the monitor
(:mod:`ehlfoam.foam.lifetime`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from foamlib import FoamFile

from ehlfoam.case.geometry import CaseGeometry, load_geometry, load_spec_of
from ehlfoam.case.ownership import CaseBusy, hold_run_lock
from ehlfoam.case.thin_film import is_thin_film_case
from ehlfoam.foam.runtime import FoamRuntime
from ehlfoam.metrics.record import MetricsRecord
from ehlfoam.run import fields as case_fields
from ehlfoam.run.balance import (OIL_FLUX_APPROXIMATE, OIL_FLUX_EXACT, dissolved_air_budget,
                                 mass_balance)
from ehlfoam.run.killed import MONITOR_KILLED, crashed_record, settle_held, settle_killed_run
from ehlfoam.run.logtail import LogTail
from ehlfoam.run.steady import steady_test
from ehlfoam.run.thin_film import run_thin_film_case
from ehlfoam.run.warnings import (CLEARANCE_WARNING, FRONT_CELL_WARNING, OFF_OUTLET_WARNING,
                                  REAR_CELL_WARNING, boundary_warnings, front_cell_warnings,
                                  rear_cell_warnings, rear_meniscus_cell)
from ehlfoam.run.watch import OnSample, SolverWatch, WatchedCase

#: run_case; the rest is re-exported from the modules that now hold it (ehlfoam.run.killed,
#: .steady, .balance, .warnings, ehlfoam.case.ownership) for the callers of this module
__all__ = ["CLEARANCE_WARNING", "FRONT_CELL_WARNING", "MONITOR_KILLED", "OFF_OUTLET_WARNING",
           "OIL_FLUX_APPROXIMATE", "OIL_FLUX_EXACT", "REAR_CELL_WARNING", "CaseBusy",
           "LogTail", "boundary_warnings", "crashed_record", "dissolved_air_budget",
           "front_cell_warnings", "mass_balance", "rear_cell_warnings", "rear_meniscus_cell",
           "run_case", "settle_killed_run", "steady_test"]


def run_case(case: str | Path, runtime: FoamRuntime | None = None,
             wall_limit: float | None = None, on_sample: OnSample | None = None,
             extend_transits: float | None = None,
             on_note: Callable[[str], None] | None = None,
             oversubscribe: bool = False) -> MetricsRecord:
    """Run the case in ``case`` to steady state (or a limit) and write ``metrics.json``.

    Restarts from the latest written time if the case ran before. With ``extend_transits``
    the run goes on for that many transit times past the latest written time whatever the
    steady-state tests say (to see whether a steady state lasts, or to go on after a time
    limit); it then ends at ``end_time``, the wall limit or divergence. ``wall_limit`` [s]
    defaults to the spec's ``run.wall_limit``. ``on_note`` gets one line about anything
    found in the case before the run (an earlier run that was killed, a cut-short write
    removed). Returns the metrics record (as written). Raises :class:`CaseBusy` when another
    process runs the case, FileNotFoundError when ``case`` is no case folder.

    Bounds (:mod:`ehlfoam.case.bounds`), checked before anything is written: ``wall_limit``
    and ``extend_transits`` positive and finite; ``run.n_procs`` within the cores this
    process may use unless ``oversubscribe``; an extension within ``run.max_steps``. A
    :class:`~ehlfoam.errors.SpecError` names the one that is not.
    """
    from ehlfoam.case.bounds import check_extension, check_limit, check_n_procs, check_wall_limit

    if wall_limit is not None:
        check_wall_limit(wall_limit)
    if extend_transits is not None:
        check_limit("extend_transits", extend_transits, "transits")
    path = Path(case).absolute()
    if not path.is_dir():
        raise FileNotFoundError(f"case folder {path} does not exist")
    if is_thin_film_case(path) and load_spec_of(path).supply.mode == "rig":
        from ehlfoam.run.cycle import run_cycle_case   # a cycle of passes (issue 75)
        return run_cycle_case(path, wall_limit=wall_limit, on_sample=on_sample, on_note=on_note,
                              extend_transits=extend_transits, crashed=crashed_record)
    if is_thin_film_case(path):   # the gap-averaged model, no solver (issue 74)
        return run_thin_film_case(path, wall_limit=wall_limit, on_sample=on_sample,
                                  extend_transits=extend_transits, crashed=crashed_record,
                                  on_note=on_note)
    run = WatchedCase(path, load_spec_of(path), load_geometry(path),
                      case_fields.Structure.load(path))
    check_n_procs(run.spec.run.n_procs, oversubscribe=oversubscribe)
    if extend_transits is not None:
        check_extension(run.spec, extend_transits, run.geom.transit_time,
                        run.geom.max_delta_t)
    with hold_run_lock(path) as lock:
        if settle_held(path) is not None and on_note:
            on_note(f"the earlier run of {path} was killed before it ended (metrics.json "
                    f"said running, its run lock was free): marked interrupted "
                    f"({MONITOR_KILLED}); this run goes on from its latest write")
        if extend_transits is not None:
            _extend_end_time(path, run.geom, extend_transits)
        watch = SolverWatch(run, runtime=runtime or FoamRuntime.from_environment(),
                            wall_limit=wall_limit or run.spec.run.wall_limit,
                            on_sample=on_sample,
                            check_steady=extend_transits is None and run.spec.stop.at is None,
                            lock=lock, on_note=on_note)
        return watch.run()


def _extend_end_time(case: Path, geom: CaseGeometry, transits: float) -> None:
    """Set controlDict's endTime ``transits`` transit times past the latest written time, or
    past 0 for a case that has not run yet (a case seeded from another one's state runs
    ``transits`` from its start)."""
    folders = case_fields.time_folders(case)
    if folders:
        start = folders[-1][0]
    elif (case / "0.orig").is_dir() or (case / "0").is_dir():
        start = 0.0
    else:
        raise FileNotFoundError(f"{case} has no written time nor initial fields (0.orig/) "
                                "to extend from")
    with FoamFile(case / "system" / "controlDict") as f:
        f["endTime"] = start + transits * geom.transit_time
