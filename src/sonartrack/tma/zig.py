"""Zig detection: change points in a target's motion found from its bearings by a sequential generalised
likelihood-ratio test of constant velocity against a velocity change at an unknown time.

Test. On a window of bearings z_1..z_m (times t_i, ownship o_i, noise sd sigma_i) the null H0 is constant
velocity (tma/batch_ml.py, X0 = [x, y, vx, vy]); the alternative H1(tau) adds a velocity change dv at time tau,
p(t) = p_CV(t) + dv (t - tau)+. With the noise sd known,

    GLR(tau) = 2 (log L_1(tau) - log L_0) = C_0 - C_1(tau),      GLR* = max_tau GLR(tau)

(C the chi-square cost). At every tested bearing GLR(tau) is evaluated for all tau at once in its
Gauss-Newton (score) form about the CV ML fit: with e the whitened residuals, G the whitened CV Jacobian,
P = I - Q Q^T the projector off G's column space (Q from its SVD, so that a window whose range the bearings do
not see, rank G = 3, is handled), and B(tau) = [(t_i - tau)+ g_i] (n x 2; g_i = dh_i/dp / sigma_i),

    GLR(tau) ~= (B^T P e)^T (B^T P B)^-1 (B^T P e)      (Rao's score statistic; Kay 1998, Fundamentals of
                                                           Statistical Signal Processing II, sec. 6.6)

which is chi-square(2) under H0 for each tau and equals the GLR for small changes. Its sums over i > tau are
suffix cumulative sums, so the whole profile costs O(m) (vectorised; no loop over tau). Since
(t - tau)+ = (t - tau) + (tau - t)+ and (t - tau) g lies in G's span, P B(tau) = P [(tau - t_i)+ g_i]: the
sums over i < tau give the same statistic, and each tau uses the shorter side (less cancellation).

Sequential use. The test runs as the record grows, at a bearing at least ``test_every_s`` (:data:`TEST_EVERY_S`,
10 s) after the last bearing it ran at, over the bearings since the start of the current leg, at most ``window_s``
back; tau ranges over the bearing times leaving >= ``min_before`` bearings and >= ``min_before_s`` (30 s) of the
window before it and >= ``min_after`` bearings and >= ``min_after_s`` (30 s) after it. Why in seconds: a candidate
with only two bearings after it tests those two bearings alone, a fresh chi-square(2) at every bearing, so with
bearings every 2 s the number of nearly independent tests per hour, and the false-alarm rate at a given threshold,
grew as the bearings got denser; with the spans and the test's cadence in seconds the statistic is a functional of
the record in time, the same however densely it is sampled (and 2-s bearings cost a fifth of the fits). The score
form screens; where it crosses the threshold h the test is confirmed on the window by the GLR itself: the CV ML
re-fitted from many cold starts (a warm start can stop a few units of chi-square above the minimum, e.g. slid out
along a range the window does not see, and the two-leg model, with two more parameters, then finds the basin: a
false zig; measured on the study's scenes) and the full (nonlinear) two-leg profile of tma/legs.py's model
(:func:`change_time_profile`, here), GLR(tau) = C_0 - C_1(tau). A zig is declared when its maximum exceeds h;
the detection time is that bearing's. tau_hat = argmax GLR(tau), and the zig's interval is
{tau : GLR(tau) >= GLR(tau_hat) - 3.84} (the chi-square(1) 95 % profile-likelihood interval).
The test restarts after the change's interval (segmentation): the next leg's window starts after the interval's
end, so that it holds the new leg's bearings between the change and its detection. (It restarted at the detection
until session 9; the next leg then lost those bearings, its constant-velocity fit before the next zig was short
and absorbed most of that zig: of the study's 7 detectable zigs found late or never at trial version 7, four are
found within 120 s since.) The legs
are then fitted jointly over the whole record with the change times refined
(:func:`~sonartrack.tma.legs.fit_legs`), and each zig's time and interval are read again from the two-leg
profile of all the bearings between its neighbours' change times: the reported zig is the one that uses all
the record, its ``detected_s`` the sequential test's.

Threshold. GLR* is a maximum over correlated chi-square(2) variables, and successive tests share most of their
bearings, so neither chi-square(2) nor a Bonferroni bound gives the false-alarm rate. We use the tail form of
the maximum of a smooth chi-square(2) process (a power of the level times the chi-square(2) tail exp(-h / 2);
Adler 1981, The Geometry of Random Fields, ch. 6; Siegmund 1985, Sequential Analysis, ch. IV), with its scale
measured by Monte Carlo for each bearing interval:

    false zigs per hour of constant-velocity motion = K(dt) (h / 2)^2 exp(-h / 2)

(dt the median bearing interval), so that h solves h / 2 = ln(K(dt) / rate) + 2 ln(h / 2). K is a table
(:data:`TAIL_SCALE_PER_H`, interpolated in log dt and log K, held at its ends; :func:`tail_scale_per_hour`)
made by benchmarks/calibrate_zig_threshold.py: the manoeuvring-target study's scene family with every target at
constant velocity (5-20 km, 4-15 kn, ownship on leg-turn-leg, zig-zag or constant-turn patterns, 60-90 min),
bearings every dt exactly with the line array's noise law (sigma_base / max(|sin cone|, 0.05), sigma_base
0.5-1 deg), about 25 h of records per dt, the sequential test at h = 9, 12, 15 and 18; K is the Poisson ML of one
scale over the four thresholds (false zigs / (hours x sum of (h / 2)^2 exp(-h / 2))), with the Garwood 95 %
interval of the count:

    dt    false zigs at h = 9 / 12 / 15 / 18 in hours    K (1/h)
    2 s   103 / 38 / 13 / 4 in 25.8 h                    17.2 [14.7, 20.1]
    5 s   91 / 34 / 13 / 5 in 25.4 h                     15.8 [13.3, 18.7]
    10 s  72 / 30 / 10 / 3 in 25.6 h                     12.7 [10.4, 15.2]
    30 s  27 / 8 / 4 / 1 in 25.2 h                       4.47 [3.19, 6.08]
    60 s  16 / 7 / 2 / 1 in 26.0 h                       2.82 [1.84, 4.12]

(session 10, on the detector as it is; about 11 min of CPU, 29 min on two loaded shared cores). The form's fall with
h holds over h = 9-18 to the counts' Poisson error (at 2 s K gives 100 / 40 / 14 / 4.5 against 103 / 38 / 13 / 4; at
5 s 90 / 36 / 12.5 / 4.0 against 91 / 34 / 13 / 5). The table before (trial version 8; about 12.5 h per dt at h = 9,
12, 15, measured before a crossing's CV refit from many starts) was 19.3, 16.6, 12.9, 4.83, 1.57: 2-12 % high at
2-30 s (thresholds a little conservative, 0.03-0.23 in h) and 44 % low at 60 s, where its 7 events were too few (26
now, at h = 9-18 in 26 h). K levels off below 10 s (the test's cadence) and falls beyond it (fewer tests per hour,
and >= 2 bearings after tau is then more than 30 s). The old form, p = 0.0085 sqrt(dt) (h / 2)^2 exp(-h / 2) per
bearing fitted at 20-60 s, is K = 30.6 / sqrt(dt): 21.6 at 2 s, 9.7 at 10 s, 3.95 at 60 s. The operating point is h
~ 20, beyond the calibrated range: the tail there is the form's extrapolation (with 4-5 events at h = 18 it still
holds), which the margin below is for (heavier tails where the bearings-only likelihood is far from quadratic:
close, fast-crossing targets). The rate holds only with the right bearing sd: a sd stated too small inflates every
GLR.

Operating point. The default stated rate is :data:`DEFAULT_FALSE_ALARM_PER_HOUR` = 0.05 per hour, half the
requirement of at most 1 false zig per 10 h (issue 30). The threshold at 0.05 per hour is h = 21.1 with bearings
every 2 s, 20.4 at 10 s, 17.7 at 30 s, 16.5 at 60 s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.angles import wrap_angle
from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import bearing_model, ml_bearings_only, pseudo_linear_estimate
from sonartrack.tma.legs import (
    MIN_BEARINGS_PER_LEG,
    LegFit,
    _lm,
    _residual_fn,
    checked_bearings,
    fit_legs,
    pseudo_linear_legs,
)
from sonartrack.tma.missed_zig import MISSED_ZIG_DV_SD_MPS, with_missed_zig

#: the calibration table of the threshold's tail form, false zigs per hour = K(dt) (h / 2)^2 exp(-h / 2) (module
#: doc): (median bearing interval dt in s, K in 1/h), measured by benchmarks/calibrate_zig_threshold.py
TAIL_SCALE_PER_H = ((2.0, 17.2), (5.0, 15.8), (10.0, 12.7), (30.0, 4.47), (60.0, 2.82))
#: least time (s) between a candidate change time and the window's first bearing, and its last (module doc)
MIN_BEFORE_S = 30.0
MIN_AFTER_S = 30.0
#: the test runs at a bearing at least this long (s) after the last bearing it ran at (module doc): with denser
#: bearings the number of tests per hour, and so the false-alarm rate per hour at a given threshold, stays put
TEST_EVERY_S = 10.0
#: the stated false zigs per hour of constant-velocity motion by default (module doc: operating point)
DEFAULT_FALSE_ALARM_PER_HOUR = 0.05
#: the chi-square(1) 95 % quantile: a zig's time interval is the set of tau whose GLR is within it of the maximum
CHI2_1_95 = 3.841458820694124


@dataclass(frozen=True, slots=True)
class Zig:
    """One detected change of the target's velocity: its estimated time, the profile-likelihood interval of that
    time, the bearing time at which the test first crossed its threshold, and the GLR (nonlinear) there."""

    time_s: float
    interval_s: tuple[float, float]
    detected_s: float
    glr: float


@dataclass(frozen=True, slots=True)
class ZigReport:
    """The zigs found in a record, its legs (None with ``message`` when they could not be fitted), the threshold
    used, and the sequential statistic GLR* at each bearing (NaN where not tested)."""

    zigs: tuple[Zig, ...]
    legs: LegFit | None
    threshold: float
    false_alarm_per_hour: float
    statistic: np.ndarray
    message: str


def tail_scale_per_hour(bearing_interval_s: float) -> float:
    """K(dt) of the threshold's tail form (module doc): :data:`TAIL_SCALE_PER_H` interpolated linearly in log dt and
    log K, held at its ends (below 2 s the test still runs every :data:`TEST_EVERY_S`; above 60 s fewer tests per
    hour only lower the rate, so the 60 s value is conservative).

    Parameters
    ----------
    bearing_interval_s : float
        Typical (median) time between bearings (s, > 0).

    Returns
    -------
    float
        K (false zigs per hour).
    """
    dt, k = (np.log(np.array(col)) for col in zip(*TAIL_SCALE_PER_H, strict=True))
    return float(np.exp(np.interp(np.log(bearing_interval_s), dt, k)))


def glr_threshold(false_alarm_per_hour: float, bearing_interval_s: float) -> float:
    """The threshold h on GLR* for a false-alarm rate (module doc): h / 2 = ln(K(dt) / rate) + 2 ln(h / 2).

    Parameters
    ----------
    false_alarm_per_hour : float
        False zigs per hour of constant-velocity motion (> 0).
    bearing_interval_s : float
        Typical (median) time between bearings (s).

    Returns
    -------
    float
        h.
    """
    require(false_alarm_per_hour > 0 and bearing_interval_s > 0,
            f"false_alarm_per_hour {false_alarm_per_hour:g} and the bearing interval {bearing_interval_s:g} s must be "
            "positive")
    level = np.log(tail_scale_per_hour(bearing_interval_s) / false_alarm_per_hour)
    require(level > 0.7, f"false_alarm_per_hour {false_alarm_per_hour:g} with bearings every {bearing_interval_s:g} s "
                         "is too high to set a threshold for (the tail form holds for small rates): lower it")
    half = max(level, 3.0)
    for _ in range(100):  # h / 2 = level + 2 ln(h / 2): a contraction for h / 2 > 2
        half = level + 2.0 * np.log(half)
    return float(2.0 * half)


def _suffix(x):
    """sum_{i > j} x_i for each j (axis 0)."""
    cs = np.cumsum(x[::-1], axis=0)[::-1]
    return np.concatenate([cs[1:], np.zeros_like(cs[:1])])


def _prefix(x):
    """sum_{i < j} x_i for each j (axis 0)."""
    cs = np.cumsum(x, axis=0)
    return np.concatenate([np.zeros_like(cs[:1]), cs[:-1]])


def _one_sided(tau, ts, g, e, Q, sums):
    """s = B^T P e and M = B^T P B for B = (+-(t - tau))+ g on one side, from cumulative ``sums`` (module doc)."""
    e1 = g * e[:, None]
    S0, S1 = sums(e1), sums(ts[:, None] * e1)
    gg = g[:, :, None] * g[:, None, :]
    T0, T1, T2 = sums(gg), sums(ts[:, None, None] * gg), sums(ts[:, None, None] ** 2 * gg)
    qg = Q[:, :, None] * g[:, None, :]
    U0, U1 = sums(qg), sums(ts[:, None, None] * qg)
    tc, tm = tau[:, None], tau[:, None, None]
    s = S1 - tc * S0
    QB = U1 - tm * U0
    M = T2 - 2.0 * tm * T1 + tm**2 * T0 - np.swapaxes(QB, 1, 2) @ QB
    return s, M


def score_profile(time_s, residual, G, min_before: int = 4, min_after: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """GLR(tau) in score form at tau = each bearing time (module doc), all tau at once.

    Parameters
    ----------
    time_s : ndarray, shape (m,)
        Bearing times (s), increasing.
    residual : ndarray, shape (m,)
        Whitened residuals wrap(z - h) / sigma of the CV ML fit.
    G : ndarray, shape (m, 4)
        Whitened CV Jacobian H / sigma (tma/batch_ml.py :func:`~sonartrack.tma.batch_ml.bearing_model`); its first
        two columns are g_i = dh_i/dp / sigma_i.
    min_before, min_after : int
        Least number of bearings at or before tau and after it.

    Returns
    -------
    tau_s : ndarray, shape (k,)
        The candidate change times (s).
    glr : ndarray, shape (k,)
        The statistic at each.
    """
    t = np.asarray(time_s, dtype=float)
    m = len(t)
    U, sv, _ = np.linalg.svd(G, full_matrices=False)
    Q = U[:, sv > sv[0] * 1e-9]
    e = residual - Q @ (Q.T @ residual)
    span = max(t[-1] - t[0], 1e-9)
    ts = (t - t[-1]) / span  # a shift and scale of time leave the statistic unchanged; this keeps the sums tame
    g = G[:, :2]
    s_suf, M_suf = _one_sided(ts, ts, g, e, Q, _suffix)
    s_pre, M_pre = _one_sided(ts, ts, g, e, Q, _prefix)
    use_pre = (np.arange(m) < (m - 1) / 2.0)  # fewer bearings before tau than after: sum over the shorter side
    s = np.where(use_pre[:, None], s_pre, s_suf)
    M = np.where(use_pre[:, None, None], M_pre, M_suf)
    det = M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]
    quad = s[:, 0] ** 2 * M[:, 1, 1] - 2.0 * s[:, 0] * s[:, 1] * M[:, 0, 1] + s[:, 1] ** 2 * M[:, 0, 0]
    scale = np.maximum(M[:, 0, 0] * M[:, 1, 1], 1e-300)
    with np.errstate(invalid="ignore", divide="ignore"):
        glr = np.where(det > 1e-10 * scale, quad / det, 0.0)
    keep = slice(min_before - 1, m - min_after)
    return t[keep], np.maximum(glr[keep], 0.0)


def _window_fit(z, t, own, sig, x_init, thorough: bool = False):
    """The CV ML on one window and its whitened residuals and Jacobian. Warm-started from the previous window's
    fit; where that lands at a cost the chi-square(m) distribution does not allow (a start whose range the last
    window left loose can slide along the flat valley through the ownship onto the mirror track), from the
    pseudo-linear estimate, then from a target at rest 10 km out on the first bearing (the pseudo-linear
    estimate can be the ownship's own track, tma/legs.py), keeping the lowest cost. ``thorough`` (a crossing being
    confirmed): every start, and targets at rest 2, 5, 20 and 40 km out too, since a CV fit stuck a few units of
    chi-square above its minimum (a plausible cost; e.g. slid out along a range the window does not see) is a false
    zig once the two-leg model, with its two more parameters, finds the basin."""
    tau = t - t[0]
    ranges_m = (10_000.0, 2_000.0, 5_000.0, 20_000.0, 40_000.0) if thorough else (10_000.0,)
    starts = [lambda: pseudo_linear_estimate(z, tau, own)]
    starts += [lambda r=r: np.r_[own[0] + r * np.array([np.sin(z[0]), np.cos(z[0])]), 0.0, 0.0] for r in ranges_m]
    if x_init is not None and np.all(np.isfinite(x_init)):
        starts.insert(0, lambda: x_init)
    best = None
    for start in starts:  # made only when needed
        x0 = start()
        with np.errstate(invalid="ignore", divide="ignore"):  # a start on the ownship's track: r = 0, cost inf
            est = ml_bearings_only(z, t, own, sig, x_init=x0, max_iter=30, tol=1e-8, check=False)
        if best is None or est.objective < best.objective:
            best = est
        if not thorough and best.objective < len(z) + 5.0 * np.sqrt(2.0 * len(z)) + 10.0:
            break
    h, H, _ = bearing_model(best.x0, tau, own)
    return best.x0, wrap_angle(z - h) / sig, H / sig[:, None]


def cv_window_cost(time_s, bearing_rad, own_xy_m, sigma_rad, x_init=None) -> float:
    """The constant-velocity ML's chi-square cost on a stretch of bearings, from every start the test's confirmation
    uses (and ``x_init``, [x, y, vx, vy] at the first bearing, if given). On the noise-free bearings of a target
    that changed velocity once in the stretch it is the GLR's noncentrality for a test at the true change time (the
    two-leg model fits them exactly; Kay 1998, Fundamentals of Statistical Signal Processing II, sec. 6.5: the
    noncentrality of the GLR is its value on noise-free data), which, unlike the linearised dv^T B^T P B dv, counts
    what the constant-velocity model's nonlinear range freedom absorbs.

    Parameters
    ----------
    time_s, bearing_rad, own_xy_m, sigma_rad
        The stretch, as :func:`change_time_profile`.
    x_init : array_like (4,) or None
        An extra start.

    Returns
    -------
    float
        The lowest cost found.
    """
    t, z, own = (np.asarray(a, dtype=float) for a in (time_s, bearing_rad, own_xy_m))
    sig = np.broadcast_to(np.asarray(sigma_rad, dtype=float), t.shape)
    _, e, _ = _window_fit(z, t, own, sig, None if x_init is None else np.asarray(x_init, float), thorough=True)
    return float(e @ e)


def change_time_profile(time_s, bearing_rad, own_xy_m, sigma_rad, candidates_s, params_init=None) -> np.ndarray:
    """The two-leg ML cost C(c) (chi-square, module doc) at each candidate change time c: the profile over one
    change time that a zig's time interval is read from (tma/zig.py). theta is re-fitted at each candidate,
    warm-started from the previous one (in increasing order of c); where that cost is implausible (far above
    chi-square(n): a wrong basin), from ``params_init``, the pseudo-linear estimate and a far start as well.

    Parameters
    ----------
    time_s, bearing_rad : ndarray, shape (n,)
        Strictly increasing times (s) and bearings (rad).
    own_xy_m : ndarray, shape (n, 2)
        Ownship positions (m).
    sigma_rad : float or array_like, shape (n,)
        Bearing noise sd (rad).
    candidates_s : array_like, shape (m,)
        Increasing change times (s) strictly inside the record.
    params_init : array_like (6,) or None
        A reference start for theta (e.g. from a joint fit), tried where the warm start fails.

    Returns
    -------
    ndarray, shape (m,)
        C at each candidate (inf where the fit failed).
    """
    t, z, own = (np.asarray(a, dtype=float) for a in (time_s, bearing_rad, own_xy_m))
    sig = np.broadcast_to(np.asarray(sigma_rad, dtype=float), t.shape)
    cand = np.asarray(candidates_s, dtype=float)
    out = np.full(len(cand), np.inf)
    ref = None if params_init is None else np.asarray(params_init, dtype=float)
    theta = ref
    plausible = len(t) + 5.0 * np.sqrt(2.0 * len(t)) + 10.0  # far above chi-square(n): a wrong basin
    for i, ck in enumerate(cand):
        starts = [] if theta is None else [theta]
        starts += [] if ref is None else [ref]
        starts += [pseudo_linear_legs(z, t, own, t[0], [ck]),
                   np.r_[own[0] + 10_000.0 * np.array([np.sin(z[0]), np.cos(z[0])]), np.zeros(4)]]
        for start in starts:  # the warm start first; the others only while the cost is implausible
            th, _, _, cost, _, _ = _lm(_residual_fn(z, t, own, sig, t[0], [ck]), start.copy(), 15, 1e-7)
            if np.isfinite(cost) and cost < out[i]:
                out[i], theta = cost, th
            if out[i] < plausible:
                break
    return out


def _locate(z, t, own, sig, cost_cv: float, detected_s: float, near_s=None, params_init=None) -> Zig:
    """The zig's time and interval from the nonlinear two-leg profile (module doc) on the record ``t``, over the
    midpoints between bearings (those within ``near_s`` = (lo, hi) if given)."""
    mid = 0.5 * (t[1:] + t[:-1])[MIN_BEARINGS_PER_LEG - 1:len(t) - MIN_BEARINGS_PER_LEG]
    if near_s is not None:
        mid = mid[(mid >= near_s[0]) & (mid <= near_s[1])]
    profile = cost_cv - change_time_profile(t, z, own, sig, mid, params_init)
    best = int(np.argmax(profile))
    inside = mid[profile >= profile[best] - CHI2_1_95]
    return Zig(time_s=float(mid[best]), interval_s=(float(inside.min()), float(inside.max())),
               detected_s=float(detected_s), glr=float(profile[best]))


def _candidates(t, e, G, min_before: int, min_after: int, min_before_s: float, min_after_s: float):
    """The score profile (:func:`score_profile`) at the change times leaving at least ``min_before_s`` of the
    window before them and ``min_after_s`` after (module doc: spans in seconds keep the test's false-alarm rate per
    hour from growing as the bearings get denser)."""
    taus, score = score_profile(t, e, G, min_before, min_after)
    keep = (taus - t[0] >= min_before_s) & (t[-1] - taus >= min_after_s)
    return taus[keep], score[keep]


def _confirm(z, t, own, sig, x_warm, e_warm, G_warm, threshold: float, detected_s: float, spans):
    """A crossing of the screening statistic, checked: the CV ML re-fitted from many cold starts too (a warm start
    can stop in a worse local minimum, whose structured residuals look like a zig), then the nonlinear GLR profile
    over the change times whose score is within 10 of its maximum. Returns (zig or None, the better CV fit)."""
    x_cold, e_cold, G_cold = _window_fit(z, t, own, sig, x_warm, thorough=True)
    x, e, G = (x_cold, e_cold, G_cold) if e_cold @ e_cold < e_warm @ e_warm else (x_warm, e_warm, G_warm)
    taus, score = _candidates(t, e, G, *spans)
    if not len(score) or score.max() <= threshold:
        return None, x
    near = taus[score >= score.max() - 10.0]
    zig = _locate(z, t, own, sig, float(e @ e), detected_s, (near.min() - 1e-9, near.max() + t[-1] - t[-2]),
                  np.r_[x, x[2:]])  # the CV fit as two equal legs: a start in the right basin
    return (zig if zig.glr > threshold else None), x


def _refined_zigs(t, z, own, sig, zigs, legs: LegFit) -> tuple[Zig, ...]:
    """Each zig's time and interval again, from all the bearings between its neighbours' change times (the joint
    leg fit's): the two-leg profile of that stretch, within 900 s of the fitted time (module doc)."""
    change_times_s = legs.change_times_s
    edges = np.r_[t[0] - 1.0, change_times_s, t[-1] + 1.0]
    out = []
    for k, zig in enumerate(zigs):
        sel = (t > edges[k]) & (t < edges[k + 2])
        c = change_times_s[k]
        if sel.sum() < 2 * MIN_BEARINGS_PER_LEG + 6:  # too few bearings to profile: keep the sequential interval
            out.append(Zig(time_s=float(c), interval_s=zig.interval_s, detected_s=zig.detected_s, glr=zig.glr))
            continue
        ref = np.r_[legs.position_at(t[sel][:1])[0][0], legs.params[2 + 2 * k:6 + 2 * k]]  # this pair of legs
        located = _locate(z[sel], t[sel], own[sel], sig[sel], 0.0, zig.detected_s, (c - 900.0, c + 900.0), ref)
        lo, hi = located.interval_s  # the grid's interval, widened to hold the joint fit's time between its points
        out.append(Zig(time_s=float(c), interval_s=(min(lo, float(c)), max(hi, float(c))), detected_s=zig.detected_s,
                       glr=zig.glr))
    return tuple(out)


def sequential_glr(time_s, bearing_rad, own_xy_m, sigma_rad, threshold: float, *, window_s: float = 1800.0,
                   min_before: int = 4, min_after: int = 2, min_before_s: float = MIN_BEFORE_S,
                   min_after_s: float = MIN_AFTER_S, test_every_s: float = TEST_EVERY_S
                   ) -> tuple[np.ndarray, tuple[Zig, ...]]:
    """Run the test as the record grows (module doc): at each bearing, GLR* over the current leg's window; on a
    crossing, locate the zig and start the next leg at it.

    Parameters
    ----------
    time_s, bearing_rad, own_xy_m, sigma_rad
        The record: times (s), bearings (rad), ownship positions (m) and bearing noise sd (rad), as
        :func:`change_time_profile`.
    threshold : float
        h (:func:`glr_threshold`).
    window_s : float
        The longest stretch of bearings tested at once (s).
    min_before, min_after : int
        Least number of bearings of the window at or before a candidate change time, and after it.
    min_before_s, min_after_s : float
        Least time (s) from the window's first bearing to a candidate change time, and from it to the last bearing.
    test_every_s : float
        The test runs at a bearing at least this long after the one it last ran at (and at the last bearing).

    Returns
    -------
    statistic : ndarray, shape (n,)
        GLR* at each bearing (NaN where the window was too short to test).
    zigs : tuple of Zig
        In time order.
    """
    t, z, own = (np.asarray(a, dtype=float) for a in (time_s, bearing_rad, own_xy_m))
    sig = np.broadcast_to(np.asarray(sigma_rad, dtype=float), t.shape)
    stat = np.full(len(t), np.nan)
    zigs: list[Zig] = []
    seg, x_prev, t_prev, t_test = 0, None, None, -np.inf
    need, spans = max(min_before + min_after, 6), (min_before, min_after, min_before_s, min_after_s)
    for n in range(len(t)):
        w0 = max(seg, int(np.searchsorted(t, t[n] - window_s, side="left")))
        if n - w0 + 1 < need or (t[n] < t_test + test_every_s - 1e-6 and n < len(t) - 1):
            continue
        t_test = t[n]
        w = slice(w0, n + 1)
        x_init = None if x_prev is None else x_prev + np.r_[x_prev[2:] * (t[w0] - t_prev), 0.0, 0.0]
        x_prev, e, G = _window_fit(z[w], t[w], own[w], sig[w], x_init)
        t_prev = t[w0]
        if not (np.all(np.isfinite(e)) and np.all(np.isfinite(G))):  # a fit onto the ownship's track: no test here
            x_prev = None
            continue
        _, glr = _candidates(t[w], e, G, *spans)
        stat[n] = glr.max() if len(glr) else np.nan
        if stat[n] > threshold:
            zig, x_prev = _confirm(z[w], t[w], own[w], sig[w], x_prev, e, G, threshold, t[n], spans)
            if zig is not None:  # the next leg's test starts after the change's interval (module doc)
                zigs.append(zig)
                seg = int(np.searchsorted(t, zig.interval_s[1], side="right"))
                x_prev = None
    return stat, tuple(zigs)


def detect_zigs(time_s, bearing_rad, own_xy_m, sigma_rad, *,
                false_alarm_per_hour: float = DEFAULT_FALSE_ALARM_PER_HOUR,
                window_s: float = 1800.0, fit: bool = True,
                missed_zig_dv_sd_mps: float | None = MISSED_ZIG_DV_SD_MPS) -> ZigReport:
    """Find a target's zigs from its bearings and the ownship's positions, and fit its legs (module doc).

    Parameters
    ----------
    time_s, bearing_rad, own_xy_m
        Times (s), bearings (rad) and ownship positions (m), as :func:`~sonartrack.tma.legs.fit_legs`.
    sigma_rad : float or array_like, shape (n,)
        Bearing noise sd (rad): the test's false-alarm rate holds only if it is right (estimate it from the
        record's residuals when unknown).
    false_alarm_per_hour : float
        The stated rate of false zigs per hour of constant-velocity motion, which sets the threshold (default
        :data:`DEFAULT_FALSE_ALARM_PER_HOUR`, module doc).
    window_s : float
        The longest stretch of bearings tested at once (s).
    fit : bool
        Fit the legs over the whole record (tma/legs.py :func:`~sonartrack.tma.legs.fit_legs`, change times
        refined).
    missed_zig_dv_sd_mps : float or None
        The current leg's covariance widened for a zig the test may have missed, of this prior sd (m/s per axis;
        tma/missed_zig.py :func:`~sonartrack.tma.missed_zig.with_missed_zig`); None: the fit's own covariance.

    Returns
    -------
    ZigReport
        The zigs, the legs (or None and the reason), the threshold and the statistic at each bearing.
    """
    t, z, own, sig = checked_bearings(time_s, bearing_rad, own_xy_m, sigma_rad, "zig detection needs at least 8 "
                                      "bearings with times and ownship positions (n, 2)", min_n=8)
    require(window_s > 0, f"window_s must be positive, got {window_s:g}")
    h = glr_threshold(false_alarm_per_hour, float(np.median(np.diff(t))))
    stat, zigs = sequential_glr(t, z, own, sig, h, window_s=window_s)
    legs, message = None, "no zig" if not zigs else ""
    if fit:
        try:
            legs = fit_legs(t, z, own, sig, [zg.time_s for zg in zigs], refine=True)
            zigs = _refined_zigs(t, z, own, sig, zigs, legs)
            if missed_zig_dv_sd_mps:
                legs = with_missed_zig(legs, t, own, sig, h, dv_sd_mps=missed_zig_dv_sd_mps)
        except InputError as err:
            message = f"legs not fitted: {err}"
    return ZigReport(zigs=zigs, legs=legs, threshold=h, false_alarm_per_hour=float(false_alarm_per_hour),
                     statistic=stat, message=message)
