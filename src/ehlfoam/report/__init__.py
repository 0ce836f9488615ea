"""Reports without ParaView: a case's or a batch's pictures and tables in one HTML page.

    report_case(case_dir) -> CASE/report/index.html
    report_batch(batch_dir) -> BATCH/report/index.html
    after_batch(batch_dir, log) -> the regime map's lines in the log, then report_batch
    report(dir)            -> whichever ``dir`` is

``ehlfoam report DIR`` (ehlfoam.cli.report) is its command line.

Everything renders off-screen (pyvista reads the case with its OpenFOAM reader and cuts
it; matplotlib's Agg canvas draws): no X server, no ParaView.
"""

from __future__ import annotations

import os
from pathlib import Path

from ehlfoam.report.case_report import report_case

__all__ = ["after_batch", "is_batch", "is_case", "report", "report_batch", "report_case"]


def is_case(path: str | os.PathLike) -> bool:
    """A case folder: written by ``ehlfoam case`` (ehlfoam/geometry.json) or at least an
    OpenFOAM case (system/controlDict)."""
    p = Path(path)
    return (p / "ehlfoam" / "geometry.json").is_file() or (p / "system" / "controlDict").is_file()


def is_batch(path: str | os.PathLike) -> bool:
    """A batch folder: plan.json, results.csv or a cases/ folder."""
    p = Path(path)
    return (p / "plan.json").is_file() or (p / "results.csv").is_file() or (p / "cases").is_dir()


def report_batch(batch_dir: str | os.PathLike, **kwargs) -> Path:
    """Write ``batch_dir/report/index.html``; see :func:`ehlfoam.report.batch.report_batch`."""
    from ehlfoam.report.batch import report_batch as _report_batch

    return _report_batch(batch_dir, **kwargs)


def after_batch(batch_dir: str | os.PathLike, log) -> Path:
    """What ``ehlfoam batch`` reports after its cases; see
    :func:`ehlfoam.report.batch.after_batch`."""
    from ehlfoam.report.batch import after_batch as _after_batch

    return _after_batch(batch_dir, log)


def report(path: str | os.PathLike, **kwargs) -> Path:
    """The report of a case or a batch folder (detected); returns the index.html path.
    Raises FileNotFoundError when ``path`` is not a folder, ValueError when it is neither."""
    p = Path(path)
    if not p.is_dir():
        raise FileNotFoundError(f"{p}: no such folder")
    if is_case(p):
        return report_case(p, **{k: v for k, v in kwargs.items() if k == "animate"})
    if is_batch(p):
        return report_batch(p, **kwargs)
    raise ValueError(f"{p}: neither a case (ehlfoam/geometry.json, system/controlDict) nor "
                     f"a batch (plan.json, results.csv, cases/)")

