"""Tracking of narrowband lines in frequency and bearing, and grouping of lines into sources (harmonic families).

Input: tonal line detections per integration period (acoustics/lofar.py ``detect_lines``): time, cone angle,
frequency, SNR. A line track's state is x = [f, fdot, theta, thetadot] (Hz, Hz/s, deg, deg/s), two independent
nearly-constant-velocity models (Bar-Shalom, Li & Kirubarajan, Estimation with Applications to Tracking and
Navigation, sec. 6.3.2, the continuous white-noise acceleration model): per axis, with period T,

    F = [[1, T], [0, 1]],   Q = q [[T^3/3, T^2/2], [T^2/2, T]],   z = [f, theta] + v,  v ~ N(0, diag(sf^2, st^2))

and the Kalman filter's predict / update (ibid. sec. 5.2.4). Association each period: global nearest
neighbour by a greedy assignment on the normalised distance d^2 = nu^T S^-1 nu (the pair of least d^2 first),
inside the chi-square gate d^2 <= ``gate`` (2 degrees of freedom). A detection that no track takes starts a
tentative track (velocity zero, velocity variances from the largest rates); a tentative track is confirmed
with detections in M of its first N periods (``confirm_m`` of ``confirm_n``) and dropped when it fails; any
track ends after ``max_misses`` periods in a row without a detection.

Sources: confirmed tracks whose bearing histories agree (RMS cone-angle difference over the periods both hold
at most ``same_bearing_deg``, at least ``min_overlap`` common periods) are one source (single-linkage groups).
Within a source, a pair of lines whose mean frequencies have a ratio within ``harmonic_tol`` (relative) of p/q,
p, q <= ``max_harmonic``, p / q != 1 (two tracks of one line), is noted as harmonics (the lower line q times
f_low / q); the family's fundamental is
the largest of those f_low / q of which every paired line is an integer multiple (200, 300, 400 Hz: 100 Hz).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sonartrack.core.errors import require
from sonartrack.core.settings import Settings, setting


class LineTrackerSettings(Settings):
    """Line tracking in frequency and bearing and the grouping into sources (module doc)."""

    sigma_freq_hz: float = setting(0.3, "frequency measurement noise sf (a line's bin is 1 / window wide)", unit="Hz",
                                   gt=0)
    sigma_bearing_deg: float = setting(2.0, "cone-angle measurement noise st of a narrowband beam's peak", unit="deg",
                                       gt=0)
    q_freq: float = setting(1e-6, "white-noise intensity of the frequency rate", unit="Hz^2/s^3", gt=0)
    q_bearing: float = setting(1e-5, "white-noise intensity of the cone-angle rate", unit="deg^2/s^3", gt=0)
    max_freq_rate_hz_s: float = setting(0.05, "largest frequency rate of a new track (its initial rate spread)",
                                        unit="Hz/s", gt=0)
    max_bearing_rate_deg_s: float = setting(0.2, "largest cone-angle rate of a new track (its initial rate "
                                                 "spread)", unit="deg/s", gt=0)
    gate: float = setting(13.8, "chi-square gate on d^2 (2 dof; 13.8 = 0.999)", unit="1", gt=0)
    confirm_m: int = setting(3, "confirmed with detections in M of the first N periods: M", unit="1", ge=1)
    confirm_n: int = setting(4, "... N", unit="1", ge=1)
    max_misses: int = setting(3, "a track ends after this many periods in a row without a detection", unit="1", ge=1)
    same_bearing_deg: float = setting(4.0, "two lines are one source when their cone angles differ by at most this "
                                           "(RMS over the common periods)", unit="deg", gt=0)
    min_overlap: int = setting(3, "common periods needed to compare two lines' bearings", unit="1", ge=1)
    harmonic_tol: float = setting(0.005, "relative tolerance of a frequency ratio p / q", unit="1", gt=0)
    max_harmonic: int = setting(6, "largest p, q of a harmonic ratio p / q", unit="1", ge=1)


@dataclass(frozen=True)
class LineTrack:
    """A tracked line: per period (n,) time (s), filtered frequency (Hz), cone angle (deg), their rates (Hz/s,
    deg/s) and the detection's SNR (dB; NaN where the period had none); ``confirmed``; the detection itself,
    ``measured_frequency_hz`` and ``measured_cone_deg`` (NaN where none: the filtered values are correlated from
    period to period, a TMA wants the measurements)."""

    track_id: int
    time_s: np.ndarray
    frequency_hz: np.ndarray
    cone_deg: np.ndarray
    frequency_rate_hz_s: np.ndarray
    cone_rate_deg_s: np.ndarray
    snr_db: np.ndarray
    confirmed: bool
    measured_frequency_hz: np.ndarray | None = None
    measured_cone_deg: np.ndarray | None = None

    @property
    def detected(self) -> np.ndarray:
        """(n,) bool: the periods with a detection."""
        return np.isfinite(self.snr_db)

    @property
    def mean_frequency_hz(self) -> float:
        """The line's mean frequency (Hz)."""
        return float(np.mean(self.frequency_hz))


