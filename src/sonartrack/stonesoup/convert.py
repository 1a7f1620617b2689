"""Converters between sonartrack's arrays and files and Stone Soup's types.

Two conventions differ and are converted here, nowhere else:

* time: sonartrack counts seconds (``time_s``), Stone Soup stamps ``datetime``s; ``epoch`` is the
  datetime of time_s = 0 (default :data:`EPOCH`).
* state order: sonartrack's Cartesian state is [x, y, vx, vy]; Stone Soup's two-axis constant velocity
  model (``CombinedLinearGaussianTransitionModel([ConstantVelocity, ConstantVelocity])``) is
  [x, vx, y, vy]. ``order`` (default :data:`STONESOUP_ORDER`) lists, for each Stone Soup state entry, the
  sonartrack entry it holds: x_ss = x_ours[order], P_ss = P_ours[order][:, order]. Pass ``order=None``
  for states that need no reordering (bearing trackers: [bearing, bearing rate]).

Detections: contacts (io/contacts.py: points with their own covariances R_m) become ``Detection``s with a
``LinearGaussian`` model each; bearing peaks (io/peaks.py: cone angle in degrees, amplitude) become
``Detection``s in radians with ``metadata["amplitude"]`` (what JPDA_A reads, stonesoup/amplitude.py);
rows flagged as clutter become ``Clutter``. Tracks: our ``TrackSnapshot`` arrays <-> ``Track``s of
``GaussianState``s (existence and confirmation in the metadata, stonesoup/tracks.py). Truth: state arrays
<-> ``GroundTruthPath``s.
"""

from __future__ import annotations

import datetime
from collections.abc import Iterable, Sequence

import numpy as np
from stonesoup.models.measurement.linear import LinearGaussian
from stonesoup.types.detection import Clutter, Detection
from stonesoup.types.groundtruth import GroundTruthPath, GroundTruthState
from stonesoup.types.state import GaussianState

from sonartrack.core.errors import InputError
from sonartrack.stonesoup.amplitude import AMPLITUDE
from sonartrack.stonesoup.tracks import CONFIRMED, EXISTENCE, STRENGTH, ExistenceTrack, stage
from sonartrack.tracking.tracks import TrackSnapshot

#: the datetime of time_s = 0 unless told otherwise
EPOCH = datetime.datetime(2000, 1, 1)
#: Stone Soup's [x, vx, y, vy] from sonartrack's [x, y, vx, vy]
STONESOUP_ORDER = (0, 2, 1, 3)

Scans = list[tuple[datetime.datetime, set]]


def to_timestamp(time_s: float, epoch: datetime.datetime = EPOCH) -> datetime.datetime:
    """The datetime ``time_s`` seconds after ``epoch``.

    Parameters
    ----------
    time_s : float
        Time (s) after the epoch.
    epoch : datetime.datetime
        The datetime of time_s = 0 (default :data:`EPOCH`).

    Returns
    -------
    datetime.datetime
        ``epoch + time_s``.
    """
    return epoch + datetime.timedelta(seconds=float(time_s))


def to_seconds(timestamp: datetime.datetime, epoch: datetime.datetime = EPOCH) -> float:
    """Seconds from ``epoch`` to ``timestamp``.

    Parameters
    ----------
    timestamp : datetime.datetime
        The time stamp.
    epoch : datetime.datetime
        As in :func:`to_timestamp`.

    Returns
    -------
    float
        ``timestamp - epoch`` in s.
    """
    return (timestamp - epoch).total_seconds()


def _inverse(order):
    return None if order is None else tuple(int(i) for i in np.argsort(order))


def _reorder(x, P, order):
    """(x[order], P[order][:, order]) over the last axes; unchanged for order None."""
    if order is None:
        return np.asarray(x, float), np.asarray(P, float)
    o = list(order)
    return np.asarray(x, float)[..., o], np.asarray(P, float)[..., o, :][..., :, o]


