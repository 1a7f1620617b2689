"""Deleter parts: after each update, confirm the tracks that earned it and delete the ones that lost it.

* :class:`ExistenceDeleter` (IPDA, paper P4): confirmed once the existence probability exceeds
  ``confirm_threshold`` (and then until deleted), deleted when it falls below ``terminate_threshold``.
* :class:`MOfNDeleter` (bearing tracks, paper P0 on user data): confirmed after a validated peak in
  ``confirm_m`` of its first ``confirm_n`` scans (else dropped), and deleted after ``delete_after``
  consecutive scans with an empty gate. Keeps the counters ``hits``, ``age``, ``misses`` in the
  tracks' ``attrs`` (a new track counts its initiating scan).
* :class:`RateConfirmation`: :class:`ExistenceDeleter` with the threshold from a stated false-track rate.

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
    """

    def __init__(self, false_tracks_per_h: float, scan_interval_s: float, initial_existence: float,
                 terminate_threshold: float, floor: float = 0.0):
        self.false_per_scan = float(false_tracks_per_h) * float(scan_interval_s) / 3600.0
        self.initial_existence, self.terminate_threshold, self.floor = initial_existence, terminate_threshold, floor
        self.started, self.scans = 0, 0

    @property
    def confirm_threshold(self) -> float:
        """The threshold now: tracks started per scan so far (at least one scan counted) into the rule."""
        from sonartrack.tracking.existence import confirm_threshold_for_rate

        rule = confirm_threshold_for_rate(self.false_per_scan, self.started / max(self.scans, 1),
                                          self.initial_existence)
        return max(float(rule), self.floor)

    def new_track_attrs(self, k: int) -> dict:
        """Count the ``k`` tracks started this scan (called once a scan); no per-track counters (an empty dict)."""
        self.started += int(k)
        self.scans += 1
        return {}

    def manage(self, T: TrackArrays, hit) -> TrackArrays:
        """Confirm above the rate's threshold; drop below ``terminate_threshold`` (as :class:`ExistenceDeleter`)."""
        return ExistenceDeleter(self.confirm_threshold, self.terminate_threshold).manage(T, hit)
