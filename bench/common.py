"""Shared helpers of the benchmark scripts: one solve per fresh process (so that its peak
memory is its own and numba's compile time is paid before the clock starts)."""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import resource
import sys
import time
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"


def _child(spec_kwargs: dict, options: dict | None, queue, workers: int | None = None) -> None:
    import os

    if workers:  # the one thread setting of a solve (numba's count, read by the solver)
        os.environ["NUMBA_NUM_THREADS"] = str(workers)
    from ehlfoam.contact.multigrid import SolverOptions
    from ehlfoam.contact.solver import solve
    from ehlfoam.contact.spec import make_spec

    solve(make_spec(**{**spec_kwargs, "grid": 65, "max_cycles": 2}))  # JIT warm-up
    spec = make_spec(**spec_kwargs)
    opt = None
    if options:
        opt = SolverOptions(**{"max_cycles": spec.max_cycles, "tol_residual": spec.tol_residual,
                               "tol_load": spec.tol_load, **options})
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        result = solve(spec, opt)
        summary = result.summary()
        summary["nan"] = False
    except Exception as err:  # noqa: BLE001 - a failed point of a map is data
        summary = {"converged": False, "failure": f"{type(err).__name__}: {err}", "nan": True}
    summary["wall_s"] = time.perf_counter() - t0
    summary["cpu_s"] = time.process_time() - c0
    summary["peak_rss_GiB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    summary["load_average"] = os.getloadavg()
    queue.put(summary)


def solve_in_subprocess(spec_kwargs: dict, options: dict | None = None,
                        workers: int | None = None) -> dict:
    """Solve in a fresh process on ``workers`` threads (default: the solver's own choice);
    returns the summary plus wall_s, cpu_s (the process's CPU time), peak_rss_GiB and the
    machine's load_average at the end."""
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=_child, args=(spec_kwargs, options, q, workers))
    p.start()
    out = q.get()
    p.join()
    return out


def save(name: str, data) -> Path:
    """Write a record ``bench/results/NAME`` as JSON, atomically (an interrupted script never
    leaves half a record); ``.json`` is added to a NAME without it, so that every record is
    found by its suffix."""
    from ehlfoam._io import atomic_write_text

    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / (name if name.endswith(".json") else f"{name}.json")
    atomic_write_text(path, json.dumps(data, indent=2, default=str) + "\n")
    return path


def log(msg: str) -> None:
    print(msg, flush=True)
    sys.stdout.flush()


def solver_cpu_s(case: Path) -> float | None:
    """The OpenFOAM solver's own last ``ExecutionTime`` [s] (CPU time) in the case's
    ``log.*Foam``; None without a log or a reported time."""
    import re

    logs = sorted(Path(case).glob("log.*Foam"))
    if not logs:
        return None
    text = logs[0].read_text(errors="replace")
    times = re.findall(r"^ExecutionTime = ([0-9.eE+-]+) s", text, re.M)
    return float(times[-1]) if times else None


def spec_option(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` of a spec option (dotted key, e.g. ``run.max_courant=1``), the value read
    as ``ehlfoam case --set`` reads it (the spec validates it); an argparse ``type``."""
    from ehlfoam.cli.main import parse_value

    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--set wants KEY=VALUE, got {text!r}")
    return key, parse_value(value)


def foam_edit(text: str) -> tuple[str, tuple[str, ...], object]:
    """``FILE:KEY/SUBKEY=VALUE`` of a ``system/`` file entry (or, where FILE has a folder,
    of that case file: ``0.orig/alpha.oil:boundaryField/"(disc|ball|island)"/limit=none``);
    VALUE is a word, a number or several words (a scheme); an argparse ``type``."""
    target, sep, value = text.partition("=")
    file, colon, path = target.partition(":")
    if not sep or not colon or not path:
        raise argparse.ArgumentTypeError(f"--edit wants FILE:KEY/SUBKEY=VALUE, got {text!r}")
    words = tuple(_word_or_number(w) for w in value.split())
    return file, tuple(path.split("/")), words if len(words) > 1 else _word_or_number(value)


def edit_value_text(value: object, sep: str = " ") -> str:
    """The VALUE of a :func:`foam_edit` as text again, its words joined by ``sep`` (``""``
    for a folder name)."""
    return sep.join(map(str, value)) if isinstance(value, tuple) else str(value)


def _word_or_number(word: str) -> int | float | str:
    """A scheme's word as the number it spells (``limitedLinear01 1``'s 1), else the word."""
    for kind in (int, float):
        try:
            return kind(word)
        except ValueError:
            pass
    return word


def apply_edits(case: Path, edits: list, solver: str = "") -> None:
    """Apply ``--edit`` entries (:func:`foam_edit`) and, where given, another solver of the
    interFoam family (``interIsoFoam``) to a written case."""
    import dataclasses

    from foamlib import FoamFile

    from ehlfoam._io import atomic_write_json
    from ehlfoam.case.writer import META, load_geometry

    for file, keys, value in edits:
        with FoamFile(case / file if "/" in file else case / "system" / file) as f:
            entry = f
            for key in keys[:-1]:
                entry = entry[key]
            entry[keys[-1]] = value
    if not solver:
        return
    geom = load_geometry(case)
    if solver != geom.solver:
        with FoamFile(case / "system" / "controlDict") as f:
            f["application"] = solver
        geom = dataclasses.replace(geom, solver=solver)
        atomic_write_json(case / META / "geometry.json", dataclasses.asdict(geom))