def detections_from_arrays(time_s, z, R=None, *, measurement_model=None, ndim_state: int = 4,
                           mapping: Sequence[int] = (0, 2), amplitude=None, clutter=None,
                           epoch: datetime.datetime = EPOCH) -> Scans:
    """Scans [(timestamp, set of detections)] in time order from rows ``time_s (k,)``, ``z (k, m)``.

    Each row gets ``measurement_model``, or (when None) ``LinearGaussian(ndim_state, mapping, R[i])`` with
    its own covariance ``R (k, m, m)``. ``amplitude (k,)`` goes to ``metadata["amplitude"]``; rows where
    ``clutter (k,)`` is True become ``Clutter``.

    Parameters
    ----------
    time_s : array_like, shape (k,)
        Detection times (s after ``epoch``); equal times form one scan.
    z : array_like, shape (k, m)
        Measurements (units of the state entries they measure: m, rad ...).
    R : array_like, shape (k, m, m) or broadcastable, optional
        Measurement covariances; needed when ``measurement_model`` is None.
    measurement_model : MeasurementModel, optional
        One model for every detection.
    ndim_state : int
        State dimension of the built LinearGaussian models.
    mapping : sequence of int
        State entries measured by the built models (default (0, 2): x and y in Stone Soup's [x, vx, y, vy]).
    amplitude : array_like, shape (k,), optional
        Detection amplitudes (metadata).
    clutter : array_like of bool, shape (k,), optional
        Rows that are clutter.
    epoch : datetime.datetime
        As in :func:`to_timestamp`.

    Returns
    -------
    list of (datetime.datetime, set of Detection)
        One scan per distinct time, in time order.
    """
    t = np.asarray(time_s, float).reshape(-1)
    z = np.asarray(z, float).reshape(len(t), -1)
    if measurement_model is None and R is None:
        raise InputError("give each detection a covariance R (k, m, m) or one measurement_model")
    if R is not None:
        R = np.broadcast_to(np.asarray(R, float), (len(t), z.shape[1], z.shape[1]))
    flags = np.zeros(len(t), bool) if clutter is None else np.asarray(clutter, bool).reshape(-1)
    scans: dict[float, set] = {}
    for i in np.argsort(t, kind="stable"):
        model = measurement_model or LinearGaussian(ndim_state, tuple(mapping), R[i])
        meta = {} if amplitude is None else {AMPLITUDE: float(amplitude[i])}
        cls = Clutter if flags[i] else Detection
        scans.setdefault(float(t[i]), set()).add(
            cls(z[i].reshape(-1, 1), timestamp=to_timestamp(t[i], epoch), measurement_model=model, metadata=meta))
    return [(to_timestamp(tk, epoch), dets) for tk, dets in scans.items()]


def detections_from_contacts(contacts, *, ndim_state: int = 4, mapping: Sequence[int] = (0, 2),
                             epoch: datetime.datetime = EPOCH, **read_options) -> Scans:
    """Scans of ``Detection``s from a :class:`~sonartrack.io.contacts.Contacts` or a contacts file path
    (``read_options`` go to :func:`~sonartrack.io.contacts.read_contacts`): x_m, y_m with their covariances.

    Parameters
    ----------
    contacts : Contacts or str or Path
        The contacts (positions in m, covariances in m^2) or their file.
    ndim_state : int
        State dimension of the detections' LinearGaussian models.
    mapping : sequence of int
        State entries measured (default x and y of Stone Soup's [x, vx, y, vy]).
    epoch : datetime.datetime
        As in :func:`to_timestamp`.
    **read_options
        Passed to ``read_contacts`` when a path is given.

    Returns
    -------
    list of (datetime.datetime, set of Detection)
        One scan per distinct time, in time order.
    """
    if not hasattr(contacts, "z"):
        from sonartrack.io.contacts import read_contacts

        contacts = read_contacts(contacts, **read_options)
    return detections_from_arrays(contacts.time_s, contacts.z, contacts.R, ndim_state=ndim_state, mapping=mapping,
                                  epoch=epoch)


def detections_from_peaks(peaks, *, bearing_sigma_deg: float | None = None, measurement_model=None,
                          epoch: datetime.datetime = EPOCH) -> Scans:
    """Scans of bearing ``Detection``s (cone angle in rad, amplitude in metadata) from a
    :class:`~sonartrack.acoustics.xcorr_bearing.PeakRecord` or a peaks file path. The measurement model is
    ``measurement_model`` or LinearGaussian on state [bearing, rate] with sigma ``bearing_sigma_deg``.

    Parameters
    ----------
    peaks : PeakRecord or str or Path
        The peaks (``bearing_deg``: cone angle in degrees) or their file.
    bearing_sigma_deg : float, optional
        Bearing standard deviation (deg); needed when ``measurement_model`` is None.
    measurement_model : MeasurementModel, optional
        One model for every detection.
    epoch : datetime.datetime
        As in :func:`to_timestamp`.

    Returns
    -------
    list of (datetime.datetime, set of Detection)
        The scans as :func:`detections_from_arrays` returns them, bearings in rad.
    """
    if not hasattr(peaks, "amplitude"):
        from sonartrack.io.peaks import read_peaks_csv

        peaks = read_peaks_csv(peaks)
    if measurement_model is None:
        if bearing_sigma_deg is None:
            raise InputError("give bearing_sigma_deg (the peaks' bearing standard deviation) or a measurement_model")
        measurement_model = LinearGaussian(2, (0,), np.array([[np.deg2rad(bearing_sigma_deg) ** 2]]))
    return detections_from_arrays(peaks.time_s, np.deg2rad(np.asarray(peaks.bearing_deg, float)),
                                  measurement_model=measurement_model, amplitude=np.asarray(peaks.amplitude, float),
                                  epoch=epoch)


