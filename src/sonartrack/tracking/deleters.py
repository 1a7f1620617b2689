"""Deleter parts: after each update, confirm the tracks that earned it and delete the ones that lost it.

* :class:`ExistenceDeleter` (IPDA, paper P4): confirmed once the existence probability exceeds
  ``confirm_threshold`` (and then until deleted), deleted when it falls below ``terminate_threshold``.
* :class:`MOfNDeleter` (bearing tracks, paper P0 on user data): confirmed after a validated peak in
  ``confirm_m`` of its first ``confirm_n`` scans (else dropped), and deleted after ``delete_after``
  consecutive scans with an empty gate. Keeps the counters ``hits``, ``age``, ``misses`` in the
  tracks' ``attrs`` (a new track counts its initiating scan).
* :class:`RateConfirmation`: :class:`ExistenceDeleter` with the threshold from a stated false-track rate.
* :class:`MinHits`: a wrapper that holds back the confirmation of a track with fewer than ``min_hits`` scans of
  contacts in its gate (counting its initiating one).

A deleter part has two methods, which the tracker calls every scan (the docstrings below say only what differs):

* ``new_track_attrs(k) -> dict``: the per-track counters of ``k`` (int) new tracks, each an array of shape (k,);
* ``manage(T, hit) -> TrackArrays``: the kept tracks, confirmation flags and counters updated, from ``T``
  (TrackArrays, the tracks after the update) and ``hit`` (ndarray of bool, shape (n,): whether each track's gate
  held a measurement this scan).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sonartrack.tracking.tracks import TrackArrays


@dataclass(frozen=True)
class ExistenceDeleter:
    """Confirm above ``confirm_threshold``, delete below ``terminate_threshold`` (existence probability)."""

    confirm_threshold: float
    terminate_threshold: float

    def new_track_attrs(self, k: int) -> dict:
        """Per-track counters this deleter keeps: none (an empty dict; protocol in the module docstring)."""
        return {}

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """Confirm tracks whose existence exceeds ``confirm_threshold``; drop those below ``terminate_threshold``
        (``hit`` is unused; protocol in the module docstring)."""
        T = replace(T, confirmed=T.confirmed | (T.existence > self.confirm_threshold))
        return T.select(T.existence >= self.terminate_threshold)


@dataclass(frozen=True)
class MOfNDeleter:
    """M-of-N confirmation and deletion after consecutive misses (module doc)."""

    confirm_m: int
    confirm_n: int
    delete_after: int

    def new_track_attrs(self, k: int) -> dict:
        """Initial M-of-N counters of ``k`` new tracks, the initiating scan counting as a hit: ``hits`` = 1,
        ``age`` = 1, ``misses`` = 0 (int arrays of shape (k,))."""
        return {"hits": np.ones(k, dtype=int), "age": np.ones(k, dtype=int), "misses": np.zeros(k, dtype=int)}

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """M-of-N confirmation, and deletion after ``delete_after`` consecutive empty gates (module docstring);
        ``T.attrs`` holds ``hits``, ``age`` and ``misses``."""
        a = T.attrs
        hits, age = a["hits"] + hit, a["age"] + 1
        misses = np.where(hit, 0, a["misses"] + 1)
        keep = (misses < self.delete_after) & (T.confirmed | (age < self.confirm_n) | (hits >= self.confirm_m))
        T = replace(T, confirmed=T.confirmed | (hits >= self.confirm_m)).with_attrs(hits=hits, age=age, misses=misses)
        return T.select(keep)


class RateConfirmation:
    """IPDA confirmation at a stated false-track rate: the threshold from the tracks started so far (existence.py
    :func:`~sonartrack.tracking.existence.confirm_threshold_for_rate`), never below ``floor``; deletion below
    ``terminate_threshold``. Counts the tracks the initiator starts and the scans (stateful, one per tracker).

    ``statistic`` says what is held against the threshold. "existence": IPDA's existence probability (P4).
    "likelihood_ratio": the quantity the rule bounds, the track's initial odds times the product of its scans'
    Lambda (Ville's inequality is on O_0 prod_j Lambda_j, existence.py), kept in ``attrs["log_lr_odds"]`` (the
    tracker adds each scan's ln Lambda: tracking/multi_target.py). Why: with p11 < 1 the existence's predicted odds
    are capped at p11 / (1 - p11) (49 at p11 0.98; Musicki, Evans, Stankovic 1994, eq. 11), below the rule's odds
    at 1 false track/h (threshold 0.987-0.997, odds 75-330, on study active-chain's LFM trials 2, 14, 18), so the
    existence crosses it only on a scan whose own hit lifts the odds from that cap by the rest (0.9-1.8 nats), and
    every scan near the cap loses 0.5-1.2 nats to the prediction (trial 14: a target whose contacts fed one track on
    pings 3-9 lost 2.0 nats so, confirmed at ping 9 where the likelihood ratio crossed at ping 8). A track the
    existence confirms is confirmed here too (both tests are kept; with p21 = 0 the existence's odds never exceed the
    likelihood ratio's), and the rule's bound is the same (it was derived for this statistic); the existence still
    deletes and is still reported. Measured (benchmarks/bench_acquisition.py, study trials 2, 14, 18, LFM): latency
    one ping less on 5 of 10 targets, held counted pings 441 -> 448 of 760, no false confirmed track on the 1 h
    reverberation-only twins of trials 14, 18, 10, nor on bench_active_rows.py's LFM seeds 1-2.

    Parameters
    ----------
    false_tracks_per_h : float
        Stated false confirmed tracks per hour.
    scan_interval_s : float
        Time between scans (s): turns the rate per hour into one per scan.
    initial_existence : float
        Existence of a new track.
    terminate_threshold : float
        A track whose existence falls below this is deleted.
    floor : float
        Lowest threshold whatever the count (0: the rule alone).
    statistic : {"existence", "likelihood_ratio"}
        What is held against the threshold (above).
    """

    def __init__(self, false_tracks_per_h: float, scan_interval_s: float, initial_existence: float,
                 terminate_threshold: float, floor: float = 0.0, statistic: str = "existence"):
        from sonartrack.core.errors import require

        require(statistic in ("existence", "likelihood_ratio"),
                f"statistic must be 'existence' or 'likelihood_ratio', not {statistic!r}")
        self.false_per_scan = float(false_tracks_per_h) * float(scan_interval_s) / 3600.0
        self.initial_existence, self.terminate_threshold, self.floor = initial_existence, terminate_threshold, floor
        self.statistic = statistic
        self.started, self.scans = 0, 0

    @property
    def confirm_threshold(self) -> float:
        """The threshold now: tracks started per scan so far (at least one scan counted) into the rule."""
        from sonartrack.tracking.existence import confirm_threshold_for_rate

        rule = confirm_threshold_for_rate(self.false_per_scan, self.started / max(self.scans, 1),
                                          self.initial_existence)
        return max(float(rule), self.floor)

    def new_track_attrs(self, k: int) -> dict:
        """Count the ``k`` tracks started this scan (called once a scan); per track, with the likelihood-ratio
        statistic, ``log_lr_odds`` NaN (the tracker starts it at the track's log odds at its first update)."""
        self.started += int(k)
        self.scans += 1
        return {"log_lr_odds": np.full(int(k), np.nan)} if self.statistic == "likelihood_ratio" else {}

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """Confirm above the rate's threshold (existence, or the likelihood-ratio odds: class doc); drop below
        ``terminate_threshold`` (as :class:`ExistenceDeleter`)."""
        threshold = self.confirm_threshold
        if self.statistic == "likelihood_ratio" and "log_lr_odds" in T.attrs:
            with np.errstate(invalid="ignore"):
                earned = T.attrs["log_lr_odds"] > np.log(threshold / (1.0 - threshold))
            T = replace(T, confirmed=T.confirmed | earned)
        return ExistenceDeleter(threshold, self.terminate_threshold).manage(T, hit)


class StillHold:
    """A deleter part that runs ``inner``, then takes back the confirmation a track has just earned while it sits on
    a recurring world position and moves slower than ``slow_mps``: such a track may be a still clutter point that the
    clutter map (detection/clutter_map.py) has not yet shown to be still. Its confirmation waits until its speed
    shows it moving (a target; the track's own velocity, as the brief of issue 34 item 2 allows) or the map
    withholds the point's contacts (the track then starves). A target slower than ``slow_mps`` is held back the
    same way: the price, stated in the clutter map's settings. The hold is kept, once taken, until the track's speed
    shows it moving, whether or not it still sits on a recurring position: a still point's mirror twin is itself
    still while the array runs straight and moves off when the array turns, and a track held on the twin till then
    would otherwise be confirmed the moment the twin leaves it (measured on the independent generator's K 1 world
    with 6 points of 35 dB: 7 of 10 false confirmed tracks in 2 h, all at the ownship's turn, speed ~0).

    Parameters
    ----------
    inner : deleter part
        The tracker's own deleter (e.g. :class:`RateConfirmation`).
    slow_mps : float
        A track slower than this (combined state's speed, m/s) is not confirmed on a recurring position.
    gamma : float
        Gate (chi-square(2)) on a recurring contact's position against a track's: d^2 with P_pos + R.
    moving_gamma : float or None
        When set, a track's speed "shows it moving" only when its velocity's confidence ellipse (chi-square(2)
        quantile ``moving_gamma``, the track's own velocity covariance P_vv) lies outside the disc of radius
        ``slow_mps``: |v| - sqrt(moving_gamma lambda_max(P_vv)) > slow_mps (the clutter map's stillness test turned
        round). None: the speed estimate alone, |v| >= slow_mps. Why: a young track's speed is noise; on study
        active-chain trial 8 (LFM 32 x 0.25 m, K +10 dB, 14 points; benchmarks/bench_active_family.py) a track on a
        TS 24 dB point was confirmed at ping 7, before the clutter map's verdict at ping 9, and held 25 pings at
        0.18 m/s: at chi2_2 0.9 (4.61) the reverberation-only twin's 20 min went 2 -> 0 false confirmed tracks; on
        the default scene (bench_active_rows.py, cached contacts) LFM seed 1's held % 74/73/85/99 -> 70/69/84/98
        (confirmations later), seed 2 unchanged and its row holding two targets gone, CW rows 4 -> 5 and 6 -> 6.
    """

    def __init__(self, inner, slow_mps: float, gamma: float, moving_gamma: float | None = None):
        self.inner, self.slow_mps, self.gamma = inner, float(slow_mps), float(gamma)
        self.moving_gamma = None if moving_gamma is None else float(moving_gamma)
        self.xy, self.R = np.zeros((0, 2)), np.zeros((0, 2, 2))
        self.held = np.zeros(0, np.int64)  # ids of the tracks whose confirmation has been taken back

    def recurring(self, xy: np.ndarray, R: np.ndarray) -> None:
        """This scan's recurring contacts (the clutter map's; world positions m, covariances m^2)."""
        self.xy, self.R = np.asarray(xy, float).reshape(-1, 2), np.asarray(R, float).reshape(-1, 2, 2)

    def new_track_attrs(self, k: int) -> dict:
        """The inner deleter's per-track counters (``inner.new_track_attrs(k)``)."""
        return self.inner.new_track_attrs(k)

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """The inner deleter's confirmation and deletion, then the hold of the class doc.

        Parameters
        ----------
        T : TrackArrays
            Tracks after the update.
        hit : ndarray of bool, shape (n,)
            Passed to ``inner``.

        Returns
        -------
        TrackArrays
            The kept tracks, a slow new confirmation on a recurring position taken back.
        """
        from sonartrack.tracking.tracks import TrackSnapshot

        before = set(T.track_id[T.confirmed].tolist())
        T = self.inner.manage(T, hit)
        new = T.confirmed & ~np.isin(T.track_id, list(before))
        self.held = self.held[np.isin(self.held, T.track_id)]
        if not new.any() or not (len(self.xy) or len(self.held)):
            return T
        snap = TrackSnapshot.of(0.0, T.select(new))
        slow = self._slow(snap)
        near = np.isin(snap.track_id, self.held)
        if len(self.xy):
            d = snap.x[:, None, :2] - self.xy[None]
            S = snap.P[:, None, :2, :2] + self.R[None]
            near |= (np.einsum("tci,tcij,tcj->tc", d, np.linalg.inv(S), d) <= self.gamma).any(axis=1)
        confirmed = T.confirmed.copy()
        confirmed[np.nonzero(new)[0][slow & near]] = False
        self.held = np.union1d(self.held, snap.track_id[slow & near])
        return replace(T, confirmed=confirmed)

    def _slow(self, snap) -> np.ndarray:
        """The tracks whose speed does not show them moving (``moving_gamma``, class doc)."""
        speed = np.hypot(snap.x[:, 2], snap.x[:, 3])
        if self.moving_gamma is None:
            return speed < self.slow_mps
        spread = np.sqrt(self.moving_gamma * np.linalg.eigvalsh(snap.P[:, 2:4, 2:4])[:, -1])
        return speed - spread <= self.slow_mps


class MinHits:
    """A deleter part that runs ``inner`` and takes back the confirmation a track has just earned with fewer than
    ``min_hits`` scans of measurements in its gate (its initiating scan counts one); the track stays tentative until
    it has them (or is deleted). Keeps the counter ``hits`` in the tracks' ``attrs``.

    Why: IPDA's existence grows by Lambda = 1 - P_D P_G + P_D sum_i p(z_i) / lambda per scan (Musicki, Evans,
    Stankovic 1994, eq. 29); where the clutter density lambda the tracker assumes is low (a CW's few contacts spread
    over the whole listening disc, systems/active/cw_tracking.py) one contact in the wide gate of a one-point track
    (velocity prior 5 m/s: a gate of 500-700 m after 30 s) multiplies the odds by 10^2-10^3, and a track of two
    contacts, i.e. any pair of contacts closer than the gate on consecutive pings, is confirmed at its first update
    (measured on the default scene as CW, seed 1: 5 confirmed tracks of 1 ping and 3 of 2, at 15-25 kn). Ville's
    bound (existence.py) holds only where the clutter is as dense as assumed; the contacts cluster (a target's
    several detections and their mirrors, the reverberation near the array), so the bound is not kept there. A third
    scan in the gate of the track's own predicted motion is a test on the velocity the first two contacts made up.

    Parameters
    ----------
    inner : deleter part
        The confirming deleter (e.g. :class:`RateConfirmation`).
    min_hits : int
        Fewest scans with a measurement in the gate before a track may be confirmed.
    """

    def __init__(self, inner, min_hits: int):
        self.inner, self.min_hits = inner, int(min_hits)

    def new_track_attrs(self, k: int) -> dict:
        """The inner deleter's counters and ``hits`` = 1 (the initiating scan) for ``k`` new tracks."""
        return {**self.inner.new_track_attrs(k), "hits": np.ones(k, dtype=int)}

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """Count this scan's hits, run ``inner``, and take back new confirmations short of ``min_hits``.

        Parameters
        ----------
        T : TrackArrays
            Tracks after the update (``attrs["hits"]`` their scans with a measurement in the gate so far).
        hit : ndarray of bool, shape (n,)
            Whether each track's gate held a measurement this scan (passed to ``inner``).

        Returns
        -------
        TrackArrays
            The kept tracks, their ``hits`` counted.
        """
        before = T.confirmed.copy()
        T = T.with_attrs(hits=T.attrs["hits"] + np.asarray(hit, dtype=int))
        keep_id = T.track_id
        out = self.inner.manage(T, hit)
        was = np.isin(out.track_id, keep_id[before])
        early = out.confirmed & ~was & (out.attrs["hits"] < self.min_hits)
        return replace(out, confirmed=out.confirmed & ~early) if early.any() else out


def listed_tracks(confirmed, existence, listed_existence: float | None):
    """The confirmed tracks a user is shown: those whose existence is at least ``listed_existence`` (None: every
    confirmed track, P4). The tracker's own confirmation (what the deleter parts keep: claims, merges, side
    decisions, the clutter map's contacts) is not changed; only the listing.

    Why. IPDA's existence is the posterior probability that the track's target exists (Musicki, Evans, Stankovic
    1994, eq. 29), and P4 keeps a track confirmed until it is deleted at the termination level. With no contact in
    its gate the predicted odds are at most p11 / (1 - p11) (49 at p11 0.98; eq. 11) and each scan multiplies them by
    about p11 (1 - P_D P_G) (0.59 at a CW's P_D 0.4), so from the cap to the termination level 0.01 a confirmed track
    is listed ln(49 / 0.0101) / ln(1 / 0.59) ~ 16 scans on nothing (measured on the study active-chain's CW twins,
    trials 11 and 1, benchmarks/bench_cw_confirm.py: false tracks listed 12-14 pings after their last contact).
    Below 1/2 the track is more likely no target than a target. Measured as the confirmation flag itself (a track
    below the level unconfirmed until it re-crossed the threshold) the chain's machinery that keys on it split and
    joined the default CW scene's rows (bench_active_rows.py seed 2: 4 -> 7 rows), hence the listing alone. Its price:
    a target's row is unlisted over its own missed scans too (default scene as CW, held % of detectable pings 90/88
    -> 85/82 at 0.5, 88/86 at 0.2).

    Parameters
    ----------
    confirmed : ndarray of bool, shape (n,)
        The tracker's confirmation flags.
    existence : ndarray, shape (n,)
        The tracks' existence probabilities.
    listed_existence : float or None
        The level (settings ``listed_existence``).

    Returns
    -------
    ndarray of bool, shape (n,)
        Listed tracks.
    """
    confirmed = np.asarray(confirmed, bool)
    if listed_existence is None:
        return confirmed
    return confirmed & (np.asarray(existence, float) >= float(listed_existence))
