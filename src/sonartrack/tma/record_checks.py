"""Does a bearings record support a constant-velocity fit? The residual tests of a TMA fit, one mechanism for
``sonartrack tma`` (tma/record_verdict.py) and the passive chain (systems/passive/targets.py).

* :func:`residual_check` / :func:`residual_scale` -- the residuals' chi-square, and that of their block means with
  the lag-1 correlation inflation, against the noise the fit states; the variance factor that reconciles them;
* :func:`range_profile_rise` -- the profile likelihood of the final range: is the range's interval what the
  record supports, or is the likelihood flat towards far ranges?
* :func:`bearing_sd_estimate` -- the bearing noise sd measured from a fit's residuals, with its chi-square interval;
* :func:`whiteness_check` -- the motion model tested: residuals of a fit of the right model to independent
  bearings are white; a target that changed course or speed leaves a slow structure in the residuals of a
  constant-velocity fit, whatever the noise's scale (so the test needs no stated sd);
* :func:`residual_span` -- the time span the residuals point at (the largest standardised run).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.gaussian import chi2_quantile

#: a determined solution's whitened residuals, averaged over blocks of this length, must fit their stated noise
RESIDUAL_BLOCK_S = 30.0
#: ... at this significance (upper tail: residuals larger than stated make the interval too narrow)
RESIDUAL_ALPHA = 1e-3


@dataclass(frozen=True, slots=True)
class ResidualCheck:
    """The normalised residual test of a fit (:func:`residual_check`): each statistic, its degrees of freedom and
    the upper limit of its (1 - :data:`RESIDUAL_ALPHA`) interval; ``consistent`` when both lie below it."""

    chi2: float
    dof: int
    limit: float
    block_chi2: float
    block_dof: int
    block_limit: float
    block_s: float = RESIDUAL_BLOCK_S

    @property
    def consistent(self) -> bool:
        """Whether the residuals agree with the stated noise (both statistics within their intervals)."""
        return self.chi2 <= self.limit and self.block_chi2 <= self.block_limit

    def note(self) -> str:
        """One line on the test, for a warning.

        Returns
        -------
        str
            Both chi-square statistics with their degrees of freedom and limits.
        """
        return (f"residuals disagree with the stated bearing noise (chi-square {self.chi2:.0f} for {self.dof} "
                f"degrees of freedom, limit {self.limit:.0f}; {self.block_s:g} s block means {self.block_chi2:.0f}"
                f" for {self.block_dof}, limit {self.block_limit:.0f})")


def residual_check(time_s, residual_rad, sigma_rad: float, *, inflation: float = 1.0,
                   n_params: int = 4, block_s: float = RESIDUAL_BLOCK_S) -> ResidualCheck:
    """Do a fit's bearing residuals agree with the noise its covariance states?

    With w_i = e_i / sigma the whitened residuals of n bearings and a fit of p parameters,

        chi2 = sum_i w_i^2  ~  chi-square(n - p)                     (white noise of sd sigma)
        chi2_B = sum_b n_b mean_b(w)^2 / kappa  ~  chi-square(B)     (B blocks of RESIDUAL_BLOCK_S)

    the second for errors correlated from bearing to bearing, whose block means have variance kappa / n_b with
    kappa = (1 + rho) / (1 - rho) the covariance inflation the solution states (AR(1) errors; Bretherton et al.
    1999, J. Climate 12, eq. 31). A fit that left a slow structure in its residuals (a wrong track absorbing part of
    the data) fails the block test although its chi2 fits. Upper-tail limits at RESIDUAL_ALPHA
    (:func:`~sonartrack.core.gaussian.chi2_quantile`).

    Parameters
    ----------
    time_s : array_like (n,)
        Bearing times (s), increasing.
    residual_rad : array_like (n,)
        Measured minus fitted bearings (rad, wrapped).
    sigma_rad : float
        The bearing noise the fit states (rad).
    inflation : float
        kappa, the covariance inflation the fit states (1: none).
    n_params : int
        Parameters fitted (4: a constant-velocity track).
    block_s : float
        Length of the blocks (s; the passive chain's :data:`RESIDUAL_BLOCK_S`); blocks of fewer than 3 bearings
        are left out of the block test.

    Returns
    -------
    ResidualCheck
        The statistics and their limits.
    """
    t = np.asarray(time_s, float)
    w = np.asarray(residual_rad, float) / float(sigma_rad)
    dof = max(len(w) - n_params, 1)
    block = np.floor((t - t[0]) / block_s).astype(int)
    counts = np.bincount(block)
    sums = np.bincount(block, weights=w)
    full = counts >= 3
    block_chi2 = float(np.sum(sums[full] ** 2 / counts[full]) / inflation)
    b = max(int(full.sum()), 1)
    q = 1.0 - RESIDUAL_ALPHA
    return ResidualCheck(float(w @ w), dof, chi2_quantile(q, dof), block_chi2, b, chi2_quantile(q, b), block_s)


#: residuals whose measured variance exceeds the stated noise's (and its correlation inflation) this many times are
#: no noise but a wrong track (two ships joined): the range is then not determined rather than given with a
#: covariance inflated that much. A 1 deg pull over 60 s of a 300 s, 0.3 deg record measures ~ 29 (its 30 s block
#: means), and inflated by that the final position's NEES falls from 9-47 to 0.3-1.6
MAX_RESIDUAL_SCALE = 100.0


def residual_scale(check: ResidualCheck) -> float:
    """The variance factor s2 >= 1 that makes a fit's residuals agree with its stated noise: the larger of
    chi2 / dof and chi2_B / B (:func:`residual_check`), the measured scale of the residuals and of their block means
    against what the noise states (the usual ML rescaling by the reduced chi-square, Bevington & Robinson, Data
    Reduction and Error Analysis, 3rd ed., 2003, sec. 8.1; here also of the block means, for errors correlated over
    a block). Scaling sigma^2 by s2 brings both statistics to their expected values.

    Parameters
    ----------
    check : ResidualCheck
        The test's statistics.

    Returns
    -------
    float
        s2 (1 when both statistics are at most their degrees of freedom).
    """
    return max(1.0, check.chi2 / check.dof, check.block_chi2 / check.block_dof)


#: a determined range must tell the target from one this many times as far, or at the stated +3 sd if that is
#: farther: the profile likelihood's rise there (in units of the stated covariance) must reach the 95 % point of
#: chi-square(1) (a Gaussian likelihood rises 9 at 3 sd). Default scene: the tanker's 2.44 +- 0.87 km of the first
#: 300 s rises 2.2 at 5.0 km (its truth is 13.9 km); the merchant's 10.5 km of 1200 s (truth 10.8 km) 6.5 at 21 km
PROFILE_FAR_FACTOR = 2.0
PROFILE_SIGMAS = 3.0
PROFILE_MIN_RISE = 3.841


def range_profile_rise(time_s, bearing_rad, own_xy, sigma_rad: float, end_state, range_m: float) -> float:
    """How much worse the bearings fit a constant-velocity target held at ``range_m`` at the last time.

    The profile likelihood of the final range (Pawitan, In All Likelihood, 2001, sec. 3.4): with the target at
    the last time t_n parametrised by its bearing b and range r from the sensor, and its velocity (vx, vy),

        J(b, r, vx, vy) = sum_i wrap(z_i - atan2(x_i - s_x,i, y_i - s_y,i))^2 / sigma^2,
        x_i = s_x,n + r sin b + vx (t_i - t_n),  y_i = s_y,n + r cos b + vy (t_i - t_n),

    the rise is min_{b, vx, vy} J(b, range_m, vx, vy) - J(end_state): 1 at one standard deviation when the
    likelihood is Gaussian in r, much less where it is flat (a far target whose range the record barely touches,
    whose first-order covariance at a near estimate claims far too much).

    Parameters
    ----------
    time_s, bearing_rad : ndarray (n,)
        Bearing times (s) and bearings (rad, clockwise from north).
    own_xy : ndarray (n, 2)
        The sensor's positions at those times (m).
    sigma_rad : float
        The bearing noise (rad).
    end_state : array_like (4,)
        The fit's state at the last time: x, y (m), vx, vy (m/s).
    range_m : float
        The range held (m).

    Returns
    -------
    float
        The rise of J (>= 0 up to the optimiser's tolerance).
    """
    from scipy.optimize import least_squares

    t, z, own = np.asarray(time_s, float), np.asarray(bearing_rad, float), np.asarray(own_xy, float)
    tau = t - t[-1]
    x_end = np.asarray(end_state, float)
    b0 = float(np.arctan2(x_end[0] - own[-1, 0], x_end[1] - own[-1, 1]))

    def residual(p, r):
        x = own[-1, 0] + r * np.sin(p[0]) + p[1] * tau
        y = own[-1, 1] + r * np.cos(p[0]) + p[2] * tau
        return ((z - np.arctan2(x - own[:, 0], y - own[:, 1]) + np.pi) % (2 * np.pi) - np.pi) / sigma_rad

    r_fit = float(np.hypot(x_end[0] - own[-1, 0], x_end[1] - own[-1, 1]))
    j_fit = float(np.sum(residual([b0, x_end[2], x_end[3]], r_fit) ** 2))
    starts = ([b0, x_end[2], x_end[3]], [b0, 0.0, 0.0])
    j_held = min(2.0 * least_squares(residual, s, args=(float(range_m),), method="lm").cost for s in starts)
    return max(j_held - j_fit, 0.0)


@dataclass(frozen=True, slots=True)
class BearingSd:
    """A bearing noise sd measured from a fit's residuals (:func:`bearing_sd_estimate`): the estimate and its
    two-sided ``level`` chi-square interval (rad), from ``dof`` degrees of freedom."""

    sd_rad: float
    lo_rad: float
    hi_rad: float
    dof: int
    level: float = 0.95

    def text(self) -> str:
        """The estimate and its interval, in degrees, e.g. "0.52 deg (95 % interval 0.43-0.66)".

        Returns
        -------
        str
            The phrase.
        """
        lo, sd, hi = np.rad2deg([self.lo_rad, self.sd_rad, self.hi_rad])
        return f"{sd:.3g} deg ({100 * self.level:.0f} % interval {lo:.3g}-{hi:.3g})"

    def excludes(self, sigma_rad: float) -> bool:
        """Whether a stated bearing sd ``sigma_rad`` (rad) lies below the interval's lower end or above its upper end
        (a stated sd the residuals contradict)."""
        return not (self.lo_rad <= sigma_rad <= self.hi_rad)


def bearing_sd_estimate(residual_rad, n_params: int = 4, level: float = 0.95) -> BearingSd:
    """The bearing noise sd of a record measured from a fit's residuals, with its chi-square interval.

    For n residuals of a fit of p parameters to bearings with white Gaussian errors of sd sigma,
    S = sum e_i^2 ~ sigma^2 chi-square(n - p), so (the usual estimate and its interval; e.g. Bevington & Robinson,
    Data Reduction and Error Analysis, 3rd ed., 2003, sec. 11.2)

        sigma_hat^2 = S / (n - p),     sigma^2 in [S / q_hi, S / q_lo],

    q_lo, q_hi the (1 -+ level) / 2 quantiles of chi-square(n - p). Quantised bearings (steps of q) have errors
    of sd q / sqrt(12), which this measures as well, as long as the bearing moves by more than a step between
    samples.

    Parameters
    ----------
    residual_rad : array_like (n,)
        Measured minus fitted bearings (rad, wrapped).
    n_params : int
        Parameters fitted (4: a constant-velocity track).
    level : float
        Two-sided probability of the interval.

    Returns
    -------
    BearingSd
        The estimate and its interval (rad).
    """
    e = np.asarray(residual_rad, float)
    dof = max(len(e) - n_params, 1)
    s = float(e @ e)
    q_lo, q_hi = chi2_quantile(0.5 * (1.0 - level), dof), chi2_quantile(0.5 * (1.0 + level), dof)
    return BearingSd(float(np.sqrt(s / dof)), float(np.sqrt(s / q_hi)), float(np.sqrt(s / q_lo)), dof, level)


@dataclass(frozen=True, slots=True)
class WhitenessCheck:
    """The lag-1 test of a fit's residuals (:func:`whiteness_check`): their lag-1 autocorrelation rho, the statistic
    z = rho sqrt(n) and its one-sided limit; ``white`` when z lies below it."""

    rho: float
    z: float
    limit: float
    n: int

    @property
    def white(self) -> bool:
        """Whether the residuals pass (no structure beyond white noise at the test's significance)."""
        return self.z <= self.limit

    def note(self) -> str:
        """The test in a phrase, for a warning.

        Returns
        -------
        str
            rho, z and the limit.
        """
        return (f"the residuals of {self.n} bearings follow each other (lag-1 correlation {self.rho:.2f}, "
                f"z = {self.z:.2f} > {self.limit:.2f})")


def whiteness_check(residual_rad, alpha: float, floor_rad: float = 0.0, n_params: int = 4) -> WhitenessCheck:
    """Do a fit's residuals, in time order, look like independent errors? The motion model's test.

    With r_k the sample lag-1 autocorrelation of n de-meaned residuals e_i,

        rho = sum_i e_i e_{i+1} / sum_i e_i^2,      z = (rho + p / n) sqrt(n)  ~  N(0, 1)  under white errors

    (the large-sample law of the lag-1 autocorrelation, Box, Jenkins & Reinsel, Time Series Analysis, 4th ed.,
    2008, eq. 2.1.13 with rho_k = 0 for k >= 1; the residuals of a least-squares fit of p parameters are biased
    towards negative correlation by about p / n, measured: on 50 constant-velocity records of 41-43 bearings with
    white noise, rho sqrt(n) averaged -0.56 with sd 0.92, against -4 / sqrt(42) = -0.62; corrected, 5 of the 50
    exceed the 0.05 limit). A target that changed course or speed between its first and last bearing leaves
    residuals of a constant-velocity fit that run in long arcs of one sign: rho near 1 (measured on 2-4 leg records
    of 41-43 bearings: rho sqrt(n) 5.0-6.0; on constant-velocity ones 0.0-1.1).
    The test is one-sided, z above the standard normal's 1 - alpha quantile, and it needs no stated noise sd, so
    it also judges a record whose sd is estimated from the same residuals. It assumes independent bearing errors:
    a record whose errors are correlated (``batch.correlation_inflation``) is judged by the block test of
    :func:`residual_check` instead (tma/motion_verdict.py).

    Structure far below the bearings' resolution is no motion: ``floor_rad`` is a white error the record is taken
    to hold at least, added to the denominator as its expectation (sum e_i^2 + n floor^2; its expected
    contribution to the numerator is 0), so that residuals much smaller than the floor read as white. Noise-free
    bearings from an ownship on a turn, its position interpolated linearly between fixes 10 s apart, leave
    residuals of 0.0013 deg rms that run with the turns (z = 11 without a floor, 0.2 with 0.01 deg).

    Parameters
    ----------
    residual_rad : array_like (n,)
        Measured minus fitted bearings (rad), in time order.
    alpha : float
        Significance (probability of rejecting a record whose errors are white).
    floor_rad : float
        The bearings' resolution (rad; 0: none).
    n_params : int
        Parameters fitted (4: a constant-velocity track).

    Returns
    -------
    WhitenessCheck
        rho, z and the limit (white when fewer than 3 residuals or no spread).
    """
    from scipy.special import ndtri

    e = np.asarray(residual_rad, float)
    e = e - e.mean() if len(e) else e
    den = float(e @ e) + len(e) * float(floor_rad) ** 2
    rho = float(np.dot(e[:-1], e[1:]) / den) if len(e) >= 3 and den > 0 else 0.0
    z = (rho + n_params / max(len(e), 1)) * float(np.sqrt(len(e)))
    return WhitenessCheck(rho, z, float(ndtri(1.0 - alpha)), len(e))


#: shortest run of residuals :func:`residual_span` reports (a single large residual is an outlier, not a manoeuvre)
MIN_SPAN_BEARINGS = 3


def residual_span(time_s, residual_rad, sigma_rad) -> tuple[float, float] | None:
    """The time span the residuals point at: the run of consecutive standardised residuals w_i = e_i / sigma_i whose
    sum is largest in magnitude for its length,

        (i, j) = argmax_{j - i + 1 >= 3} |w_i + ... + w_j| / sqrt(j - i + 1)

    (the scan statistic of a mean shift over an unknown interval; Siegmund & Venkatraman, Ann. Statist. 23(1),
    1995: under white noise each such sum is N(0, 1)). A constant-velocity fit to a record whose target changed
    course bends its track towards both legs; its residuals are largest, in one sign, over the stretch it fits
    worst, which starts at or after the change. A localisation for the reason's text, not a change-point estimate
    (tma/zig.py's GLR is that).

    Parameters
    ----------
    time_s : array_like (n,)
        Bearing times (s), increasing.
    residual_rad : array_like (n,)
        Measured minus fitted bearings (rad).
    sigma_rad : float or array_like (n,)
        The bearings' noise sd (rad).

    Returns
    -------
    (float, float) or None
        First and last time of the run (s); None for fewer than :data:`MIN_SPAN_BEARINGS` residuals or no finite
        spread.
    """
    t = np.asarray(time_s, float)
    w = np.asarray(residual_rad, float) / np.broadcast_to(np.asarray(sigma_rad, float), t.shape)
    n = len(w)
    if n < MIN_SPAN_BEARINGS or not np.all(np.isfinite(w)) or not np.any(w):
        return None
    c = np.concatenate([[0.0], np.cumsum(w)])
    best, span = -1.0, None
    for length in range(MIN_SPAN_BEARINGS, n + 1):
        score = np.abs(c[length:] - c[:-length]) / np.sqrt(length)
        i = int(np.argmax(score))
        if score[i] > best:
            best, span = float(score[i]), (float(t[i]), float(t[i + length - 1]))
    return span


#: the order of the differences :func:`difference_sd_estimate` takes by default: they cancel every polynomial of
#: degree < 3 in time, so a bearing track's curvature (2 (v / r)^2 rad/s^2 or so) leaves only its third derivative
#: (a 10 m/s target at 5 km, bearings every 60 s: second differences 0.7 deg rms of curvature alone, third 0.1 deg)
DIFFERENCE_ORDER = 3
#: differences beyond this many robust sds (the MAD's) are outliers or a manoeuvre's kink, left out of the estimate
DIFFERENCE_CLIP = 3.5
#: the MAD of a standard normal, Phi^-1(3/4)
MAD_NORMAL = 0.6744897501960817


def _difference_weights(t, order: int) -> np.ndarray:
    """Coefficients (n - order, order + 1) of the order-k divided differences of samples at times ``t``:
    c_jm = 1 / prod_{l != m} (t_{j+m} - t_{j+l}) (Abramowitz & Stegun 1964, eq. 25.1.4), scaled per row to unit
    norm (only the ratios matter once the differences are normalised)."""
    n = len(t) - order
    idx = np.arange(n)[:, None] + np.arange(order + 1)[None, :]
    tt = t[idx]
    c = np.ones_like(tt)
    for m in range(order + 1):
        for j in range(order + 1):
            if j != m:
                c[:, m] /= tt[:, m] - tt[:, j]
    return c / np.sqrt(np.sum(c**2, axis=1, keepdims=True))


def _difference_correlation(c, s) -> np.ndarray:
    """The correlation of the normalised differences d_j = sum_m c_jm z_{j+m} / sqrt(sum_m c_jm^2 s_{j+m}^2) under
    white noise of sds proportional to ``s``: a band of half-width k (n - k, k + 1), column l the correlation of d_j
    with d_{j+l} (zero past the end)."""
    n, k1 = c.shape
    idx = np.arange(n)[:, None] + np.arange(k1)[None, :]
    var = c**2 * s[idx] ** 2
    norm = np.sqrt(var.sum(axis=1))
    band = np.zeros((n, k1))
    band[:, 0] = 1.0
    for lag in range(1, k1):  # d_j and d_{j+lag} share samples j+lag .. j+k: c_j[m] with c_{j+lag}[m - lag]
        prod = c[:-lag, lag:] * c[lag:, :k1 - lag] * s[idx[:-lag, lag:]] ** 2
        band[:-lag, lag] = prod.sum(axis=1) / (norm[:-lag] * norm[lag:])
    return band


def _satterthwaite_dof(band, keep) -> float:
    """nu = (tr R)^2 / tr(R^2) of the kept differences' correlation R (a band, :func:`_difference_correlation`):
    a pair counts only when both differences are kept."""
    band = band.copy()
    for lag in range(1, band.shape[1]):
        band[:-lag, lag] *= keep[:-lag] & keep[lag:]
    band[~keep] = 0.0
    return int(keep.sum()) ** 2 / float(np.sum(band[:, 0] ** 2) + 2.0 * np.sum(band[:, 1:] ** 2))


def difference_sd_estimate(time_s, bearing_rad, relative_sd=1.0, order: int = DIFFERENCE_ORDER,
                           level: float = 0.95) -> BearingSd:
    """The bearing noise sd of a record from the bearings alone, with no motion model: from their divided
    differences of order k, which cancel any polynomial of degree < k in time, robust to outliers and manoeuvres.

    With c_jm the order-k divided-difference coefficients on bearings j..j+k at uneven times (Abramowitz & Stegun
    1964, eq. 25.1.4) and s_i each bearing's sd relative to the reference (1 when equal), the normalised differences

        d_j = sum_m c_jm z_{j+m} / sqrt(sum_m c_jm^2 s_{j+m}^2)  ~  N(0, sigma^2)

    under white Gaussian noise and a bearing track smooth to degree k - 1 over k + 1 bearings; neighbouring d_j share
    bearings and are correlated (band R of half-width k; equal spacing, k = 2: -2/3 and 1/6; k = 3: -3/4, 3/10 and
    -1/20). Differences beyond :data:`DIFFERENCE_CLIP` robust sds (1.4826 median |d|, the MAD; Hampel 1974, JASA 69)
    are left out (an outlier spoils k + 1 differences, a zig's kink a few), and of the m kept

        sigma_hat^2 = sum d_j^2 / (m f),   f = 1 - 2 a phi(a) / (2 Phi(a) - 1)  (a = DIFFERENCE_CLIP)

    (f the variance of a standard normal truncated at +-a, 0.9939). Its interval is Satterthwaite's (Biometrics
    Bulletin 2(6), 1946): sum d_j^2 has mean sigma^2 tr R and variance 2 sigma^4 tr R^2, the moments of
    sigma^2 chi-square(nu) / nu scaled, nu = (tr R)^2 / tr(R^2) (m / 1.94 at k = 2, m / 2.31 at k = 3 for equal
    spacing), so

        sigma^2 in [sigma_hat^2 nu / q_hi, sigma_hat^2 nu / q_lo],   q the (1 -+ level) / 2 quantiles of chi-square(nu).

    Parameters
    ----------
    time_s : array_like (n,)
        Strictly increasing bearing times (s), n >= order + 3.
    bearing_rad : array_like (n,)
        Bearings (rad; unwrapped here).
    relative_sd : float or array_like (n,)
        Each bearing's sd relative to the reference the estimate is of (1: all equal).
    order : int
        k (2 or 3; :data:`DIFFERENCE_ORDER`).
    level : float
        Two-sided probability of the interval.

    Returns
    -------
    BearingSd
        The reference sd's estimate and interval (rad), ``dof`` = round(nu).
    """
    from scipy.special import ndtr

    t = np.asarray(time_s, float)
    z = np.unwrap(np.asarray(bearing_rad, float))
    s = np.broadcast_to(np.asarray(relative_sd, float), t.shape)
    c = _difference_weights(t, order)
    idx = np.arange(len(c))[:, None] + np.arange(order + 1)[None, :]
    d = np.sum(c * z[idx], axis=1) / np.sqrt(np.sum(c**2 * s[idx] ** 2, axis=1))
    robust = np.median(np.abs(d)) / MAD_NORMAL
    keep = np.abs(d) <= DIFFERENCE_CLIP * robust if robust > 0 else np.ones(len(d), bool)
    m, nu = int(keep.sum()), _satterthwaite_dof(_difference_correlation(c, s), keep)
    a = DIFFERENCE_CLIP
    f = 1.0 - 2.0 * a * np.exp(-0.5 * a * a) / np.sqrt(2.0 * np.pi) / (2.0 * ndtr(a) - 1.0)
    var = float(np.sum(d[keep] ** 2)) / (m * f)
    q_lo, q_hi = chi2_quantile(0.5 * (1.0 - level), nu), chi2_quantile(0.5 * (1.0 + level), nu)
    return BearingSd(float(np.sqrt(var)), float(np.sqrt(var * nu / q_hi)), float(np.sqrt(var * nu / q_lo)),
                     int(round(nu)), level)
