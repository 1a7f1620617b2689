"""Compiled PDA over the gated pairs (numba), for the tracker: the weights' sums and the mixture update.

The same update as ``association.pda.pda_mixture_update`` (equations there and in association/pda.py's
module doc), for n tracks x r modes and G gated (track, measurement) pairs g = (t, m):

    dx_g = K_g nu_g                                     (K_g = P-_t H^T S_g^-1)
    x_t = x-_t + sum_g beta_g dx_g
    P_t = beta_0 P-_t + sum_g beta_g (P-_t - K_g H P-_t + dx_g dx_g^T) - dx dx^T,   dx = sum_g beta_g dx_g

The compiled loops do the per-pair terms, their sums per track and the combination with the same
floating-point operations in the same order as the reference (its sums accumulate pair after pair,
0 + v_1 + v_2 + ...), so the results are identical bit for bit, without the reference's (G, r, d, d)
temporaries and reading only the G gated pairs (never an (n, r, m) array). The gains K_g and the
products K_g H P-_t of 2-D measurements are computed in the loop too, as NumPy's matmul computes them
on this machine (its BLAS accumulates c = a_0 b_0, then c = fma(a_1, b_1, c)); :func:`gains_match_numpy`
checks that once per process on random matrices, and where it does not hold (another BLAS, no FMA)
the wrapper takes NumPy's products instead, as before. With scalar measurements (k = 1, the bearing
tracker) every entry of K_g and K_g H P-_t is a single product, which any matmul gives exactly, so those are
computed in the loop too (:func:`_pair_sums_k1`).

:func:`dense_row_sums` gives the PDA weights' sums over measurements, sum_m p_rm / rho_m, from the
gated pairs alone with exactly NumPy's result for the dense (n, r, m) row sum (its pairwise summation:
blocks of at most 128 summed in 8 interleaved accumulators, longer rows split in halves rounded down
to a multiple of 8; the zeros outside the gate add nothing), so the dense array is never formed.

This module imports numba at the top; tracking/multi_target.py imports it on the first update, so
``import sonartrack`` stays fast. Compiled functions are cached on disk.
"""

from __future__ import annotations

import functools

import llvmlite.ir as llvm_ir
import numba as nb
import numpy as np
from numba.core import cgutils
from numba.extending import intrinsic

from sonartrack.association.likelihood import Likelihoods
from sonartrack.core.linalg import symmetrize


@intrinsic
def _fma(typingctx, a, b, c):
    """a * b + c rounded once (LLVM's fma intrinsic: the hardware instruction, or an exact software one)."""
    sig = nb.types.float64(nb.types.float64, nb.types.float64, nb.types.float64)

    def codegen(context, builder, signature, args):
        dbl = llvm_ir.DoubleType()
        fn = cgutils.get_or_insert_function(builder.module, llvm_ir.FunctionType(dbl, [dbl] * 3), "llvm.fma.f64")
        return builder.call(fn, args)

    return sig, codegen


@nb.njit(cache=True)
def _dot2(a0, a1, b0, b1):  # pragma: no cover - compiled
    """a0 b0 + a1 b1 as NumPy's matmul of 2-column matrices computes it (module doc)."""
    return _fma(a1, b1, a0 * b0)


@nb.njit(cache=True)
def gains2(P_pred, ti, S_inv):  # pragma: no cover - compiled
    """Gains ``K_g = P-_t H^T S_g^-1`` and products ``K_g H P-_t`` for 2-D measurements (H = [I 0]), as NumPy does.

    Parameters
    ----------
    P_pred : ndarray, shape (n, r, d, d)
        Predicted covariances.
    ti : ndarray of int, shape (G,)
        Track of each gated pair.
    S_inv : ndarray, shape (G, r, 2, 2)
        Inverse innovation covariances of the pairs.

    Returns
    -------
    K : ndarray, shape (G, r, d, 2)
        Gains.
    KHP : ndarray, shape (G, r, d, d)
        ``K H P-``.
    """
    r, d = P_pred.shape[1], P_pred.shape[2]
    G = len(ti)
    K = np.empty((G, r, d, 2))
    KHP = np.empty((G, r, d, d))
    for g in range(G):
        t = ti[g]
        for q in range(r):
            for i in range(d):
                for j in range(2):
                    K[g, q, i, j] = _dot2(P_pred[t, q, i, 0], P_pred[t, q, i, 1], S_inv[g, q, 0, j], S_inv[g, q, 1, j])
            for i in range(d):
                for j in range(d):
                    KHP[g, q, i, j] = _dot2(K[g, q, i, 0], K[g, q, i, 1], P_pred[t, q, j, 0], P_pred[t, q, j, 1])
    return K, KHP


