"""What the benchmarks share: a solve in a fresh process, spec options, work folders, the
printed tables and the record written with ``--out``.

Benchmarks import only the public package (``ehlfoam.*``) and this file. They print their
tables and write nothing into the tree: results go to ``--out FILE.json`` when given, cases
to ``--work DIR`` when given, else to a temporary folder removed at the end.
"""

from __future__ import annotations

import argparse
import contextlib
import multiprocessing as mp
import re
import resource
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any


def _child(spec_kwargs: dict, queue, workers: int | None = None) -> None:
    import os

    from ehlfoam.contact.threads import numba_threads, solve_threads
    from ehlfoam.contact.solver import solve
    from ehlfoam.contact.spec import make_spec

    with numba_threads(solve_threads(workers)):  # the solver's one thread setting
        solve(make_spec(**{**spec_kwargs, "grid": 65, "max_cycles": 2}))  # numba's compile
        spec = make_spec(**spec_kwargs)
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            summary = solve(spec).summary()
        except Exception as err:  # noqa: BLE001 - a failed point of a map is data
            summary = {"converged": False, "failure": f"{type(err).__name__}: {err}"}
        summary["wall_s"] = time.perf_counter() - t0
        summary["cpu_s"] = time.process_time() - c0
    summary["peak_rss_GiB"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    summary["load_average"] = os.getloadavg()
    summary["threads"] = solve_threads(workers)
    queue.put(summary)


def solve_in_subprocess(spec_kwargs: dict, workers: int | None = None) -> dict:
    """The EHL precalc of ``make_spec(**spec_kwargs)`` solved in a fresh process on
    ``workers`` threads (default: the solver's own choice), so that its peak memory is its own
    and numba's compile time is paid before the clock starts: its summary plus ``wall_s`` [s],
    ``cpu_s`` [s] (the process's CPU time, all threads), ``peak_rss_GiB`` and the machine's
    ``load_average`` at the end (timings on a shared machine are noisy); a solve that raised
    gives ``converged`` False and its ``failure``."""
    ctx = mp.get_context("spawn")
    queue = ctx.Queue()
    proc = ctx.Process(target=_child, args=(spec_kwargs, queue, workers))
    proc.start()
    out = queue.get()
    proc.join()
    return out


def spec_option(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` of a spec option (dotted key, e.g. ``run.max_courant=1``), the value read
    as ``ehlfoam case --set`` reads it; an argparse ``type``."""
    from ehlfoam.cli.case import parse_value

    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--set wants KEY=VALUE, got {text!r}")
    return key, parse_value(value)


def count_option(low: int, high: int):
    """An argparse type: an integer in [low, high], refused with the range named."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{text!r}: must be an integer in [{low}, {high}]")
        return value
    return parse


def add_output_options(ap: argparse.ArgumentParser, work: bool = False) -> None:
    """``--quick``, ``--out FILE.json`` and, for benchmarks that write cases, ``--work DIR``."""
    ap.add_argument("--quick", action="store_true",
                    help="a small size that runs in seconds (what the tests run)")
    ap.add_argument("--out", type=Path, default=None, metavar="FILE.json",
                    help="write the results here (default: print only)")
    if work:
        ap.add_argument("--work", type=Path, default=None, metavar="DIR",
                        help="write the cases here and keep them (default: a temporary "
                             "folder, removed at the end)")


@contextlib.contextmanager
def work_folder(given: Path | None) -> Iterator[Path]:
    """``given`` (made, kept), or a temporary folder removed on leaving."""
    if given is not None:
        given.mkdir(parents=True, exist_ok=True)
        yield given
        return
    with tempfile.TemporaryDirectory(prefix="ehlfoam-bench-") as tmp:
        yield Path(tmp)


def write_out(path: Path | None, data: Any) -> None:
    """With ``--out``, write ``data`` there as JSON, atomically; say so."""
    if path is None:
        return
    from ehlfoam._io import atomic_write_json

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_json(path, data)
    print(f"wrote {path}")


def print_table(rows: Sequence[dict], columns: Sequence[tuple[str, str, str]],
                title: str = "") -> None:
    """Print ``rows`` as a table: ``columns`` are (key, heading, format spec); a missing or
    None value prints as '-'."""
    def cell(value: Any, fmt: str) -> str:
        if value is None:
            return "-"
        try:
            return format(value, fmt)
        except (TypeError, ValueError):
            return str(value)
    texts = [[cell(r.get(k), f) for k, _, f in columns] for r in rows]
    widths = [max([len(h)] + [len(t[i]) for t in texts]) for i, (_, h, _) in enumerate(columns)]
    if title:
        print(title)
    print("  ".join(h.rjust(w) for (_, h, _), w in zip(columns, widths)))
    for t in texts:
        print("  ".join(v.rjust(w) for v, w in zip(t, widths)), flush=True)


def ratios(rows: list[dict], key: str, name: str) -> None:
    """Set ``row[name]`` to each row's ``key`` over the previous row's (None for the first or
    where either is missing): the cost per step of size."""
    for prev, row in zip([None, *rows[:-1]], rows):
        ok = prev is not None and prev.get(key) and row.get(key) is not None
        row[name] = row[key] / prev[key] if ok else None


def solver_cpu_s(case: Path) -> float | None:
    """The OpenFOAM solver's own last ``ExecutionTime`` [s] (CPU time) in the case's
    ``log.*Foam``; None without a log or a reported time."""
    logs = sorted(Path(case).glob("log.*Foam"))
    if not logs:
        return None
    times = re.findall(r"^ExecutionTime = ([0-9.eE+-]+) s", logs[0].read_text(errors="replace"),
                       re.M)
    return float(times[-1]) if times else None

