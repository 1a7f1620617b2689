"""The delete-a-block jackknife of the side decision and of the decided side's final state (the passive chain's
check that no stretch of the record carries the answer alone; moved out of tma/sides.py, whose side decision it
repeats with each block of the record left out).

The record's span is cut into g equal stretches of time (:func:`time_blocks`, cuts moved to long gaps); each
replicate leaves one out and repeats the side decision and the decided side's constant-velocity fit
(:func:`side_jackknife`); the spread of the replicates' final states gives the block jackknife covariance, and each
left-out block's bearings against the replicate's prediction of them find a block that is another source's
(:meth:`SideJackknife.foreign_block`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import BatchEstimate, ml_bearings_only
from sonartrack.tma.sides import MIN_BEARINGS, SideDecision

#: blocks of the delete-a-block jackknife of the side decision and the final state (:func:`side_jackknife`)
JACKKNIFE_BLOCKS = 10
#: a gap in the record longer than this fraction of a block is a place where the track may have changed ship or
#: side unseen: a block's cut near it moves to it (:func:`time_blocks`)
GAP_BLOCK_FRACTION = 0.25


@dataclass(frozen=True, slots=True)
class SideJackknife:
    """The side decision and the decided side's fit repeated with each block of the record left out (g blocks).

    ``log_lr`` (g,): ln L_starboard - ln L_port of each replicate, with the whole record's sigma; ``state`` (g, 4):
    the decided side's fit at the record's last time (m, m/s), NaN where a fit failed; ``covariance`` (4, 4): the
    block jackknife covariance of that final state; ``block_rms_rad`` (g,): the rms difference between the left-out
    block's bearings and the replicate's prediction of them; ``block_sd_rad`` (g,): the rms standard deviation of
    that prediction (the replicate's covariance, its own residual scale) (:func:`side_jackknife`)."""

    log_lr: np.ndarray
    state: np.ndarray
    covariance: np.ndarray
    block_rms_rad: np.ndarray
    block_sd_rad: np.ndarray

    def stable(self, side: str, min_log_lr: float) -> bool:
        """Whether every replicate decides ``side`` (|ln LR| at least ``min_log_lr``, with its sign) and has a fit.

        Parameters
        ----------
        side : str
            The whole record's decision ("starboard" or "port").
        min_log_lr : float
            The decision threshold on |ln LR|.

        Returns
        -------
        bool
            True when no block's removal leaves the side undecided, decides the other one or fails a fit.
        """
        sign = 1.0 if side == "starboard" else -1.0
        return bool(np.all(sign * self.log_lr >= min_log_lr) and np.all(np.isfinite(self.state)))

    def foreign_block(self, width_rad: float, sds: float = 3.0) -> int | None:
        """The block (its index) whose bearings the rest of the record predicts worst, when the rms difference
        exceeds both ``width_rad`` and ``sds`` times the prediction's standard deviation; else None.

        Parameters
        ----------
        width_rad : float
            The bearing difference (rad) beyond which the block is another source's: the array's beamwidth.
        sds : float
            How many of the prediction's standard deviations the difference must also exceed.

        Returns
        -------
        int or None
            The block, or None when every block is predicted within those limits.
        """
        with np.errstate(invalid="ignore"):
            out = (self.block_rms_rad > width_rad) & (self.block_rms_rad > sds * self.block_sd_rad)
        return int(np.argmax(np.where(out, self.block_rms_rad, -1.0))) if out.any() else None


def _refit(z, t, xy, full: BatchEstimate, keep) -> BatchEstimate | None:
    """The ML CV fit of the kept bearings started from ``full`` (the whole record's fit) moved to their first time."""
    tk = t[keep]
    x_init, _ = full.state_at(tk[0])
    try:
        est = ml_bearings_only(z[keep], tk, xy[keep], 1.0, x_init=x_init[0], check=False)
    except (InputError, np.linalg.LinAlgError, FloatingPointError):
        return None
    return est if np.isfinite(est.objective) and np.all(np.isfinite(est.x0)) else None


def _prediction(est: BatchEstimate, z, t, xy, keep) -> tuple[float, float]:
    """(rms of the left-out bearings minus ``est``'s prediction, rms sd of the prediction), rad."""
    from sonartrack.tma.batch_ml import bearing_model

    out = ~keep
    h, H, _ = bearing_model(est.x0, t[out] - est.t0_s, xy[out])
    s2 = est.objective / max(int(keep.sum()) - 4, 1)
    with np.errstate(invalid="ignore", over="ignore"):
        v = np.einsum("ni,ij,nj->n", H, est.covariance * s2, H)
    return float(np.sqrt(np.mean(wrap_angle(z[out] - h) ** 2))), float(np.sqrt(np.mean(v)))


def time_blocks(time_s, blocks: int) -> np.ndarray:
    """Edges (indices) of the non-empty blocks when the record's span is cut into ``blocks`` equal stretches of time.

    Parameters
    ----------
    time_s : ndarray (n,)
        Times (s), increasing.
    blocks : int
        Stretches of time.

    Returns
    -------
    numpy.ndarray
        Increasing indices from 0 to n; block j holds the bearings edges[j]:edges[j + 1] (a stretch without
        bearings, inside a gap of the record, is no block). A cut within half a stretch of a gap (either side)
        longer than ``GAP_BLOCK_FRACTION`` of a stretch moves to the gap's end, so that a piece of the record
        between gaps is not split by a cut close to its end (its last few bearings would anchor the rest's
        prediction of it).
    """
    t = np.asarray(time_s, float)
    cuts = np.linspace(t[0], t[-1], blocks + 1)[1:-1]
    length = (t[-1] - t[0]) / blocks
    after_gap = np.flatnonzero(np.diff(t) > GAP_BLOCK_FRACTION * length) + 1
    edges = np.searchsorted(t, cuts, side="left")
    if after_gap.size:  # a cut within half a block of a gap moves to it: the piece before or after stays whole
        start, end = t[after_gap - 1][None, :], t[after_gap][None, :]
        near = np.maximum(np.maximum(start - cuts[:, None], cuts[:, None] - end), 0.0)  # distance to each gap
        k = np.argmin(near, axis=1)
        snap = near[np.arange(len(cuts)), k] < 0.5 * length
        edges = np.where(snap, after_gap[k], edges)
    return np.unique(np.concatenate([[0], edges, [len(t)]]))


def side_jackknife(time_s, starboard_rad, port_rad, sensor_xy_m, decision: SideDecision, *,
                   blocks: int = JACKKNIFE_BLOCKS) -> SideJackknife:
    """The side decision and the final state of the decided side's CV fit, each recomputed with one block of the
    record left out: the delete-a-block jackknife (Carlstein, Ann. Statist. 14(3), 1986, 1171-1179; Kunsch, Ann.
    Statist. 17(3), 1989, 1217-1241, eq. 2.2 with non-overlapping blocks).

    The record's span is cut into g equal stretches of time (:func:`time_blocks`: a short piece of the record
    between gaps lies in one block and is left out whole); replicate j leaves block j out and refits both mirror
    hypotheses (Gauss-Newton from the whole record's fits), giving ln LR_j (module doc, with the whole record's
    sigma) and the decided side's state x_j at the last time t_n. The jackknife covariance

        P_J = (g - 1) / g  sum_j (x_j - x_bar)(x_j - x_bar)^T,      x_bar = mean_j x_j

    estimates the final state's covariance without assuming the bearing errors white or the CV model right: errors
    correlated over less than a block, a bias over part of the record, a stretch of another ship's bearings all
    move the replicates as much as they move the estimate (the white-noise covariance (J^T J)^-1 sees none of
    it). It errs on the large side (Efron & Stein, Ann. Statist. 9(3), 1981). A decision that one block's removal
    overturns or leaves undecided rests on that block alone, whatever its ln LR on the whole record. Each replicate
    also predicts the bearings it left out: their rms difference and the prediction's own standard deviation
    (from the replicate's covariance at its residual scale) say whether the block belongs to the same target
    (:meth:`SideJackknife.foreign_block`; the predictive test of Chow, Econometrica 28(3), 1960, sec. 3).

    Parameters
    ----------
    time_s : ndarray (n,)
        Bearing times (s), increasing.
    starboard_rad, port_rad : ndarray (n,)
        The two mirror hypotheses' true bearings (rad, clockwise from north; :func:`mirror_bearings_rad`).
    sensor_xy_m : ndarray (n, 2)
        The array centre (m).
    decision : SideDecision
        The whole record's decision, with both fits and its sigma.
    blocks : int
        g, the stretches of time (fewer blocks where stretches hold no bearing).

    Returns
    -------
    SideJackknife
        Each replicate's ln LR, final state and prediction of its block, and P_J (NaN when a fit failed).
    """
    t, xy = np.asarray(time_s, float), np.asarray(sensor_xy_m, float)
    zs, zp = np.asarray(starboard_rad, float), np.asarray(port_rad, float)
    require(decision.starboard is not None and decision.port is not None and decision.side != "unresolved",
            "side_jackknife needs a decided side with both fits")
    edges = time_blocks(t, blocks)
    g = len(edges) - 1
    require(g >= 2, f"side_jackknife: {len(t)} bearings over {t[-1] - t[0]:g} s make fewer than 2 blocks")
    i = np.arange(len(t))
    reps = np.array([_replicate(t, zs, zp, xy, decision, (i < edges[j]) | (i >= edges[j + 1])) for j in range(g)])
    state = reps[:, 1:5]
    d = state - state.mean(axis=0)
    return SideJackknife(reps[:, 0], state, (g - 1) / g * d.T @ d, reps[:, 5], reps[:, 6])


def _replicate(t, zs, zp, xy, decision: SideDecision, keep) -> np.ndarray:
    """One jackknife replicate of :func:`side_jackknife`: [ln LR, the decided side's final state (4), the rms of
    its prediction of the left-out bearings and the prediction's rms sd] (ln LR 0 and NaNs when a fit fails)."""
    out = np.r_[0.0, np.full(6, np.nan)]
    if keep.sum() <= MIN_BEARINGS:
        return out
    with np.errstate(invalid="ignore", over="ignore"):  # a replicate without range information has no finite sd
        fs, fp = _refit(zs, t, xy, decision.starboard, keep), _refit(zp, t, xy, decision.port, keep)
        if fs is None or fp is None:
            return out
        own, z = (fs, zs) if decision.side == "starboard" else (fp, zp)
        out[0] = -(fs.objective - fp.objective) / (2.0 * float(decision.sigma_bearing_rad) ** 2)
        out[1:5] = own.state_at(t[-1])[0][0]
        out[5:] = _prediction(own, z, t, xy, keep)
    return out
