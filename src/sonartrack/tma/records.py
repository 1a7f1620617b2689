"""Plain containers for TMA data shared by the estimators, the readers (io/) and the CLI, and the check
that a navigation record covers a measurement record.

They live in tma/ (not io/) because the estimators take and return them and io/ sits above tma/ in
the layering; ``sonartrack.io.records`` re-exports them for readers.

These are the API boundary between ``io/`` (which reads and validates files) and the algorithm
layers (which take arrays). All quantities are SI: seconds, metres, radians, hertz, dB. Build them
with keywords: ``BearingRecord(time_s=t, bearing_rad=b)``, ``OwnshipTrack(time_s=tn, x_m=x, y_m=y)``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.core.errors import InputError

#: longest gap (s) between two ownship samples across which positions are interpolated
MAX_NAV_GAP_S = 120.0


@dataclass(frozen=True, slots=True)
class BearingRecord:
    """Passive measurements against time: bearing (rad, clockwise from north, (-pi, pi]),
    optionally received frequency (Hz), SNR (dB) and each bearing's own noise sd (rad; e.g. a line array's,
    which grows towards endfire). Times strictly increasing."""

    time_s: np.ndarray
    bearing_rad: np.ndarray
    frequency_hz: np.ndarray | None = None
    snr_db: np.ndarray | None = None
    #: each bearing's noise standard deviation (rad, > 0); None: one sd for all (the settings' or estimated)
    bearing_sd_rad: np.ndarray | None = None

    def reference_sd_rad(self) -> float | None:
        """The one sd worth the same information as the bearings' own sds (None without them): the harmonic
        mean of the variances, 1 / sqrt(mean(1 / sigma_i^2)), so that n bearings of this sd carry the Fisher
        information sum 1 / sigma_i^2 of the record's (what a single-sd method such as a sequential filter uses).

        Returns
        -------
        float or None
            The reference sd (rad).
        """
        if self.bearing_sd_rad is None:
            return None
        return float(1.0 / np.sqrt(np.mean(1.0 / np.square(np.asarray(self.bearing_sd_rad, float)))))

    def relative_sd(self) -> np.ndarray | float:
        """Each bearing's sd relative to :meth:`reference_sd_rad` (1.0 without per-bearing sds): the weights that
        the single-sd checks (tma/record_checks.py, tma/record_verdict.py) whiten the residuals by.

        Returns
        -------
        ndarray (n,) or float
            sigma_i / sigma_ref.
        """
        if self.bearing_sd_rad is None:
            return 1.0
        return np.asarray(self.bearing_sd_rad, float) / self.reference_sd_rad()

    def until(self, end_s: float) -> BearingRecord:
        """The measurements at times <= ``end_s``.

        Parameters
        ----------
        end_s : float
            Last time kept (s).

        Returns
        -------
        BearingRecord
            The rows with time_s <= end_s (optional columns stay None).
        """
        keep = np.asarray(self.time_s) <= end_s

        def cut(a):
            return None if a is None else np.asarray(a)[keep]

        return BearingRecord(time_s=cut(self.time_s), bearing_rad=cut(self.bearing_rad),
                             frequency_hz=cut(self.frequency_hz), snr_db=cut(self.snr_db),
                             bearing_sd_rad=cut(self.bearing_sd_rad))


@dataclass(frozen=True, slots=True)
class OwnshipTrack:
    """Own-ship navigation: position (m, x east, y north) against time (s), strictly increasing."""

    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray

    def position_at(self, t_s) -> np.ndarray:
        """Linearly interpolated position (..., 2) at times ``t_s`` (caller checks the time span).

        Parameters
        ----------
        t_s : float or array_like
            Times (s).

        Returns
        -------
        ndarray, shape (..., 2)
            (x, y) (m; x east, y north); clamped to the end positions outside the span (np.interp).
        """
        t = np.asarray(t_s, dtype=float)
        return np.stack([np.interp(t, self.time_s, self.x_m), np.interp(t, self.time_s, self.y_m)], axis=-1)


@dataclass(frozen=True, slots=True)
class ModeProbabilities:
    """An IMM's mode probabilities over time and which of its modes are manoeuvre modes.

    ``names`` one per mode ("cv" for the quietest, "q<intensity>" for the others, tma/imm_mgekf.py
    ``mode_names``), ``prob`` (n, r) the posterior probability of each mode per time, ``manoeuvre_mode`` (r,)
    True for the modes whose process noise stands for a manoeuvre, ``level`` the probability of the manoeuvre
    modes above which a row is flagged as manoeuvring."""

    names: tuple[str, ...]
    prob: np.ndarray  # (n, r)
    manoeuvre_mode: np.ndarray  # (r,) bool
    level: float

    def manoeuvre_prob(self) -> np.ndarray:
        """The probability of the manoeuvre modes together, per time (n,) (NaN where the filter gave none)."""
        return np.asarray(self.prob, float)[:, np.asarray(self.manoeuvre_mode, bool)].sum(axis=1)

    def joined(self, later: ModeProbabilities) -> ModeProbabilities:
        """These rows, then ``later``'s from its second row on (same bank of modes)."""
        return replace(self, prob=np.concatenate([self.prob, later.prob[1:]]))


