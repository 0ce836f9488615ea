"""Running OpenFOAM cases, the ehlfoam command line and its runtime."""

import os

# One OpenBLAS thread (unless the user chose otherwise): the flow-pattern raster makes
# thousands of tiny LAPACK calls, which an OpenBLAS thread pool slows from 0.02 s to seconds
# on cores busy with OpenFOAM (runs/report/threads.py). Effective when numpy loads after this.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
