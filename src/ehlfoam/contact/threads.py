"""The EHL precalc's one thread setting: how many threads a solve uses (scipy.fft and the
numba kernels alike) and the block that runs the numba kernels on them."""

from __future__ import annotations

from contextlib import contextmanager

import numba

#: Grids with fewer points than this run on one thread (threads cost more than they save).
PARALLEL_MIN_POINTS = 300_000


def solve_threads(workers: int | None = None) -> int:
    """Threads a solve uses, the one setting for both scipy.fft and the numba kernels:
    ``workers`` if given, else the calling thread's numba thread count, which a batch sets to
    the cores it gives the job (``numba.set_num_threads``), the environment sets by
    ``NUMBA_NUM_THREADS``, and which is otherwise the cores this process may run on; never
    more than numba's thread pool."""
    n = numba.get_num_threads() if workers is None else int(workers)
    return max(1, min(n, numba.config.NUMBA_NUM_THREADS))


@contextmanager
def numba_threads(n: int):
    """Run the numba kernels of the block on ``n`` threads (the previous count restored)."""
    prev = numba.get_num_threads()
    numba.set_num_threads(n)
    try:
        yield
    finally:
        numba.set_num_threads(prev)
