"""One BLAS thread around the front end's matrix products.

numpy's bundled OpenBLAS starts its own threads for products above a size threshold; on a loaded 2-core machine
those threads spin against the other processes and a product runs ~60 times slower (measured on the beam-power
product: 16 windows/s threaded, 1000 on one thread; the LOFAR beams of 64 elements: 6.7 s a batch threaded, 0.02 s
on one thread). :func:`one_blas_thread` sets OpenBLAS's thread count for the calling thread only
(``openblas_set_num_threads_local``) and restores it; where numpy's OpenBLAS cannot be reached it does nothing.
"""

from __future__ import annotations

from contextlib import contextmanager
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=1)
def _set_blas_threads_local():
    """numpy's bundled OpenBLAS ``openblas_set_num_threads_local`` (returns the previous count), or None."""
    import ctypes
    import glob
    import os

    try:
        libs = glob.glob(os.path.join(os.path.dirname(np.__file__), os.pardir, "numpy.libs", "libscipy_openblas*"))
        f = ctypes.CDLL(libs[0]).openblas_set_num_threads_local
    except (IndexError, OSError, AttributeError):
        return None
    f.restype, f.argtypes = ctypes.c_int, [ctypes.c_int]
    return f


def blas_reachable() -> bool:
    """Whether numpy's OpenBLAS thread count can be set (else :func:`one_blas_thread` does nothing).

    Returns
    -------
    bool
        True when ``openblas_set_num_threads_local`` was found.
    """
    return _set_blas_threads_local() is not None


@contextmanager
def one_blas_thread():
    """Run the block with numpy's OpenBLAS on one thread (the calling thread's setting; restored after)."""
    set_threads = _set_blas_threads_local()
    if set_threads is None:
        yield
        return
    previous = set_threads(1)
    try:
        yield
    finally:
        set_threads(previous)
