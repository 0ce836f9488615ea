"""One BLAS thread while a report is drawn.

The raster of the metrics (:func:`ehlfoam.metrics.pattern.raster`) locates 140,000 pixels in a Delaunay
triangulation; scipy computes the triangles' barycentric transforms with thousands of tiny
LAPACK calls. With OpenBLAS's default thread pool on a machine whose cores are busy (the
OpenFOAM runs), each call waits for worker threads that are not scheduled: measured on the
2-core machine, the same raster took 0.1 s to 7 s from run to run, against a steady 0.02 s
with one thread. :func:`single_blas_thread` sets every loaded OpenBLAS (numpy's and scipy's)
to one thread for the duration and restores the previous count afterwards.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
from collections.abc import Iterator

#: (setter, getter) symbol names of the OpenBLAS builds numpy and scipy wheels bundle.
_SYMBOLS = (("scipy_openblas_set_num_threads64_", "scipy_openblas_get_num_threads64_"),
            ("scipy_openblas_set_num_threads", "scipy_openblas_get_num_threads"),
            ("openblas_set_num_threads64_", "openblas_get_num_threads64_"),
            ("openblas_set_num_threads", "openblas_get_num_threads"))


def _openblas_libraries() -> list[tuple]:
    """(set, get) function pairs of the OpenBLAS libraries loaded in this process."""
    try:
        with open("/proc/self/maps") as fh:
            paths = {parts[-1] for parts in (line.split() for line in fh)
                     if len(parts) >= 6 and parts[-1].startswith("/")}
    except OSError:
        return []
    out = []
    for path in sorted(p for p in paths if os.path.basename(p).startswith("lib")
                       and "openblas" in os.path.basename(p).lower()):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for setter, getter in _SYMBOLS:
            if hasattr(lib, setter) and hasattr(lib, getter):
                out.append((getattr(lib, setter), getattr(lib, getter)))
                break
    return out


@contextlib.contextmanager
def single_blas_thread() -> Iterator[int]:
    """Within the block, every loaded OpenBLAS runs one thread (and child processes started
    in it inherit OPENBLAS_NUM_THREADS=1); yields how many libraries were set."""
    import scipy.spatial  # noqa: F401 - loads scipy's own OpenBLAS, so that it is set too

    env = os.environ.get("OPENBLAS_NUM_THREADS")
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    libs = _openblas_libraries()
    before = []
    for setter, getter in libs:
        try:
            before.append(int(getter()))
            setter(1)
        except Exception:  # noqa: BLE001 - a library we cannot steer is left alone
            before.append(None)
    try:
        yield len(libs)
    finally:
        for (setter, _), n in zip(libs, before):
            if n:
                setter(n)
        if env is None:
            os.environ.pop("OPENBLAS_NUM_THREADS", None)
        else:
            os.environ["OPENBLAS_NUM_THREADS"] = env