@nb.njit(cache=True)
def _pair_sums(P_pred, beta_pair, ti, K, KHP, nu):  # pragma: no cover - compiled
    """sum_g beta_g dx_g (n, r, d) and sum_g beta_g (P- - K H P- + dx_g dx_g^T) (n, r, d, d) per track;
    ``beta_pair (G, r)`` the weights of the gated pairs."""
    n, r, d = P_pred.shape[0], P_pred.shape[1], P_pred.shape[2]
    k = nu.shape[2]
    acc_x = np.zeros((n, r, d))
    acc_P = np.zeros((n, r, d, d))
    dx = np.empty(d)
    for g in range(len(ti)):
        t = ti[g]
        for q in range(r):
            b = beta_pair[g, q]
            for i in range(d):
                s = 0.0  # the reference's einsum sums into a zeroed output
                for j in range(k):
                    s += K[g, q, i, j] * nu[g, q, j]
                dx[i] = s
                acc_x[t, q, i] += b * s
            for i in range(d):
                for j in range(d):
                    acc_P[t, q, i, j] += ((P_pred[t, q, i, j] - KHP[g, q, i, j]) + dx[i] * dx[j]) * b
    return acc_x, acc_P


@nb.njit(cache=True)
def _gain_row(P_t, i, s00, s01, s10, s11, n0, n1):  # pragma: no cover - compiled
    """Row i of K = P-_t H^T S^-1 (as :func:`gains2`) and dx_i = (K nu)_i summed from 0 (as the reference's einsum)."""
    k0 = _dot2(P_t[i, 0], P_t[i, 1], s00, s10)
    k1 = _dot2(P_t[i, 0], P_t[i, 1], s01, s11)
    s = 0.0
    s += k0 * n0
    s += k1 * n1
    return k0, k1, s


@nb.njit(cache=True)
def _pair_sums_cv2(P_pred, beta_pair, ti, S_inv, nu):  # pragma: no cover - compiled
    """:func:`_pair_sums` for a 4-D state and 2-D measurements (the position tracker) with K_g and K_g H P-_t
    computed in the loop (as :func:`gains2`), in registers: no (G, r, d, d) array is written and read back."""
    n, r = P_pred.shape[0], P_pred.shape[1]
    acc_x = np.zeros((n, r, 4))
    acc_P = np.zeros((n, r, 4, 4))
    for g in range(len(ti)):
        t = ti[g]
        for q in range(r):
            b = beta_pair[g, q]
            s00, s01, s10, s11 = S_inv[g, q, 0, 0], S_inv[g, q, 0, 1], S_inv[g, q, 1, 0], S_inv[g, q, 1, 1]
            n0, n1 = nu[g, q, 0], nu[g, q, 1]
            P_t = P_pred[t, q]
            K = (_gain_row(P_t, 0, s00, s01, s10, s11, n0, n1), _gain_row(P_t, 1, s00, s01, s10, s11, n0, n1),
                 _gain_row(P_t, 2, s00, s01, s10, s11, n0, n1), _gain_row(P_t, 3, s00, s01, s10, s11, n0, n1))
            ax, aP = acc_x[t, q], acc_P[t, q]
            for i in range(4):
                ki0, ki1, dxi = K[i]
                ax[i] += b * dxi
                for j in range(4):
                    khp = _dot2(ki0, ki1, P_t[j, 0], P_t[j, 1])
                    aP[i, j] += ((P_t[i, j] - khp) + dxi * K[j][2]) * b
    return acc_x, acc_P


@nb.njit(cache=True)
def _pair_sums_k1(P_pred, beta_pair, ti, S_inv, nu):  # pragma: no cover - compiled
    """:func:`_pair_sums` for scalar measurements (the bearing tracker) with K_g = P-_t H^T s_g and K_g H P-_t
    computed in the loop: with one measurement dimension each of their entries is a single product, which is what
    NumPy's matmul gives, so the sums are the general path's bit for bit (without its gathers and temporaries)."""
    n, r, d = P_pred.shape[0], P_pred.shape[1], P_pred.shape[2]
    acc_x = np.zeros((n, r, d))
    acc_P = np.zeros((n, r, d, d))
    gain, dx = np.empty(d), np.empty(d)
    for g in range(len(ti)):
        t = ti[g]
        for q in range(r):
            b, s_inv, v = beta_pair[g, q], S_inv[g, q, 0, 0], nu[g, q, 0]
            for i in range(d):
                gain[i] = P_pred[t, q, i, 0] * s_inv
                s = 0.0  # as _pair_sums: the reference's einsum sums into a zeroed output
                s += gain[i] * v
                dx[i] = s
                acc_x[t, q, i] += b * s
            for i in range(d):
                for j in range(d):
                    acc_P[t, q, i, j] += ((P_pred[t, q, i, j] - gain[i] * P_pred[t, q, j, 0]) + dx[i] * dx[j]) * b
    return acc_x, acc_P