@dataclass(frozen=True, slots=True)
class TmaSolution:
    """A target solution against time: state ``[x, y, vx, vy]`` (m, m/s) and its covariance."""

    time_s: np.ndarray
    state: np.ndarray  # (n, 4)
    covariance: np.ndarray  # (n, 4, 4)
    method: str
    #: (n,) False where the data cannot resolve the range (the state's range and speed then mean nothing;
    #: bearings still do). None: determined everywhere.
    range_determined: np.ndarray | None = None
    #: (n,) why each undetermined row is so ("diverged", "unobservable", ...; "" where determined). None: no reasons.
    undetermined_reason: np.ndarray | None = None
    #: an IMM's mode probabilities per row (imm-ekf, imm-mgekf); None for the other methods
    modes: ModeProbabilities | None = None

    def range_flags(self) -> np.ndarray:
        """``range_determined`` as a boolean array (all True when not set).

        Returns
        -------
        ndarray of bool, shape (n,)
            Whether the range of each row is determined by the data.
        """
        n = len(np.asarray(self.time_s))
        return np.ones(n, bool) if self.range_determined is None else np.asarray(self.range_determined, bool)

    def followed_by(self, later: TmaSolution) -> TmaSolution:
        """This solution, then ``later`` from its second row on (its first row restates this one's last time),
        under ``later``'s method name.

        Parameters
        ----------
        later : TmaSolution
            The solution that takes over (its first row at this one's last time).

        Returns
        -------
        TmaSolution
            The joined rows.
        """
        return TmaSolution(time_s=np.concatenate([self.time_s, later.time_s[1:]]),
                           state=np.concatenate([self.state, later.state[1:]]),
                           covariance=np.concatenate([self.covariance, later.covariance[1:]]), method=later.method,
                           range_determined=np.concatenate([self.range_flags(), later.range_flags()[1:]]),
                           undetermined_reason=np.concatenate([self.reasons(), later.reasons()[1:]]),
                           modes=_joined_modes(self, later))

    def reasons(self) -> np.ndarray:
        """Why each row's range is not determined: ``undetermined_reason``, "" on determined rows, and "not
        determined" on an undetermined row that gives no reason.

        Returns
        -------
        ndarray of str, shape (n,)
            One reason per row ("" where the range is determined).
        """
        flags = self.range_flags()
        given = (np.full(len(flags), "", dtype=object) if self.undetermined_reason is None
                 else np.asarray(self.undetermined_reason, dtype=object))
        return np.where(flags, "", np.where(given == "", "not determined", given)).astype(object)


def _joined_modes(first: TmaSolution, later: TmaSolution) -> ModeProbabilities | None:
    """The mode probabilities of two joined solutions: kept only when both have them, from the same bank."""
    a, b = first.modes, later.modes
    if a is None or b is None or a.names != b.names:
        return None
    return a.joined(b)


def check_bearing_sds(record: BearingRecord) -> None:
    """A record's per-bearing sds, when given, must be one finite positive value per bearing. Raises
    :class:`InputError`.

    Parameters
    ----------
    record : BearingRecord
        The measurements.
    """
    if record.bearing_sd_rad is None:
        return
    sd = np.asarray(record.bearing_sd_rad, float)
    if sd.shape != np.shape(record.time_s):
        raise InputError(f"the record gives {sd.size} bearing sds for {np.size(record.time_s)} bearings: give one per "
                         "bearing (or none)")
    bad = ~np.isfinite(sd) | (sd <= 0)
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"bearing sd {sd[i]:g} rad at t = {np.asarray(record.time_s)[i]:g} s is not a positive "
                         "number: give each bearing's noise sd (> 0), or leave the column out")


def check_coverage(record: BearingRecord, ownship: OwnshipTrack, max_gap_s: float = MAX_NAV_GAP_S) -> None:
    """Every measurement time must lie within the ownship span, in no gap longer than ``max_gap_s``
    (positions are interpolated linearly, never extrapolated). Raises :class:`InputError`.

    Parameters
    ----------
    record : BearingRecord
        The measurements (times in s).
    ownship : OwnshipTrack
        The ownship samples (times in s).
    max_gap_s : float
        Longest ownship gap (s) interpolated across; a measurement exactly on an ownship sample is always fine.
    """
    t = np.asarray(record.time_s, float)
    nt = np.asarray(ownship.time_s, float)
    outside = (t < nt[0]) | (t > nt[-1])
    if outside.any():
        raise InputError(f"{int(outside.sum())} measurement time(s) (first {t[np.argmax(outside)]:g} s) lie outside "
                         f"the ownship file's span {nt[0]:g}..{nt[-1]:g} s: extend the ownship file or trim the "
                         "bearings (positions are not extrapolated)")
    k = np.clip(np.searchsorted(nt, t, side="right"), 1, len(nt) - 1)
    gap = nt[k] - nt[k - 1]
    on_sample = np.isin(t, nt)
    bad = (gap > max_gap_s) & ~on_sample
    if bad.any():
        i = int(np.argmax(bad))
        raise InputError(f"no ownship position near t = {t[i]:g} s: the ownship file has a {gap[i]:g} s gap "
                         f"({nt[k[i] - 1]:g}..{nt[k[i]]:g} s) and sonartrack interpolates across at most "
                         f"{max_gap_s:g} s: add ownship samples or drop those measurements")
