"""Initiator parts: new tracks from the measurements of a scan that no existing track validated.

* :class:`OnePointInitiator` (positions, paper P4): every unvalidated measurement z starts a tentative
  track at [z, 0] with covariance diag(R_z, s_v^2 I), s_v the velocity prior's standard deviation.
  One-point initiation needs no pairing of measurements across scans in dense clutter and lets the
  existence probability do the discrimination (Musicki & Evans 2004, JIPDA, sec. VI uses the same).
* :class:`PeakInitiator` (bearing peaks, paper P0 on user data): one track per cluster of unvalidated
  peaks at least ``init_amplitude`` strong (the strongest of peaks closer than half a gate), at
  [bearing, 0] with P(0) = [[s^2, s^2], [s^2, 2 s^2]], s = sigma_p (the paper's P(0)).

Both keep the covariance at initiation (``P_init``, the CTT test of P4 eq. 23) and the time.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.tracking.tracks import Scan, TrackArrays


def _new_tracks(x, P, n_modes: int, first_id: int, time_s: float, existence: float, attrs: dict) -> TrackArrays:
    """k tentative tracks with every mode at (x (k, d), P (k, d, d)) and equal mode probabilities."""
    k = len(x)
    return TrackArrays(np.repeat(x[:, None], n_modes, axis=1), np.repeat(P[:, None], n_modes, axis=1),
                       np.full((k, n_modes), 1.0 / n_modes), np.full(k, existence), np.zeros(k, bool),
                       np.arange(first_id, first_id + k, dtype=np.int64), np.full(k, float(time_s)), P, attrs)


def bearing_covariance(sigma_p_deg) -> np.ndarray:
    """Paper P0's initial covariance of [bearing, bearing rate]: ``[[s^2, s^2], [s^2, 2 s^2]]`` per track.

    Parameters
    ----------
    sigma_p_deg : float or array_like, shape (k,)
        Peak spread s (deg).

    Returns
    -------
    ndarray, shape (k, 2, 2)
        Covariances (deg^2, deg^2/s, deg^2/s^2), the paper's P(0) as used by the module's initiator.
    """
    s2 = np.asarray(sigma_p_deg, dtype=float) ** 2
    return np.stack([np.stack([s2, s2], -1), np.stack([s2, 2 * s2], -1)], -2)


def velocity_std_from_speed_bound(max_speed_mps: float) -> float:
    """Per-axis standard deviation of a one-point track's zero-mean velocity prior from a bound on the target's speed:
    the velocity uniform over the disc |v| <= v_max (every heading and every speed up to the bound as likely per unit
    area) has covariance (v_max^2 / 4) I, so the Gaussian of the same two moments has s_v = v_max / 2 per axis.

    Why: the prior sets a young track's predicted position spread (S = R + T^2 s_v^2 I at its first update after one
    scan of T s), and every hit's likelihood ratio falls as 1 / sqrt(det S) (Musicki, Evans, Stankovic 1994, eq. 29):
    on study active-chain's LFM trials (30 s pings, contacts known to ~15 m in range) a hit's S was 8-10 times R in
    sqrt(det) (benchmarks/bench_acquisition.py --ledger), most of it the prior along the range axis. An active chain
    that searches bistatic range rates up to r_max (MFTD, CW Doppler bank) states a target no faster than r_max / 2
    (an approaching target's bistatic range rate is twice its speed), so v_max = r_max / 2.

    Parameters
    ----------
    max_speed_mps : float
        The bound v_max on the target's speed (m/s, > 0).

    Returns
    -------
    float
        s_v (m/s per axis).
    """
    from sonartrack.core.errors import require

    require(max_speed_mps > 0, f"the speed bound must be positive (m/s), not {max_speed_mps}")
    return 0.5 * float(max_speed_mps)


@dataclass(frozen=True)
class OnePointInitiator:
    """Position tracks from single measurements, with a zero-mean velocity prior."""

    velocity_std: float
    initial_existence: float
    max_tracks: int

    def initiate(self, scan: Scan, used, n_live: int, n_modes: int, first_id: int) -> TrackArrays:
        """Tentative position tracks at ``[z, 0]`` with covariance ``diag(R_z, s_v^2 I)`` from unvalidated measurements.

        At most ``max_tracks - n_live`` tracks are started, in measurement order.

        Parameters
        ----------
        scan : Scan
            The scan (positions z (m, k) in m, covariances R (m, k, k) in m^2).
        used : ndarray of bool, shape (m,)
            Measurements some existing track validated.
        n_live : int
            Live tracks after deletion.
        n_modes : int
            IMM modes of each new track (equal mode probabilities).
        first_id : int
            Identifier of the first new track.

        Returns
        -------
        TrackArrays
            New tracks with existence ``initial_existence``, not confirmed.
        """
        new = np.nonzero(~used)[0][: max(0, self.max_tracks - n_live)]
        z, R = scan.z[new], scan.R[new]
        k, dims = z.shape
        P = np.zeros((len(new), 2 * dims, 2 * dims))
        P[:, :dims, :dims] = R
        for i in range(dims, 2 * dims):
            P[:, i, i] = self.velocity_std**2
        x = np.zeros((len(new), 2 * dims))
        x[:, :dims] = z
        return _new_tracks(x, P, n_modes, first_id, scan.time_s, self.initial_existence, {})


@dataclass(frozen=True)
class AmplitudeOnePointInitiator(OnePointInitiator):
    """:class:`OnePointInitiator` for amplitude-aided IPDA (tracking/measurements.py
    :class:`AmplitudeRangeRateMeasurements`): each new track carries its first contact's amplitude in ``amp_w`` (1)
    and ``amp_sum`` (a); with ``amplitude_start`` its initial existence odds are multiplied by that contact's
    amplitude ratio under the prior target law (association/amplitude_ipda.py ``AmplitudeModel.log_ratio`` at
    zero weight), the first update of a track that IPDA's one-point initiation otherwise gives the prior
    P(E) for: the odds stay a mean-one multiple of the prior's on clutter (E_clutter[r] = 1), so Ville's bound on
    the false confirmed tracks (tracking/existence.py ``confirm_threshold_for_rate``) holds as before. After
    starting the tracks, the scan's amplitudes are added to the model's clutter sample (``add_scan``): the next
    scan's ratios use the scans before it."""

    model: object = None
    amplitude_start: bool = False

    def initiate(self, scan: Scan, used, n_live: int, n_modes: int, first_id: int) -> TrackArrays:
        """Tentative tracks as :meth:`OnePointInitiator.initiate`, with the amplitude attrs (class doc)."""
        new = np.nonzero(~used)[0][: max(0, self.max_tracks - n_live)]
        base = super().initiate(scan, used, n_live, n_modes, first_id)
        a = np.zeros(len(new)) if scan.amplitude is None else np.asarray(scan.amplitude, float)[new]
        existence = base.existence
        if self.amplitude_start and self.model is not None and len(new):
            r, p0 = np.exp(self.model.log_ratio(a, np.zeros(len(a)), np.zeros(len(a)))), self.initial_existence
            existence = p0 * r / (1.0 - p0 + p0 * r)  # odds O_0 r (exactly P_0 at r = 1)
        if self.model is not None and scan.amplitude is not None:
            self.model.add_scan(scan.amplitude)
        return replace(base, existence=existence, attrs={"amp_w": np.ones(len(new)), "amp_sum": a})


@dataclass(frozen=True)
class PeakInitiator:
    """Bearing tracks from strong unvalidated peaks, one per cluster (module doc)."""

    init_amplitude: float
    sigma_p_deg: float
    amplitude_sd: float
    gate_deg: float

    def initiate(self, scan: Scan, used, n_live: int, n_modes: int, first_id: int) -> TrackArrays:
        """Tentative bearing tracks from strong unvalidated peaks, one per cluster (module docstring).

        Peaks of amplitude >= ``init_amplitude`` are taken strongest first; a peak closer than half a gate
        (``gate_deg / 2``) to a chosen one is skipped.

        Parameters
        ----------
        scan : Scan
            The scan (bearings z (m, 1) in deg, amplitudes (m,)).
        used : ndarray of bool, shape (m,)
            Peaks some existing track validated.
        n_live : int
            Live tracks (unused: no cap).
        n_modes : int
            Modes of each new track.
        first_id : int
            Identifier of the first new track.

        Returns
        -------
        TrackArrays
            New tracks at [bearing, 0] with ``sigma_p``, ``strength`` and ``sigma_a`` in ``attrs``; existence NaN.
        """
        z, a = scan.z[:, 0], scan.amplitude
        new = np.nonzero(~used & (a >= self.init_amplitude))[0]
        chosen: list[int] = []
        for j in new[np.argsort(-a[new])]:  # strongest first; one per cluster of nearby peaks
            if all(abs(z[j] - z[i]) > self.gate_deg / 2 for i in chosen):
                chosen.append(int(j))
        k = len(chosen)
        x = np.zeros((k, 2))
        x[:, 0] = z[chosen]
        attrs = {"sigma_p": np.full(k, self.sigma_p_deg), "strength": a[chosen].astype(float),
                 "sigma_a": np.full(k, self.amplitude_sd)}
        return _new_tracks(x, bearing_covariance(np.full(k, self.sigma_p_deg)), n_modes, first_id, scan.time_s,
                           np.nan, attrs)