@nb.njit(cache=True)
def _combine(x_pred, P_pred, beta0, acc_x, acc_P):  # pragma: no cover - compiled
    """x = x- + acc_x;  P = sym(beta_0 P- + acc_P - acc_x acc_x^T), sym(A) = (A + A^T) / 2."""
    n, r, d = x_pred.shape
    x = np.empty((n, r, d))
    P = np.empty((n, r, d, d))
    A = np.empty((d, d))
    for t in range(n):
        for q in range(r):
            for i in range(d):
                x[t, q, i] = x_pred[t, q, i] + acc_x[t, q, i]
                for j in range(d):
                    A[i, j] = (beta0[t, q] * P_pred[t, q, i, j] + acc_P[t, q, i, j]) - acc_x[t, q, i] * acc_x[t, q, j]
            for i in range(d):
                for j in range(d):
                    P[t, q, i, j] = 0.5 * (A[i, j] + A[j, i])
    return x, P


@nb.njit(cache=True)
def _block_sums(col, val, a, b, lo, n, acc, res):  # pragma: no cover - compiled
    """NumPy's sums (into ``res (r,)``) of a dense block [lo, lo + n), n <= 128, whose only non-zero entries are
    ``val[a:b]`` (G, r) at the (increasing) columns ``col[a:b]``: one by one below 8 entries, else 8 interleaved
    accumulators (``acc (8, r)``) over the first n - n % 8 entries, combined pairwise, then the rest one by
    one (numpy's ``pairwise_sum``); every mode at once."""
    r = val.shape[1]
    res[:] = 0.0
    p = a
    if n >= 8:
        acc[:] = 0.0
        top = lo + n - n % 8
        while p < b and col[p] < top:
            for q in range(r):
                acc[(col[p] - lo) % 8, q] += val[p, q]
            p += 1
        for q in range(r):
            low4 = (acc[0, q] + acc[1, q]) + (acc[2, q] + acc[3, q])
            res[q] = low4 + ((acc[4, q] + acc[5, q]) + (acc[6, q] + acc[7, q]))
    while p < b:  # below 8 entries all of them, else the rest
        for q in range(r):
            res[q] += val[p, q]
        p += 1


@nb.njit(cache=True)
def _push(frames, depth, col, lo, n, a, b):  # pragma: no cover - compiled
    """A new segment [lo, lo + n) with non-zero entries a:b at ``depth`` of the stack, not yet started, and where
    its entries split between the halves [lo, lo + n2) and the rest (n2 = n // 2 rounded down to a multiple of 8)."""
    n2 = n // 2
    n2 -= n2 % 8
    split = a
    while split < b and col[split] < lo + n2:
        split += 1
    frames[depth, 0], frames[depth, 1], frames[depth, 2], frames[depth, 3] = lo, n, a, b
    frames[depth, 4], frames[depth, 5], frames[depth, 6] = 0, n2, split


@nb.njit(cache=True)
def _pairwise(col, val, a, b, m, frames, left, acc, ret):  # pragma: no cover - compiled
    """NumPy's pairwise sums (into ``ret (r,)``) of the dense rows of m entries whose only non-zero entries are
    ``val[a:b]`` (G, r) at the (increasing) columns ``col[a:b]``: rows longer than 128 are split at n2 (:func:`_push`)
    and summed as sum(first n2) + sum(rest). Written with an explicit stack (numba cannot cache a recursive
    function): ``frames (depth, 7)`` holds lo, n, a, b, stage, n2, split of each pending segment, ``left (depth, r)``
    its left sums."""
    _push(frames, 0, col, 0, m, a, b)
    depth = 0
    while depth >= 0:
        lo, n, a, b, stage, n2, split = frames[depth]
        if stage == 0 and (a == b or n <= 128):
            if a < b:
                _block_sums(col, val, a, b, lo, n, acc, ret)
            else:
                ret[:] = 0.0
            depth -= 1
        elif stage == 0:  # first the left half
            frames[depth, 4] = 1
            depth += 1
            _push(frames, depth, col, lo, n2, a, split)
        elif stage == 1:  # then the right half
            left[depth] = ret
            frames[depth, 4] = 2
            depth += 1
            _push(frames, depth, col, lo + n2, n - n2, split, b)
        else:
            ret[:] = left[depth] + ret
            depth -= 1


