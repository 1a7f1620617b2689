"""Range-Doppler frames of an active sonar with one Swerling-1 target (Im & Kim 1996, paper P1, sec. V).

K frames of n_range x n_doppler square-law cells. Every cell is exponential with mean 2 (noise,
eq. 8); if a target is present, the cell it occupies in frame k is exponential with mean
2 (1 + rho) instead (Swerling 1, eq. 7; independent from frame to frame). The target moves by the
AR model of eq. 23,

    w_{k+1} = Phi w_k + g (a_k + u_k),   a_k ~ N(0, sigma_a^2),  u_k known,

and occupies the cell its true [range, range-rate] falls in. Its first state is uniform over the
plane; tracks that leave the plane before frame K are redrawn (the paper assumes the target stays
in the plane for the K frames, footnote 2), so the simulated tracks are conditioned on staying.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.errors import require
from sonartrack.models.range_doppler import RangeDopplerGrid, ar_input_gain, ar_transition, own_accel_array
from sonartrack.models.swerling import sample_cells

#: candidate tracks drawn per batch while looking for one that stays in the plane
_BATCH = 64


@dataclass(frozen=True, slots=True)
class TargetTrack:
    """A simulated target: true states (K, 2) [range m, range-rate m/s] and its cells (K, 2) [i, j]."""

    states: np.ndarray
    cells: np.ndarray


def simulate_target(rng: np.random.Generator, grid: RangeDopplerGrid, period_s: float, sigma_a_mps2: float,
                    n_frames: int, own_accel_mps2=None, max_tries: int = 100_000) -> TargetTrack:
    """Draw a target track that stays in the plane for ``n_frames`` frames (paper P1's AR model, eq. 23; rejection).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    grid : RangeDopplerGrid
        The plane; the first state is uniform over it.
    period_s : float
        Frame period T (s).
    sigma_a_mps2 : float
        Standard deviation of the range acceleration (m/s^2).
    n_frames : int
        K.
    own_accel_mps2 : float or sequence of float, optional
        Known inputs u_k (m/s^2).
    max_tries : int, default 100000
        Candidate tracks drawn before giving up.

    Returns
    -------
    TargetTrack
        True states (K, 2) [range (m), range-rate (m/s)] and their cells (K, 2) [i, j].

    Raises
    ------
    RuntimeError
        If no candidate stayed in the plane.
    """
    require(n_frames >= 1, f"K (frames) must be at least 1, got {n_frames}")
    u = own_accel_array(own_accel_mps2, n_frames)
    Phi, g = ar_transition(period_s), ar_input_gain(period_s)
    r0, r1, v0, v1 = grid.extent()
    tried = 0
    while tried < max_tries:
        w = np.empty((_BATCH, n_frames, 2))
        w[:, 0, 0] = rng.uniform(r0, r1, _BATCH)
        w[:, 0, 1] = rng.uniform(v0, v1, _BATCH)
        a = rng.normal(0.0, sigma_a_mps2, (_BATCH, max(n_frames - 1, 0)))
        for k in range(n_frames - 1):
            w[:, k + 1] = w[:, k] @ Phi.T + np.outer(a[:, k] + u[k], g)
        i, j, inside = grid.cell_index(w)
        ok = np.nonzero(inside.all(axis=1))[0]
        if ok.size:
            b = ok[0]
            return TargetTrack(w[b].copy(), np.stack([i[b], j[b]], axis=-1))
        tried += _BATCH
    raise RuntimeError(f"no target track stayed in the plane in {max_tries} draws: enlarge the plane or lower sigma_a")


def simulate_frames(rng: np.random.Generator, grid: RangeDopplerGrid, n_frames: int, snr: float = 0.0,
                    cells=None) -> np.ndarray:
    """Square-law range-Doppler frames: noise of mean 2, optionally a Swerling-1 target (paper P1, eqs. 7, 8).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random stream.
    grid : RangeDopplerGrid
        The plane.
    n_frames : int
        K.
    snr : float, default 0.0
        Target SNR rho (linear power ratio).
    cells : array_like of int, shape (K, 2), optional
        [range index, Doppler index] of the target per frame; None: noise only.

    Returns
    -------
    ndarray, shape (K, n_range, n_doppler)
        Cell values.
    """
    y = sample_cells(rng, (n_frames, grid.n_range, grid.n_doppler))
    if cells is not None:
        cells = np.asarray(cells, dtype=np.int64)
        k = np.arange(n_frames)
        y[k, cells[:, 0], cells[:, 1]] = sample_cells(rng, n_frames, snr)
    return y
