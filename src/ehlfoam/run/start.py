"""Getting a case ready for its solver, and saying why a run could not start.

Before the solver starts, :func:`prepare_case` brings the case to one consistent state:

- the ranks' writes of an earlier parallel run (``processor*/``) are reconstructed into the
  case folder, then the processor folders are removed;
- a last write cut short by a kill (a time folder whose fields cannot be read) is removed, so
  that the solver does not restart from it;
- with ``run.n_procs > 1``, ``system/decomposeParDict`` is written from the spec's
  ``run.n_procs`` (one source of truth) and the latest time decomposed afresh, so the
  processor folders always match the spec.

A failure there, or a solver that stops before its first time step (OpenFOAM refusing a path,
a missing application, a decomposition that does not fit), ends the run with ``end_reason``
``start_failed`` and the log's reason (:func:`failure_from_log`), not ``diverged``.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from ehlfoam.case.dictionaries import write_decomposition
from ehlfoam.case.geometry import CaseGeometry
from ehlfoam.foam.runtime import FoamError, FoamRuntime
from ehlfoam.run import fields as case_fields

__all__ = ["START_FAILED", "StartFailed", "failure_from_log", "prepare_case",
           "reconstruct_new", "restart_history"]

_ERROR_WORDS = re.compile(r"error|fatal|failed|invalid|cannot|not found|no such|denied|abort",
                          re.I)

#: end_reason of a run that failed before its first time step
START_FAILED = "start_failed"


class StartFailed(RuntimeError):
    """The run could not reach its first time step; the message says why, in one line."""


def failure_from_log(text: str, limit: int = 400) -> str:
    """One line saying why an OpenFOAM application stopped: its ``FOAM FATAL (IO) ERROR``
    block (the lines after the banner, up to the first blank one after the message), else
    its last non-empty line; '' for an empty log."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if "FOAM FATAL" in line:
            msg: list[str] = []
            for ln in lines[i + 1:]:
                s = ln.strip()
                if not s:
                    if msg:
                        break
                    continue
                if s.startswith(("From ", "in file ", "-->", "file:")):
                    continue
                msg.append(s)
            head = line.strip().strip("-> ").rstrip(":").strip()
            return " ".join((head + ": " + " ".join(msg)).split())[:limit]
    rest = [ln.strip() for ln in lines if ln.strip().strip("-=*") and ln.strip()]
    errors = [ln for ln in rest if _ERROR_WORDS.search(ln)]
    chosen = errors[:3] if errors else rest[-1:]
    return " ".join(" ".join(chosen).split())[:limit]


def _log_reason(log: Path) -> str:
    try:
        return failure_from_log(log.read_text(errors="replace"))
    except OSError:
        return ""


def _new_rank_times(case: Path) -> list[str]:
    """The times the ranks wrote (processor0/) that the case folder has not, in time order."""
    proc0 = case / "processor0"
    if not proc0.is_dir():
        return []
    have = {p.name for _, p in case_fields.time_folders(case)}
    return [p.name for _, p in case_fields.time_folders(proc0) if p.name not in have]


def reconstruct_new(case: Path, runtime: FoamRuntime, check: bool = False) -> None:
    """Bring the times the ranks wrote into the case folder (reconstructPar -newTimes).

    ``check`` (before a restart, the ranks stopped): a last write the ranks did not finish
    (a kill) is removed from the processor folders and reconstructPar tried again; raise
    :class:`StartFailed` when it still fails."""
    log = case / "log.reconstructPar"
    dropped = False
    while new := _new_rank_times(case):
        res = runtime.run("reconstructPar", ["-newTimes"], cwd=case, log_path=log,
                          check=False)
        if res.returncode == 0 or not check:
            return
        if dropped:   # not only a cut-short last write: keep everything, say why
            raise StartFailed(f"reconstructPar of the earlier parallel run's writes failed "
                              f"(exit code {res.returncode}; the processor folders are kept): "
                              f"{_log_reason(log)}")
        last, dropped = new[-1], True
        for p in _processor_folders(case):
            shutil.rmtree(p / last, ignore_errors=True)
        shutil.rmtree(case / last, ignore_errors=True)


def _processor_folders(case: Path) -> list[Path]:
    return sorted(p for p in case.glob("processor*") if p.is_dir())


def restart_history(case: Path, structure: case_fields.Structure, geom: CaseGeometry
                    ) -> tuple[list[case_fields.Sample], set[str], list[str]]:
    """The samples of the case's earlier writes (a restart: they count), the names read,
    and the names of trailing writes removed because they cannot be read (a write cut short
    by a kill; the solver would restart from it and fail)."""
    folders = case_fields.time_folders(case)
    removed: list[str] = []
    while folders:
        try:
            case_fields.sample(folders[-1][1], structure, geom)
            break
        except Exception:  # noqa: BLE001 - unreadable: cut short
            removed.append(folders[-1][1].name)
            shutil.rmtree(folders[-1][1], ignore_errors=True)
            folders.pop()
    history, done = [], set()
    for _, folder in folders:
        try:
            history.append(case_fields.sample(folder, structure, geom))
        except Exception:  # noqa: BLE001 - an unreadable earlier write is skipped
            pass
        done.add(folder.name)
    return history, done, removed


def prepare_case(case: Path, runtime: FoamRuntime, n_procs: int,
                 structure: case_fields.Structure, geom: CaseGeometry
                 ) -> tuple[list[case_fields.Sample], set[str], list[str]]:
    """Make the case ready for its solver (module docstring): its initial fields, an earlier
    parallel run's writes reconstructed and its processor folders removed, an unreadable last
    write removed, and with ``n_procs > 1`` decomposeParDict written from the spec and the
    latest time decomposed. Returns :func:`restart_history`'s (samples, names, removed).
    Raises :class:`StartFailed` with the reason."""
    if not (case / "0").is_dir():
        shutil.copytree(case / "0.orig", case / "0")
    if _processor_folders(case):
        reconstruct_new(case, runtime, check=True)
        for p in _processor_folders(case):
            shutil.rmtree(p)
    history, done, removed = restart_history(case, structure, geom)
    if n_procs < 2:
        return history, done, removed
    write_decomposition(case, n_procs)
    log = case / "log.decomposePar"
    try:
        runtime.run("decomposePar", ["-force", "-latestTime"], cwd=case, log_path=log)
    except FoamError as err:
        reason = _log_reason(log) if log.is_file() else " ".join(str(err).split())[:400]
        raise StartFailed(f"decomposePar into {n_procs} subdomains failed: {reason}") from None
    if len(_processor_folders(case)) != n_procs:
        raise StartFailed(f"decomposePar wrote {len(_processor_folders(case))} processor "
                          f"folders, run.n_procs = {n_procs}")
    return history, done, removed