@nb.njit(cache=True)
def dense_row_sums(pair_track, pair_meas, val, n, m):  # pragma: no cover - compiled
    """Row sums of the dense (n, r, m) array that is ``val`` at the gated pairs and 0 elsewhere, bit for bit.

    Equal to ``dense.sum(axis=-1)`` (NumPy's pairwise summation; module docstring) without forming it.

    Parameters
    ----------
    pair_track, pair_meas : ndarray of int, shape (G,)
        The gated pairs, in row-major (track, measurement) order.
    val : ndarray, shape (G, r)
        Values at the pairs (e.g. p_rm / rho_m).
    n, m : int
        Tracks and measurements.

    Returns
    -------
    ndarray, shape (n, r)
        Sums over the measurements.
    """
    r = val.shape[1]
    out = np.zeros((n, r))
    frames = np.empty((64, 7), np.int64)  # depth <= log2(m / 64): 64 levels hold any row
    left, acc, ret = np.empty((64, r)), np.empty((8, r)), np.empty(r)
    g, G = 0, len(pair_track)
    while g < G:
        e = g
        while e < G and pair_track[e] == pair_track[g]:
            e += 1
        _pairwise(pair_meas, val, g, e, m, frames, left, acc, ret)
        for q in range(r):
            out[pair_track[g], q] = 0.0 + ret[q]  # numpy's reduction starts from 0
        g = e
    return out


@functools.cache
def gains_match_numpy() -> bool:
    """Whether :func:`gains2` gives NumPy's ``P H^T @ S^-1`` and ``K @ H P`` bit for bit on this machine.

    Checked once per process on random matrices (module docstring).

    Returns
    -------
    bool
        True if the compiled products can be used.
    """
    rng = np.random.default_rng(0)
    A = rng.normal(size=(256, 2, 4, 4))
    P = A @ np.swapaxes(A, -1, -2)
    B = rng.normal(size=(256, 2, 2, 2))
    S_inv = B @ np.swapaxes(B, -1, -2)
    ti = np.arange(256)
    K, KHP = gains2(P, ti, S_inv)
    K_np = P[..., :, :2] @ S_inv
    return bool(np.array_equal(K, K_np) and np.array_equal(KHP, K_np @ np.swapaxes(P[..., :, :2], -1, -2)))


def pda_mixture_update_fast(x_pred, P_pred, lik: Likelihoods, beta0, beta):
    """``pda_mixture_update`` (association/pda.py) with the sums compiled: same arguments, identical results.

    Parameters
    ----------
    x_pred : ndarray, shape (n, r, d)
        Predicted mode-conditioned states.
    P_pred : ndarray, shape (n, r, d, d)
        Their covariances.
    lik : Likelihoods
        The gated pairs' innovations and inverse innovation covariances.
    beta0 : ndarray, shape (n, r)
        Weight of "no measurement is the target's".
    beta : ndarray, shape (n, r, m)
        Weight of each measurement (zero outside the gate).

    Returns
    -------
    x : ndarray, shape (n, r, d)
        Updated states.
    P : ndarray, shape (n, r, d, d)
        Updated covariances (symmetrised).
    """
    if lik.gated.shape[1] == 0:
        return x_pred.copy(), P_pred.copy()
    return pda_mixture_update_pairs(x_pred, P_pred, lik, beta0, beta[lik.pair_track, :, lik.pair_meas])


def pda_mixture_update_pairs(x_pred, P_pred, lik: Likelihoods, beta0, beta_pair):
    """:func:`pda_mixture_update_fast` with the weights of the gated pairs only.

    Parameters
    ----------
    beta_pair : ndarray, shape (G, r)
        Weights of the gated pairs (``beta[lik.pair_track, :, lik.pair_meas]``).
    x_pred, P_pred, lik, beta0
        As :func:`pda_mixture_update_fast`.

    Returns
    -------
    x, P : ndarray
        As :func:`pda_mixture_update_fast`.
    """
    k = lik.nu.shape[-1]
    ti = np.ascontiguousarray(lik.pair_track, dtype=np.int64)  # one layout, one compiled specialisation
    if lik.gated.shape[1] == 0:
        return x_pred.copy(), P_pred.copy()
    if not len(ti):
        return x_pred.copy(), symmetrize(beta0[..., None, None] * P_pred)
    P_pred = np.ascontiguousarray(P_pred, dtype=float)
    beta0, beta_pair = np.ascontiguousarray(beta0, dtype=float), np.ascontiguousarray(beta_pair, dtype=float)
    if k == 2 and P_pred.shape[-1] == 4 and gains_match_numpy():
        acc_x, acc_P = _pair_sums_cv2(P_pred, beta_pair, ti, np.ascontiguousarray(lik.S_inv), lik.nu)
    elif k == 1:
        acc_x, acc_P = _pair_sums_k1(P_pred, beta_pair, ti, np.ascontiguousarray(lik.S_inv), lik.nu)
    else:
        PHt = P_pred[ti][..., :, :k]  # P H^T for H = [I 0], per pair (G, r, d, k)
        K = PHt @ lik.S_inv
        KHP = K @ np.swapaxes(PHt, -1, -2)
        acc_x, acc_P = _pair_sums(P_pred, beta_pair, ti, K, KHP, lik.nu)
    return _combine(x_pred, P_pred, beta0, acc_x, acc_P)