@dataclass(frozen=True)
class LineSource:
    """Lines with one bearing history: ``track_ids``, and ``harmonics`` as (lower id, higher id, q, p) with
    f_higher / f_lower ~ p / q; ``fundamental_hz`` the largest f0 of which all those lines are integer multiples
    (NaN when none)."""

    source_id: int
    track_ids: tuple[int, ...]
    harmonics: tuple[tuple[int, int, int, int], ...]
    fundamental_hz: float


@dataclass
class _Track:
    track_id: int
    x: np.ndarray
    P: np.ndarray
    rows: list = field(default_factory=list)
    hits: int = 0
    periods: int = 0
    misses: int = 0
    confirmed: bool = False


def _cv(T: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    return np.array([[1.0, T], [0.0, 1.0]]), q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])


def _models(T: float, s: LineTrackerSettings):
    """Block-diagonal F and Q of [f, fdot, theta, thetadot], H and R."""
    F, Q = np.zeros((4, 4)), np.zeros((4, 4))
    for i, q in ((0, s.q_freq), (2, s.q_bearing)):
        F[i:i + 2, i:i + 2], Q[i:i + 2, i:i + 2] = _cv(T, q)
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    return F, Q, H, np.diag([s.sigma_freq_hz**2, s.sigma_bearing_deg**2])


def _assign(tracks: list[_Track], z: np.ndarray, H, R, gate: float) -> dict[int, int]:
    """Greedy global nearest neighbour: track index -> detection index, least d^2 first, inside the gate."""
    if not tracks or not len(z):
        return {}
    d2 = np.full((len(tracks), len(z)), np.inf)
    for i, t in enumerate(tracks):
        S = H @ t.P @ H.T + R
        nu = z - H @ t.x
        d2[i] = np.einsum("ki,ij,kj->k", nu, np.linalg.inv(S), nu)
    out: dict[int, int] = {}
    for flat in np.argsort(d2, axis=None):
        i, j = divmod(int(flat), len(z))
        if d2[i, j] > gate:
            break
        if i not in out and j not in out.values():
            out[i] = j
    return out


def _update(t: _Track, z: np.ndarray, H, R) -> None:
    S = H @ t.P @ H.T + R
    K = t.P @ H.T @ np.linalg.inv(S)
    t.x = t.x + K @ (z - H @ t.x)
    t.P = (np.eye(4) - K @ H) @ t.P


def _step(tracks, z, snr, time_s, s, H, R, next_id) -> tuple[list[_Track], int]:
    """One period: associate, update, start new tracks, confirm and drop (module doc)."""
    taken = _assign(tracks, z, H, R, s.gate)
    for i, t in enumerate(tracks):
        t.periods += 1
        if i in taken:
            j = taken[i]
            _update(t, z[j], H, R)
            t.hits, t.misses = t.hits + 1, 0
        else:
            t.misses += 1
        z_row = z[taken[i]] if i in taken else (np.nan, np.nan)
        t.rows.append((time_s, *t.x, snr[taken[i]] if i in taken else np.nan, *z_row))
        if not t.confirmed and t.hits >= s.confirm_m:
            t.confirmed = True
    alive = [t for t in tracks if t.misses < s.max_misses and (t.confirmed or t.periods - t.hits <= s.confirm_n -
                                                                s.confirm_m)]
    used = set(taken.values())
    p0 = np.diag([s.sigma_freq_hz**2, s.max_freq_rate_hz_s**2, s.sigma_bearing_deg**2, s.max_bearing_rate_deg_s**2])
    for j in range(len(z)):
        if j not in used:
            t = _Track(next_id, np.array([z[j, 0], 0.0, z[j, 1], 0.0]), p0.copy(), hits=1, periods=1)
            t.rows.append((time_s, *t.x, snr[j], *z[j]))
            t.confirmed = s.confirm_m <= 1
            alive.append(t)
            next_id += 1
    return alive, next_id


def track_lines(time_s, frequency_hz, cone_deg, snr_db, settings: LineTrackerSettings | None = None
                ) -> list[LineTrack]:
    """Track line detections through the periods (module doc).

    Parameters
    ----------
    time_s, frequency_hz, cone_deg, snr_db : array_like (n,)
        The detections: period centre (s), frequency (Hz), cone angle (deg), SNR (dB); periods equally spaced.
    settings : LineTrackerSettings, optional
        Noise, gates, confirmation.

    Returns
    -------
    list of LineTrack
        Every track that was confirmed, in order of its start (tentative tracks that failed are left out).
    """
    s = settings or LineTrackerSettings()
    t_all = np.asarray(time_s, float)
    z_all = np.column_stack([np.asarray(frequency_hz, float), np.asarray(cone_deg, float)])
    snr_all = np.asarray(snr_db, float)
    require(len(t_all) == len(z_all) == len(snr_all), "line detections: time, frequency, cone and SNR differ in length")
    periods = np.unique(t_all)
    if len(periods) == 0:
        return []
    T = float(np.median(np.diff(periods))) if len(periods) > 1 else 1.0
    F, Q, H, R = _models(T, s)
    tracks: list[_Track] = []
    finished: list[_Track] = []
    next_id = 1
    for tp in periods:
        for t in tracks:
            t.x, t.P = F @ t.x, F @ t.P @ F.T + Q
        sel = t_all == tp
        alive, next_id = _step(tracks, z_all[sel], snr_all[sel], float(tp), s, H, R, next_id)
        finished += [t for t in tracks if t not in alive]
        tracks = alive
    return [_as_line_track(t) for t in sorted(finished + tracks, key=lambda t: t.track_id) if t.confirmed]


