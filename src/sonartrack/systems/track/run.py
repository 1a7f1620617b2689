"""The track system: a tracker over a user's whole record, typed records in and out.

* :func:`run_contacts` -- contacts (points with covariances) -> position tracks, IPDA / IMM-IPDA with track
  management (paper P4; tracking/run.py :func:`~sonartrack.tracking.run.track_contacts`);
* :func:`run_peaks` -- bearing peaks -> bearing tracks, JPDA_A with eq. 9 track strengths or JPDA (paper
  P0), tracks started on strong peaks and confirmed M-of-N (:func:`~sonartrack.tracking.run.track_peaks`).

Reading and writing the files is files.py's; the pictures are report/figures' (drawn by the command line).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.acoustics.xcorr_bearing import PeakRecord
from sonartrack.io.contacts import Contacts
from sonartrack.systems.track.settings import ContactsTrackSettings, PeaksTrackSettings
from sonartrack.tracking.run import BearingTracks, PositionTracks, track_contacts, track_peaks


def _n_scans(time_s: np.ndarray) -> int:
    return len(set(np.asarray(time_s).tolist()))


@dataclass(frozen=True, slots=True)
class ContactTrackResult:
    """Position tracks of a contacts record: the contacts tracked and the tracks (one row per track per scan)."""

    contacts: Contacts
    tracks: PositionTracks

    @property
    def n_confirmed(self) -> int:
        """Number of distinct tracks confirmed at some scan."""
        return len(np.unique(self.tracks.track_id[self.tracks.confirmed]))

    def summary(self) -> str:
        """One line: scans, contacts and confirmed tracks.

        Returns
        -------
        str
            "S scans, C contacts -> N confirmed track(s)".
        """
        t = self.contacts.time_s
        return f"{_n_scans(t)} scans, {len(t)} contacts -> {self.n_confirmed} confirmed track(s)"


@dataclass(frozen=True, slots=True)
class PeakTrackResult:
    """Bearing tracks of a peaks record: the peaks tracked, the tracks and the associator used."""

    peaks: PeakRecord
    tracks: BearingTracks
    associator: str

    @property
    def name(self) -> str:
        """The tracker's name as printed: JPDA or JPDA-A."""
        return self.associator.upper().replace("_", "-")

    def summary(self) -> str:
        """One line: scans, peaks, confirmed and started tracks.

        Returns
        -------
        str
            "track NAME: S scans, P peaks, N confirmed track(s) (M started)".
        """
        tr, t = self.tracks, self.peaks.time_s
        n_confirmed = len(np.unique(tr.track_id[tr.confirmed.astype(bool)]))
        return (f"track {self.name.lower()}: {_n_scans(t)} scans, {len(t)} peaks, {n_confirmed} confirmed track(s) "
                f"({len(np.unique(tr.track_id))} started)")


def run_contacts(data: Contacts, settings: ContactsTrackSettings | None = None, *,
                 confirmed_only: bool = False) -> ContactTrackResult:
    """Track a record of contacts with the position tracker (IPDA / IMM-IPDA, paper P4).

    Parameters
    ----------
    data : Contacts
        Contact times (s), positions (m) and covariances (m^2), sorted by time; rows sharing a time are one scan
        (io/contacts.py reads them from a file).
    settings : ContactsTrackSettings, optional
        The system's settings; only ``settings.tracker`` acts here (the input errors act when reading).
    confirmed_only : bool
        Keep confirmed tracks only.

    Returns
    -------
    ContactTrackResult
        The contacts and their position tracks.
    """
    s = settings or ContactsTrackSettings()
    tracks = track_contacts(data.time_s, data.z, data.R, s.tracker, confirmed_only=confirmed_only)
    return ContactTrackResult(data, tracks)


def run_peaks(record: PeakRecord, settings: PeaksTrackSettings | None = None) -> PeakTrackResult:
    """Track a record of bearing peaks with JPDA_A or JPDA (paper P0), with automatic initiation.

    Parameters
    ----------
    record : PeakRecord
        Peak times (s), cone angles (deg) and amplitudes, sorted by time (io/peaks.py reads them).
    settings : PeaksTrackSettings, optional
        The associator (``jpda_a`` weighs peak amplitudes, ``jpda`` ignores them) and the bearing tracker.

    Returns
    -------
    PeakTrackResult
        The peaks and their bearing tracks.
    """
    s = settings or PeaksTrackSettings()
    tracks = track_peaks(record.time_s, record.bearing_deg, record.amplitude, s.tracker,
                         amplitude_aided=s.associator == "jpda_a")
    return PeakTrackResult(record, tracks, s.associator)
