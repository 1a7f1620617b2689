"""The multi-target tracker, composed of parts (like Stone Soup's MultiTargetTracker, on stacked arrays).

Parts (each a small object; tracking/configurations.py builds the paper trackers from settings):

* ``motion`` -- constant-velocity modes with an IMM mode chain (tracking/motion.py);
* ``measurements`` -- likelihoods and gates of a scan against the predicted tracks (tracking/measurements.py);
* ``associator`` -- association weights of all tracks at once: PDA or exact JPDA (tracking/associators.py);
* ``existence`` -- optional IPDA existence Markov chain (tracking/existence.py);
* ``initiator`` -- optional: new tracks from measurements no track validated (tracking/initiators.py);
* ``deleter`` -- optional: confirmation and deletion (tracking/deleters.py);
* ``own_motion`` -- optional: the array's heading change between scans predicted in a cone-angle state, each
  track's side a hypothesis (tracking/own_motion.py); :meth:`step` then takes ``array_turn_deg``;
* ``resolution`` -- optional: two confirmed tracks closer than the sensor resolves are associated and updated as
  one merged track, its update split onto them (tracking/resolution.py; one mode, bearing tracks).

One scan (Park, Song, Lee 2017, Fig. 3 and eqs. 7-21 for the IMM-IPDA configuration; Park, Ryu & Lee
1994 for the JPDA_A one), every step on the arrays of all tracks:

1. interaction and prediction per mode (motion); existence prediction
2. likelihoods and gates (measurements)
3. association weights (associator), then the PDA Gaussian-mixture update with them (association/pda.py;
   its sums over the gated pairs compiled, association/pda_mixture_kernel.py, with identical results)
4. mode probabilities mu_r ∝ c_r Lambda_r (filters/imm.py) and existence from Lambda = sum_r c_r Lambda_r
5. confirmation and deletion (deleter), then initiation from the unvalidated measurements (initiator)

The tracker keeps no history (memory is bounded by the live tracks); :meth:`step` returns a
:class:`~sonartrack.tracking.tracks.TrackSnapshot` with the combined (IMM output) estimates.

Under load (hundreds of tracks, thousands of contacts a scan) steps 2-4 work on the gated (track,
measurement) pairs only, never on an (n tracks, r modes, m measurements) array: a windowed pre-gate
(association/likelihood_kernel.py), PDA weights from the pairs (``pda_pair_weights``) and the mixture
update over the pairs, each giving the dense evaluation's numbers bit for bit (tests/association,
tests/tracking/test_load_numerics.py; timing in benchmarks/bench_tracker_load.py).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from sonartrack.core.errors import InputError
from sonartrack.tracking.tracks import Scan, TrackArrays, TrackSnapshot


class MultiTargetTracker:
    """Tracker of parts (module doc); call :meth:`step` once per scan, in time order.

    ``tracks`` and ``time_s`` start it with known tracks (e.g. on the truth, as paper P0's runs do);
    their ``attrs`` must hold what the measurement part needs."""

    def __init__(self, motion, measurements, associator, *, existence=None, initiator=None, deleter=None,
                 tracks: TrackArrays | None = None, time_s: float | None = None, own_motion=None,
                 resolution=None):
        if associator.single_mode_only and motion.n_modes > 1:
            raise InputError(f"{associator!r} needs a single motion mode (IMM-JPDA is not implemented): give one q")
        if resolution is not None and motion.n_modes > 1:
            raise InputError("merged-measurement groups need a single motion mode: give one q or no resolution")
        if existence is not None and not associator.supports_existence:
            raise InputError(f"{associator!r} cannot drive an existence model (JIPDA is not implemented): use PDA")
        self.motion, self.measurements, self.associator = motion, measurements, associator
        self.existence, self.initiator, self.deleter = existence, initiator, deleter
        self.own_motion, self.resolution = own_motion, resolution
        self._tracks = tracks if tracks is not None else TrackArrays.empty(motion.n_modes, motion.state_dim)
        for part in (deleter, own_motion):
            if part is not None and len(self._tracks):
                self._tracks = self._tracks.with_attrs(**part.new_track_attrs(len(self._tracks)))
        self._time = time_s
        self._next_id = int(self._tracks.track_id.max(initial=0)) + 1

    @property
    def tracks(self) -> TrackArrays:
        """The live tracks (stacked arrays, mode-conditioned)."""
        return self._tracks

    def step(self, time_s: float, z, R=None, amplitude=None, array_turn_deg: float = 0.0) -> TrackSnapshot:
        """Process one scan (steps 1-5 of the module docstring).

        Parameters
        ----------
        time_s : float
            Scan time (s), later than the previous scan's.
        z : array_like, shape (m, k) or (m,)
            Measurements: positions [x, y] (m) for the position tracker, bearings (deg) for the bearing tracker.
        R : array_like, shape (m, k, k) or (k, k), optional
            Per-measurement covariances (m^2), if the measurement part takes them.
        amplitude : array_like, shape (m,), optional
            Peak amplitudes, if the measurement part takes them.
        array_turn_deg : float
            The array's heading change since the last scan (deg, clockwise positive), used by the ``own_motion``
            part (ignored without one).

        Returns
        -------
        TrackSnapshot
            The live tracks after the scan, with combined (IMM output) estimates.

        Raises
        ------
        InputError
            If a required input is missing, a value is NaN/inf, shapes disagree, or the time does not increase.
        """
        scan = self._scan(time_s, z, R, amplitude)
        T = self._tracks
        hit, used = np.zeros(len(T), bool), np.zeros(len(scan), bool)
        if len(T):
            T, hit, used = self._update(T, scan, time_s - self._time, float(array_turn_deg))
        if self.deleter is not None and len(T):
            T = self.deleter.manage(T, hit)
        if self.initiator is not None:
            new = self.initiator.initiate(scan, used, len(T), self.motion.n_modes, self._next_id)
            self._next_id += len(new)
            for part in (self.deleter, self.own_motion):
                if part is not None and (attrs := part.new_track_attrs(len(new))):
                    new = new.with_attrs(**attrs)
            T = T.append(new)
        self._tracks, self._time = T, float(time_s)
        return TrackSnapshot.of(time_s, T)

    def snapshot(self) -> TrackSnapshot:
        """The live tracks now.

        Returns
        -------
        TrackSnapshot
            Combined estimates; time NaN before the first scan.
        """
        return TrackSnapshot.of(np.nan if self._time is None else self._time, self._tracks)

    def _update(self, T: TrackArrays, scan: Scan, dt_s: float, turn_deg: float = 0.0):
        """Steps 1-4 of the module doc for the live tracks; returns them, hit (n,) and used (m,)."""
        c, x0, P0 = self.motion.interact(T.mu, T.x, T.P, dt_s)
        x_pred, P_pred = self.motion.predict(x0, P0, dt_s)
        x_still, P_still = x_pred, P_pred
        if self.own_motion is not None and turn_deg != 0.0:
            x_pred, P_pred = self.own_motion.predict(x_pred, P_pred, T.attrs, turn_deg)
        pairs = self.resolution.pairs(x_pred, T.confirmed, scan.z[:, 0]) if self.resolution is not None else None
        if pairs is not None and len(pairs):
            x, P, lik, w, rows, attrs = self._grouped_update(x_pred, P_pred, scan, T.attrs, pairs)
        else:
            x, P, lik, w, attrs = self._plain_update(x_pred, P_pred, scan, T.attrs)
            rows = np.arange(len(T))
        mu, log_total = self.motion.mode_update(c, None if w.log_lambda is None else w.log_lambda[rows])
        existence = T.existence
        if self.existence is not None:
            existence = self.existence.update(self.existence.predict(T.existence), log_total)
        if self.own_motion is not None and turn_deg != 0.0:
            own = lik.gated[rows]
            if pairs is not None:
                own[pairs.ravel()] = False  # a shared peak says nothing of either member's own side
            attrs = self.own_motion.update(attrs, x_still, P_still, T.attrs["sigma_p"], scan.z[:, 0], own, turn_deg)
        if "log_lr_odds" in attrs:  # the likelihood-ratio odds of a rate confirmation (tracking/deleters.py)
            start = np.log(T.existence / (1.0 - T.existence))  # a new track's (NaN) from its existence before this scan
            attrs = {**attrs, "log_lr_odds": np.where(np.isnan(attrs["log_lr_odds"]), start, attrs["log_lr_odds"])
                     + log_total}
        T = replace(T, x=x, P=P, mu=mu, existence=existence, attrs=attrs)
        n, m = lik.gated.shape  # the gated pairs say the same as lik.gated.any(axis=1) and .any(axis=0)
        # hits (a track's life) and used peaks (no new track) count the pairs of the measurement part's own window
        # (all gated pairs but where it widens some tracks' gates: tracking/measurements.py ``widened_gates``)
        counts = getattr(self.measurements, "counted_pairs", None)
        k = np.ones(len(lik.pair_track), bool) if counts is None else counts(lik)
        return (T, (np.bincount(lik.pair_track[k], minlength=n) > 0)[rows],
                np.bincount(lik.pair_meas[k], minlength=m) > 0)

    def _plain_update(self, x_pred, P_pred, scan: Scan, attrs: dict):
        """Likelihoods, association weights and the PDA update of every track (steps 2-3)."""
        lik = self.measurements.likelihoods(x_pred, P_pred, scan, attrs)
        w = self.associator.weights(lik)
        from sonartrack.association.pda_mixture_kernel import pda_mixture_update_pairs  # numba: loaded on first use

        beta_pair = w.of_pairs(lik)
        x, P = pda_mixture_update_pairs(x_pred, P_pred, lik, w.beta0, beta_pair)
        return x, P, lik, w, self.measurements.after_update(attrs, lik, scan, beta_pair)

    def _grouped_update(self, x_pred, P_pred, scan: Scan, attrs: dict, pairs):
        """Steps 2-3 with each unresolved pair as one merged track (tracking/resolution.py); the members keep
        their own per-track quantities (a merged peak's amplitude is neither's)."""
        g = self.resolution.group(x_pred, P_pred, attrs, pairs)
        x_r, P_r, lik, w, attrs_r = self._plain_update(g.x, g.P, scan, g.attrs)
        x, P = self.resolution.split(g, x_r, P_r, x_pred, P_pred, g.attrs["sigma_p"])
        single = np.ones(len(x), bool)
        single[pairs.ravel()] = False
        out = {k: v.copy() for k, v in attrs.items()}
        for k, v in attrs_r.items():
            out[k][single] = v[g.rows[single]]
        return x, P, lik, w, g.rows, out

    def _scan(self, time_s, z, R, amplitude) -> Scan:
        k = self.measurements.measurement_dim
        z = np.asarray(z, float).reshape(-1, k)
        for name, value in (("R", R), ("amplitude", amplitude)):
            if value is None and name in self.measurements.scan_needs:
                raise InputError(f"{type(self.measurements).__name__} needs {name} with every scan")
        if R is not None:
            R = np.asarray(R, float)
            R = R if R.shape == (len(z), k, k) else np.broadcast_to(R, (len(z), k, k))
        if amplitude is not None:
            amplitude = np.asarray(amplitude, float).reshape(-1)
            if len(amplitude) != len(z):
                raise InputError(f"scan at t = {time_s} s has {len(z)} measurements but {len(amplitude)} amplitudes")
        finite = _all_finite(z) and (R is None or _all_finite(R))
        if not finite or (amplitude is not None and not _all_finite(amplitude)):
            raise InputError(f"scan at t = {time_s} s has NaN or infinite measurements: remove or fix those rows")
        if self._time is not None and not time_s > self._time:
            raise InputError(f"scan times must increase (got {time_s} s after {self._time} s)")
        return Scan(float(time_s), z, R, amplitude)


def _all_finite(a: np.ndarray) -> bool:
    """Whether every entry of ``a`` is finite. A NaN or infinite entry makes the sum NaN or infinite, so a finite
    sum (one reduction) settles it; only a non-finite one (such an entry, or an overflow) is checked entry by entry."""
    return math.isfinite(a.sum()) or bool(np.isfinite(a).all())
