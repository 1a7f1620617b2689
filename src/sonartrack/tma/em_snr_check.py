"""The test of an em-map solution's SNR residuals against its propagation model (paper P3's model judged by its
own data; moved out of tma/em_map.py, whose solver it checks): the residuals' chi-square against sigma_SNR and
their trend against log range. A propagation model that does not explain the SNRs along the solution's track
makes the SNR's range untrustworthy (tma/solve.py :func:`~sonartrack.tma.solve.em_map_verdict`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class SnrCheck:
    """The test of a solution's SNR residuals against the propagation model (:func:`snr_residual_check`): the
    chi-square statistic with its degrees of freedom and upper limit, the trend statistic against log range with
    its limit, and the number of SNRs tested."""

    chi2: float
    dof: int
    limit: float
    trend_chi2: float
    trend_limit: float
    n: int

    @property
    def explained(self) -> bool:
        """Whether the model explains the SNRs (both statistics within their limits; True with fewer than 5 SNRs)."""
        return self.n < 5 or (self.chi2 <= self.limit and self.trend_chi2 <= self.trend_limit)

    def note(self) -> str:
        """One line on the test.

        Returns
        -------
        str
            "the propagation model does (not) explain the SNR (chi2 = ... for ... dof, ...)".
        """
        verb = "explains" if self.explained else "does not explain"
        return (f"the propagation model {verb} the SNR (chi2 = {self.chi2:.0f} for {self.dof} dof, limit "
                f"{self.limit:.0f}; trend with log range chi2 = {self.trend_chi2:.1f} for 1 dof, limit "
                f"{self.trend_limit:.1f})")


def snr_residual_check(snr_db, predicted_db, range_m, sigma_snr_db: float, *, alpha: float = 1e-3,
                       n_params: int = 4) -> SnrCheck:
    """Do the measured SNRs agree with the propagation model along the solution's track?

    With w_n = (xi_n - xi_bar(r_n)) / sigma_SNR the standardised SNR residuals at the solution's ranges r_n
    (eq. 30 is the model: w_n ~ N(0, 1) independent when it holds),

        chi2   = sum_n w_n^2  ~  chi-square(n - p)        (p = 4 track parameters fitted)
        chi2_T = (sum_n (l_n - l_bar) w_n)^2 / sum_n (l_n - l_bar)^2  ~  chi-square(1),   l_n = ln r_n

    the second the squared z statistic of the least-squares slope of w against log range (a model whose
    spreading or absorption differs from the sea's leaves residuals that trend with range, which a
    range-shifted track can make small on average but not flat). Each is compared with its upper-tail
    1 - alpha quantile (scipy.stats.chi2). A wrong model can still be fitted by a wrong track: then the SNRs fit
    and the bearings pay, which is why the solution is also judged against the bearings alone (tma/solve.py).

    Parameters
    ----------
    snr_db, predicted_db : array_like (n,)
        Measured SNRs and the model's mean SNR at the solution's ranges (dB); NaN entries are skipped.
    range_m : array_like (n,)
        The solution's ranges (m).
    sigma_snr_db : float
        The SNR noise the model states (dB).
    alpha : float
        Significance of each test.
    n_params : int
        Parameters fitted.

    Returns
    -------
    SnrCheck
        The statistics and their limits.
    """
    from scipy.stats import chi2 as chi2_dist

    xi, pred, r = (np.asarray(a, float) for a in (snr_db, predicted_db, range_m))
    use = np.isfinite(xi) & np.isfinite(pred) & (r > 0)
    w = (xi[use] - pred[use]) / float(sigma_snr_db)
    n = int(use.sum())
    dof = max(n - n_params, 1)
    lr = np.log(r[use]) - np.log(r[use]).mean() if n else np.zeros(0)
    sxx = float(lr @ lr)
    trend = float((lr @ w) ** 2 / sxx) if sxx > 0 else 0.0
    return SnrCheck(float(w @ w), dof, float(chi2_dist.ppf(1 - alpha, dof)), trend,
                    float(chi2_dist.ppf(1 - alpha, 1)), n)
