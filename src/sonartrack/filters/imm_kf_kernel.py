"""Compiled single-track IMM-KF step (numba), the same cycle as filters/imm_kf.imm_kf_step.

Mixing, per-mode KF predict and Joseph update, mode probabilities, combination (equations in
filters/imm.py and filters/kalman.py), each a compiled step, called in turn by one compiled function:
one track's IMM step with a few modes costs microseconds instead of ~100 us of NumPy call overhead.
Compiled lazily (numba is imported on the first call), cached on disk. The NumPy ``imm_kf_step`` is
the reference it is tested against.
"""

from __future__ import annotations

import numpy as np


def imm_kf_step_fast(x, P, mu, z, F, Q, H, R, Pi):
    """Compiled (numba) IMM-KF step: same arguments and results as :func:`filters.imm_kf.imm_kf_step`.

    Parameters
    ----------
    x, P, mu, z, F, Q, H, R, Pi
        As ``imm_kf_step``; ``F`` may be ``(n, n)`` (shared by the modes) or ``(r, n, n)``.

    Returns
    -------
    x_r, P_r, mu, x_comb, P_comb
        As ``imm_kf_step``.
    """
    from sonartrack.filters.imm_kf_jit import kernel
    x = np.ascontiguousarray(x, dtype=float)
    F = np.asarray(F, float)
    F = np.ascontiguousarray(F.reshape((1,) + F.shape) if F.ndim == 2 else F)  # (1, n, n): shared by the modes
    return kernel(x, np.ascontiguousarray(P, dtype=float), np.ascontiguousarray(mu, dtype=float),
                   np.ascontiguousarray(z, dtype=float), F, np.ascontiguousarray(Q, dtype=float),
                   np.ascontiguousarray(H, dtype=float), np.ascontiguousarray(R, dtype=float),
                   np.ascontiguousarray(Pi, dtype=float))