def _as_line_track(t: _Track) -> LineTrack:
    rows = np.array(t.rows)
    last = len(rows)
    while last > 1 and np.isnan(rows[last - 1, 5]):  # the coasted periods after the last detection
        last -= 1
    r = rows[:last]
    return LineTrack(t.track_id, r[:, 0], r[:, 1], r[:, 3], r[:, 2], r[:, 4], r[:, 5], t.confirmed, r[:, 6], r[:, 7])


def _same_bearing(a: LineTrack, b: LineTrack, s: LineTrackerSettings) -> bool:
    common, ia, ib = np.intersect1d(a.time_s, b.time_s, return_indices=True)
    if len(common) < s.min_overlap:
        return False
    return float(np.sqrt(np.mean((a.cone_deg[ia] - b.cone_deg[ib]) ** 2))) <= s.same_bearing_deg


def harmonic_ratio(f_low: float, f_high: float, max_harmonic: int, tol: float) -> tuple[int, int] | None:
    """(q, p) with f_high / f_low within ``tol`` (relative) of p / q, p and q coprime and <= ``max_harmonic`` (the
    smallest p + q first), else None.

    Parameters
    ----------
    f_low, f_high : float
        Frequencies (Hz), f_low <= f_high.
    max_harmonic : int
        Largest p, q.
    tol : float
        Relative tolerance.

    Returns
    -------
    tuple of int or None
        (q, p).
    """
    r = f_high / f_low
    pairs = sorted(((q, p) for p in range(1, max_harmonic + 1) for q in range(1, p + 1) if np.gcd(p, q) == 1),
                   key=lambda qp: (qp[0] + qp[1], qp[1]))
    for q, p in pairs:
        if abs(r - p / q) <= tol * r:
            return q, p
    return None


def group_sources(tracks: list[LineTrack], settings: LineTrackerSettings | None = None) -> list[LineSource]:
    """Group line tracks with one bearing history into sources; note harmonic pairs (module doc).

    Parameters
    ----------
    tracks : list of LineTrack
        Line tracks (:func:`track_lines`).
    settings : LineTrackerSettings, optional
        ``same_bearing_deg``, ``min_overlap``, ``harmonic_tol``, ``max_harmonic``.

    Returns
    -------
    list of LineSource
        One per group, in order of the lowest track id.
    """
    s = settings or LineTrackerSettings()
    label = list(range(len(tracks)))

    def root(i):
        while label[i] != i:
            i = label[i]
        return i

    for i in range(len(tracks)):
        for j in range(i + 1, len(tracks)):
            if _same_bearing(tracks[i], tracks[j], s):
                label[root(j)] = root(i)
    groups: dict[int, list[LineTrack]] = {}
    for i, t in enumerate(tracks):
        groups.setdefault(root(i), []).append(t)
    return [_source(k + 1, members, s) for k, members in enumerate(groups.values())]


def _family_fundamental(freqs: list[float], candidates: list[float], s: LineTrackerSettings) -> float:
    """The largest candidate f0 of which every line is an integer multiple (within ``harmonic_tol``), else NaN."""
    for f0 in sorted(candidates, reverse=True):
        n = np.round(np.asarray(freqs) / f0)
        if np.all(n >= 1) and np.all(np.abs(np.asarray(freqs) - n * f0) <= s.harmonic_tol * np.asarray(freqs)):
            return float(np.mean(np.asarray(freqs) / n))
    return float("nan")


def _source(source_id: int, members: list[LineTrack], s: LineTrackerSettings) -> LineSource:
    lines = sorted(members, key=lambda t: t.mean_frequency_hz)
    pairs, candidates, in_pairs = [], [], set()
    for i, lo in enumerate(lines):
        for hi in lines[i + 1:]:
            qp = harmonic_ratio(lo.mean_frequency_hz, hi.mean_frequency_hz, s.max_harmonic, s.harmonic_tol)
            if qp is not None and qp != (1, 1):  # 1:1 is one line tracked twice (before and after a break)
                pairs.append((lo.track_id, hi.track_id, qp[0], qp[1]))
                candidates.append(lo.mean_frequency_hz / qp[0])
                in_pairs |= {lo.mean_frequency_hz, hi.mean_frequency_hz}
    f0 = _family_fundamental(sorted(in_pairs), candidates, s) if pairs else float("nan")
    return LineSource(source_id, tuple(sorted(t.track_id for t in members)), tuple(pairs), f0)
