"""ehlfoam: OpenFOAM cases of the oil flow around an EHL ball-on-disc contact.

The public API: a case spec, its EHL precalc, the OpenFOAM case, its run and metrics, a batch
of cases, a report (``write_report``)::

    import ehlfoam

    spec = ehlfoam.load_case_spec("examples/cases/nominal.toml", **{"mesh.resolution": "coarse"})
    ehlfoam.write_case(spec, "runs/nominal")
    metrics = ehlfoam.run_case("runs/nominal")
    print(metrics["state"], metrics["inlet_meniscus_distance_over_a"])

SI units throughout (lengths in m, speeds in m/s; ``_over_a``: in Hertz radii). Names load on
first use (PEP 562), so ``import ehlfoam`` is quick. It changes one thing: unless
``NUMBA_CACHE_DIR`` is set, it points numba's cache at a folder per version of the package's
kernels (:mod:`ehlfoam._kernel_cache`: numba would otherwise keep running a kernel's old
callees from other files after an update).
"""

from __future__ import annotations

import os
from importlib import import_module
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ehlfoam._kernel_cache import use_kernel_cache_dir

if TYPE_CHECKING:
    from ehlfoam.batch.launch import BatchOutcome
    from ehlfoam.case.geometry import CaseGeometry
    from ehlfoam.contact.spec import PrecalcSpec
    from ehlfoam.errors import SpecError
    from ehlfoam.metrics.record import MetricsRecord
    from ehlfoam.report import report as write_report
    from ehlfoam.run.monitor import run_case
    from ehlfoam.spec.case import CaseSpec, load_case_spec, make_case_spec

__all__ = ["SpecError", "__version__", "load_case_spec", "make_case_spec", "precalc",
           "read_metrics", "run_batch", "run_case", "write_case", "write_report"]

#: the names re-exported from the subpackages: name -> (module, its name there). The report
#: is ``write_report``: ``ehlfoam.report`` is the subpackage, which its import binds here.
_REEXPORTED = {
    "SpecError": ("ehlfoam.errors", "SpecError"),
    "load_case_spec": ("ehlfoam.spec.case", "load_case_spec"),
    "make_case_spec": ("ehlfoam.spec.case", "make_case_spec"),
    "run_case": ("ehlfoam.run.monitor", "run_case"),
    "write_report": ("ehlfoam.report", "report"),
}


use_kernel_cache_dir()


def __getattr__(name: str) -> Any:
    if name in _REEXPORTED:
        module, attr = _REEXPORTED[name]
        value = getattr(import_module(module), attr)
    elif name == "__version__":
        from importlib.metadata import version

        value = version("ehlfoam")
    else:
        raise AttributeError(f"module 'ehlfoam' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


def precalc(spec: CaseSpec | PrecalcSpec) -> dict[str, Any]:
    """The EHL precalc of a case spec's contact (or of a contact spec): solved once per
    contact, then read from the cache. Returns its summary (SI units: ``a_m``, ``hc_m``,
    ``hmin_m``, ``p_max_Pa``, ``converged``, ...) with ``folder`` (a Path), where summary.json,
    solution.npz and precalc.png are."""
    import json

    from ehlfoam.gap.source import precalc_dir
    from ehlfoam.spec.case import CaseSpec

    folder = precalc_dir(spec.contact if isinstance(spec, CaseSpec) else spec,
                         require_converged=False)
    return {**json.loads((folder / "summary.json").read_text()), "folder": folder}


def write_case(spec: CaseSpec, out: str | os.PathLike, *,
               start_from: str | os.PathLike | None = None,
               overwrite: bool = False) -> CaseGeometry:
    """Write the OpenFOAM case of ``spec`` in ``out`` (as ``ehlfoam case``): precalc, mesh,
    OpenFOAM files; started from ``start_from`` (a run case, a case snapshot or a thin-film
    state) if given. Returns the case's geometry (cells, a, transit time, ...). Raises
    :class:`SpecError` before any work where ``out`` cannot be written (a file, a read-only
    or full disk) or OpenFOAM cannot take its path (a space, a quote, ...)."""
    from ehlfoam.paths import check_case_out
    from ehlfoam.seed.follow import write_started_case

    check_case_out(out, "out")
    geometry, _ = write_started_case(spec, out, start_from, overwrite=overwrite)
    return geometry


def read_metrics(case_dir: str | os.PathLike) -> MetricsRecord:
    """The metrics record of a run case (its ``metrics.json``; ``record["state"]``,
    ``record.state``). A record that a killed run left saying ``running`` (no process holds
    the case's run lock) is first rewritten as ``interrupted`` (end_reason
    ``monitor_killed``). Raises FileNotFoundError when it has none (not run)."""
    from ehlfoam.metrics.record import read_metrics as _read
    from ehlfoam.run.monitor import settle_killed_run

    settle_killed_run(case_dir)
    return _read(case_dir)


def run_batch(spec_path: str | os.PathLike, *, out: str | os.PathLike | None = None,
              **options: Any) -> BatchOutcome:
    """Run a batch spec (as ``ehlfoam batch``): ``out`` the batch folder (default
    runs/STEM/ in the working folder); ``options`` as ``ehlfoam batch``'s (``jobs``,
    ``cores``, ``rerun_failed``, ``scheduler``, ``quiet``, ...; see
    :class:`ehlfoam.batch.launch.BatchOptions`), and ``report=False`` for no report.
    Returns the outcome (counts, exit code). Raises :class:`SpecError` before any work where
    the batch folder cannot be written or OpenFOAM cannot take its path."""
    from ehlfoam.batch.folder import batch_folder
    from ehlfoam.batch.launch import BatchOptions, run_batch as _run_batch
    from ehlfoam.paths import check_case_out
    from ehlfoam.report import after_batch

    check_case_out(batch_folder(Path(spec_path), None if out is None else Path(out)))
    options["report"] = after_batch if options.get("report", True) else None
    return _run_batch(spec_path, BatchOptions(out=None if out is None else Path(out),
                                              **options))
