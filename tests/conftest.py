"""Shared test fixtures."""

import os

import matplotlib

matplotlib.use("Agg")
# numba-compiled kernels cache into the package; keep test runs from fighting over it
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".numba-cache"))