def detections_to_arrays(detections: Iterable) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``z (m, k)``, ``R (m, k, k)`` (each detection's measurement-model covariance) and ``amplitude (m,)``
    (NaN where a detection has none) of one scan's detections, in iteration order.

    Parameters
    ----------
    detections : iterable of Detection
        One scan's m detections (each with a measurement model).

    Returns
    -------
    z : ndarray, shape (m, k)
        Measurements.
    R : ndarray, shape (m, k, k)
        Their covariances.
    amplitude : ndarray, shape (m,)
        ``metadata["amplitude"]``, NaN where absent.
    """
    dets = list(detections)
    if not dets:
        return np.zeros((0, 0)), np.zeros((0, 0, 0)), np.zeros(0)
    z = np.array([np.asarray(d.state_vector, float).ravel() for d in dets])
    R = np.array([np.asarray(d.measurement_model.covar(), float) for d in dets])
    amp = np.array([float((d.metadata or {}).get(AMPLITUDE, np.nan)) for d in dets])
    return z, R, amp


def tracks_from_snapshots(snapshots: Sequence[TrackSnapshot], *, order=STONESOUP_ORDER,
                          epoch: datetime.datetime = EPOCH) -> set:
    """``ExistenceTrack``s (id = str(track_id)) of ``GaussianState``s, one per snapshot a track appears in;
    each state's metadata holds the existence (when finite), confirmation and strength of that scan.

    Parameters
    ----------
    snapshots : sequence of TrackSnapshot
        Our track snapshots (state [x, y, vx, vy] in m and m/s), in time order.
    order : sequence of int or None
        For each Stone Soup state entry, the sonartrack entry it holds (default :data:`STONESOUP_ORDER`); None: no
        reordering.
    epoch : datetime.datetime
        As in :func:`to_timestamp`.

    Returns
    -------
    set of ExistenceTrack
        One Stone Soup track per track id.
    """
    tracks: dict[int, ExistenceTrack] = {}
    for snap in snapshots:
        x, P = _reorder(snap.x, snap.P, order)
        strength = snap.attrs.get("strength")
        for i, tid in enumerate(snap.track_id):
            track = tracks.setdefault(int(tid), ExistenceTrack(id=str(int(tid))))
            meta = {CONFIRMED: bool(snap.confirmed[i])}
            if np.isfinite(snap.existence[i]):
                meta[EXISTENCE] = float(snap.existence[i])
            if strength is not None:
                meta[STRENGTH] = float(strength[i])
            stage(track, **meta)
            track.append(GaussianState(x[i].reshape(-1, 1), P[i], timestamp=to_timestamp(snap.time_s, epoch)))
    return set(tracks.values())


def _state_at(track, timestamp):
    """(state, its metadata) of ``track`` at ``timestamp``, or None."""
    for state, meta in zip(track.states, track.metadatas, strict=True):
        if state.timestamp == timestamp:
            return state, meta
    return None


def _stack_states(states, order):
    """x (n, d), P (n, d, d) in our order from Stone Soup states."""
    if not states:
        d = len(order) if order else 0
        return np.zeros((0, d)), np.zeros((0, d, d))
    x = np.array([np.asarray(s.state_vector, float).ravel() for s in states])
    P = np.array([np.asarray(s.covar, float) for s in states])
    return _reorder(x, P, _inverse(order))


def _id_key(track_id):
    """Numeric ids in numeric order, then the others in text order."""
    text = str(track_id)
    return (0, int(text), "") if text.isdigit() else (1, 0, text)


def snapshot_from_tracks(tracks: Iterable, timestamp: datetime.datetime, *, order=STONESOUP_ORDER,
                         epoch: datetime.datetime = EPOCH) -> TrackSnapshot:
    """Our ``TrackSnapshot`` of the tracks that have a state at ``timestamp`` (one mode, mu = 1), in id order.
    Ids that are not numbers become the track's rank; existence is NaN where the metadata has none.

    Parameters
    ----------
    tracks : iterable of Track
        Stone Soup tracks.
    timestamp : datetime.datetime
        The scan time.
    order, epoch : sequence of int or None, datetime.datetime
        As in :func:`tracks_from_snapshots` and :func:`to_timestamp`.

    Returns
    -------
    TrackSnapshot
        States and covariances in our order, confirmation, existence, the first state's covariance as ``P_init``,
        birth times (s) and the strength (``attrs``) when every track has one.
    """
    live = sorted(((tr, _state_at(tr, timestamp)) for tr in tracks), key=lambda p: _id_key(p[0].id))
    live = [(tr, *found) for tr, found in live if found is not None]
    x, P = _stack_states([state for _, state, _ in live], order)
    _, P0 = _stack_states([tr.states[0] for tr, _, _ in live], order)
    metas = [meta for _, _, meta in live]
    ids = [int(tr.id) if str(tr.id).isdigit() else k for k, (tr, _, _) in enumerate(live)]
    attrs = {}
    if metas and all(STRENGTH in m for m in metas):
        attrs["strength"] = np.array([float(m[STRENGTH]) for m in metas])
    return TrackSnapshot(time_s=to_seconds(timestamp, epoch), track_id=np.array(ids, dtype=np.int64),
                         confirmed=np.array([bool(m.get(CONFIRMED, False)) for m in metas], dtype=bool),
                         existence=np.array([float(m.get(EXISTENCE, np.nan)) for m in metas]), x=x, P=P,
                         mu=np.ones((len(live), 1)), P_init=P0,
                         born_s=np.array([to_seconds(tr.states[0].timestamp, epoch) for tr, _, _ in live]), attrs=attrs)


def groundtruth_paths(time_s, states, *, order=STONESOUP_ORDER, ids: Sequence | None = None,
                      epoch: datetime.datetime = EPOCH) -> list[GroundTruthPath]:
    """One ``GroundTruthPath`` per target from ``states (n_targets, k, d)`` at ``time_s (k,)`` (our state order).

    Parameters
    ----------
    time_s : array_like, shape (k,)
        Times (s after ``epoch``).
    states : array_like, shape (n_targets, k, d) or (k, d)
        True states in our order ([x, y, vx, vy]: m, m/s).
    order : sequence of int or None
        As in :func:`tracks_from_snapshots`.
    ids : sequence, optional
        Path ids (default 0, 1, ...; stored as strings).
    epoch : datetime.datetime
        As in :func:`to_timestamp`.

    Returns
    -------
    list of GroundTruthPath
        One path per target.
    """
    t = np.asarray(time_s, float).reshape(-1)
    s = np.asarray(states, float)
    if s.ndim == 2:
        s = s[None]
    if s.shape[1] != len(t):
        raise InputError(f"states must be (targets, {len(t)} times, d), got {s.shape}")
    x, _ = _reorder(s, np.zeros(s.shape[:2] + (s.shape[2], s.shape[2])), order)
    ids = [str(i) for i in (ids if ids is not None else range(len(s)))]
    return [GroundTruthPath([GroundTruthState(x[n, k].reshape(-1, 1), timestamp=to_timestamp(t[k], epoch))
                             for k in range(len(t))], id=ids[n]) for n in range(len(s))]


def groundtruth_to_arrays(path: GroundTruthPath, *, order=STONESOUP_ORDER,
                          epoch: datetime.datetime = EPOCH) -> tuple[np.ndarray, np.ndarray]:
    """``time_s (k,)`` and ``states (k, d)`` (our state order) of one ground-truth path.

    Parameters
    ----------
    path : GroundTruthPath
        The path.
    order, epoch : sequence of int or None, datetime.datetime
        As in :func:`tracks_from_snapshots` and :func:`to_timestamp`.

    Returns
    -------
    time_s : ndarray, shape (k,)
        Times (s after ``epoch``).
    states : ndarray, shape (k, d)
        States in our order.
    """
    t = np.array([to_seconds(s.timestamp, epoch) for s in path.states])
    x = np.array([np.asarray(s.state_vector, float).ravel() for s in path.states])
    inv = _inverse(order)
    return t, (x if inv is None else x[:, list(inv)])
