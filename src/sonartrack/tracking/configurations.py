"""The paper trackers as configurations of the same parts (tracking/multi_target.py).

============  ===============================================  =============================================
part          position tracker (P4, :func:`position_tracker`)  bearing tracker (P0, :func:`bearing_tracker`)
============  ===============================================  =============================================
motion        CV in x, y; one mode per q (and optional          CV in bearing (deg); one mode
              coordinated turns at known rates), IMM chain
measurements  points with R_m, chi-square gate                 peaks, window gate V, sigma_p per track
associator    PDA (IPDA / IMM-IPDA with existence)             exact JPDA (JPDA_A: amplitude ratio)
existence     IPDA Markov chain                                none
initiator     one-point, velocity prior                        strongest peak per cluster (or given tracks)
deleter       existence thresholds                             M-of-N, consecutive misses
============  ===============================================  =============================================
"""

from __future__ import annotations

import numpy as np

from sonartrack.association.amplitude import STRENGTH_INITIAL
from sonartrack.tracking.associators import JPDA, PDA
from sonartrack.tracking.deleters import ExistenceDeleter, MinHits, MOfNDeleter
from sonartrack.tracking.existence import IpdaExistence
from sonartrack.tracking.initiators import OnePointInitiator, PeakInitiator, bearing_covariance
from sonartrack.tracking.measurements import BearingMeasurements, PositionMeasurements
from sonartrack.tracking.motion import ImmConstantVelocity, TurnModes
from sonartrack.tracking.multi_target import MultiTargetTracker
from sonartrack.tracking.own_motion import ArrayTurnPrediction
from sonartrack.tracking.resolution import UnresolvedPairs
from sonartrack.tracking.settings import BearingTrackerSettings, PositionTrackerSettings
from sonartrack.tracking.tracks import TrackArrays

#: with the resolution model, a track's half-window is at least this many sds of its prediction
#: (tracking/measurements.py ``widened_gates``): 3 sds hold its peak with probability 0.997
GATE_SDS = 3.0


def position_motion(settings: PositionTrackerSettings, turns: TurnModes | None = None) -> ImmConstantVelocity:
    """The IMM modes of a position tracker: P4's constant-velocity modes (one per q), then a clockwise and a
    counter-clockwise coordinated turn at each rate of ``turns`` (filters/coordinated_turn.py).

    The mode chain keeps each mode with probability ``transition_diagonal`` and spreads the rest evenly over the
    other modes (P4's rule, applied to all r modes). With the turns' mean course change set (``turns.turn_deg``), a
    turn mode at rate w is kept over a scan interval T with probability exp(-T w / turn_deg) (its mean sojourn
    turn_deg / w, tracking/motion.py ``sojourn_transition``) and left for the constant-velocity modes and the turn
    modes of its own sense, evenly: a turn ends on a straight leg or tightens/eases, it does not reverse.

    Parameters
    ----------
    settings : PositionTrackerSettings
        The constant-velocity intensities ``q`` (m^2/s^3) and ``transition_diagonal``.
    turns : TurnModes, optional
        Turn modes to add; None or no rates: P4's modes alone.

    Returns
    -------
    ImmConstantVelocity
        The modes and their Markov chain.
    """
    if turns is None or not turns.rates_deg_s:
        return ImmConstantVelocity(tuple(settings.q), dims=2, transition=settings.transition_matrix())
    w = (0.0,) * len(settings.q) + turns.signed_rates_rad_s()
    q = tuple(settings.q) + (turns.q,) * (len(w) - len(settings.q))
    r, n_cv = len(w), len(settings.q)
    Pi = np.full((r, r), (1.0 - settings.transition_diagonal) / (r - 1))
    np.fill_diagonal(Pi, settings.transition_diagonal)
    sojourn = turns.sojourn_s()
    if sojourn is not None:  # a turn's row: its sojourn (motion.py) decides the diagonal, the rest goes as above
        for i in range(n_cv, r):
            to = np.array([j != i and (j < n_cv or np.sign(w[j]) == np.sign(w[i])) for j in range(r)], float)
            Pi[i] = (1.0 - settings.transition_diagonal) * to / to.sum()
            Pi[i, i] = settings.transition_diagonal
        sojourn = (None,) * n_cv + sojourn
    return ImmConstantVelocity(q, dims=2, transition=Pi, turn_rate_rad_s=w, sojourn_s=sojourn)


def position_tracker(settings: PositionTrackerSettings | None = None, *, associator=None,
                     turns: TurnModes | None = None) -> MultiTargetTracker:
    """IPDA (one q) / IMM-IPDA (several q) position tracker of paper P4 (Park, Song, Lee 2017).

    One-point initiation and existence-based confirmation and deletion (module table).

    Parameters
    ----------
    settings : PositionTrackerSettings, optional
        Tracker settings; None for the defaults (P4's tracker).
    associator : optional
        Replaces PDA (``JPDA()`` needs one mode and no existence, so it is refused here).
    turns : TurnModes, optional
        Coordinated-turn modes added to P4's (:func:`position_motion`); None: P4's modes alone.

    Returns
    -------
    MultiTargetTracker
        The tracker; its state is [x, y, vx, vy] (m, m/s; x east, y north).

    Raises
    ------
    InputError
        If the associator cannot drive these parts.
    """
    s = settings or PositionTrackerSettings()
    deleter = ExistenceDeleter(s.confirm_threshold, s.terminate_threshold)
    return MultiTargetTracker(
        position_motion(s, turns),
        PositionMeasurements(s.pd, s.gate_probability, s.clutter_density_per_m2),
        associator or PDA(),
        existence=IpdaExistence(s.p_survive, s.p_birth),
        initiator=OnePointInitiator(s.init_velocity_std_mps, s.initial_existence, s.max_tracks),
        deleter=MinHits(deleter, s.confirm_min_hits) if s.confirm_min_hits > 1 else deleter)


def bearing_tracker(settings: BearingTrackerSettings | None = None, *, amplitude_aided: bool = True,
                    adaptive_strength: bool = True, initial: TrackArrays | None = None,
                    time_s: float | None = None, associator=None, array_turn: bool = False,
                    resolution_deg: float | None = None) -> MultiTargetTracker:
    """JPDA (``amplitude_aided=False``) / JPDA_A bearing tracker of paper P0 (Park, Ryu, Lee 1994).

    With ``initial`` tracks (:func:`bearing_tracks`, starting at ``time_s``) it follows exactly those, as the
    paper's runs do; without, it starts tracks on strong peaks and confirms them M-of-N (user data).

    Parameters
    ----------
    settings : BearingTrackerSettings, optional
        Tracker settings; None for the defaults (P0's tracker).
    amplitude_aided : bool, default True
        JPDA_A: weigh the peak amplitudes.
    adaptive_strength : bool, default True
        Track strengths by eq. 9 (real data) instead of known ones (the paper's synthetic runs).
    initial : TrackArrays, optional
        Known tracks to follow (no initiation or deletion then).
    time_s : float, optional
        Time of ``initial`` (s).
    associator : optional
        Replaces JPDA (e.g. ``PDA()``, each track on its own).
    array_turn : bool, default False
        Predict the array's heading change (given to each ``step`` as ``array_turn_deg``) with each track's side
        as a hypothesis (tracking/own_motion.py); off: the turn is left to the process noise (paper P0).
    resolution_deg : float, optional
        Two confirmed tracks closer than this (deg) share one peak and are updated as a group
        (tracking/resolution.py); None: the settings' ``resolution_deg`` (0: off, paper P0). With it, two ships'
        peaks may share a gate, and each track's strength follows its own peak and its window widens to
        ``GATE_SDS`` sds of its prediction (tracking/measurements.py module docstring; DEVIATIONS from P0).

    Returns
    -------
    MultiTargetTracker
        The tracker; its state is [bearing (deg), bearing rate (deg/s)], the bearing being the 1-D angle
        the peaks measure (a cone angle from the array axis for a line array).
    """
    s = settings or BearingTrackerSettings()
    auto = initial is None
    res = s.resolution_deg if resolution_deg is None else resolution_deg
    return MultiTargetTracker(
        ImmConstantVelocity((s.q,), dims=1),
        BearingMeasurements(s.p_detect, s.gate_deg, s.clutter_density_per_deg, s.amplitude_threshold,
                            s.false_amplitude_rate, amplitude_aided, adaptive_strength, s.endfire_fold,
                            own_peak_strength=bool(res), gate_sds=GATE_SDS if res else 0.0),
        associator or JPDA(),
        initiator=(PeakInitiator(s.init_amplitude, s.init_sigma_p_deg, s.init_amplitude_sd, s.gate_deg)
                   if auto else None),
        deleter=MOfNDeleter(s.confirm_m, s.confirm_n, s.delete_after) if auto else None,
        tracks=initial, time_s=time_s,
        own_motion=ArrayTurnPrediction(s.p_detect, s.clutter_density_per_deg, s.gate_deg) if array_turn else None,
        resolution=UnresolvedPairs(res, s.gate_deg) if res else None)


def bearing_tracks(bearing_deg, rate_deg_s, sigma_p_deg, strength, sigma_a, *, adaptive_strength: bool = False,
                   time_s: float = 0.0) -> TrackArrays:
    """Known (confirmed) bearing tracks to start :func:`bearing_tracker` with (paper P0's runs).

    ``P(0) = [[s^2, s^2], [s^2, 2 s^2]]`` with s = sigma_p (P0).

    Parameters
    ----------
    bearing_deg : float or array_like, shape (n,)
        Initial bearings (deg).
    rate_deg_s : float or array_like
        Initial bearing rates (deg/s), broadcast to (n,).
    sigma_p_deg : float or array_like
        Peak spread sigma_p of each track (deg).
    strength : float or array_like
        Amplitude strength z_hat of each track (correlator output unit).
    sigma_a : float or array_like
        Amplitude spread of each track (same unit).
    adaptive_strength : bool, default False
        Start the strengths at eq. 9's 15000 instead of ``strength``.
    time_s : float, default 0.0
        Time of initiation (s).

    Returns
    -------
    TrackArrays
        n confirmed single-mode tracks, identifiers 1..n.
    """
    b = np.atleast_1d(np.asarray(bearing_deg, float))
    n = len(b)
    col = lambda v: np.broadcast_to(np.asarray(v, float), (n,)).copy()  # noqa: E731
    x = np.stack([b, col(rate_deg_s)], -1)
    sp = col(sigma_p_deg)
    st = np.full(n, STRENGTH_INITIAL) if adaptive_strength else col(strength)
    P = bearing_covariance(sp)
    return TrackArrays(x[:, None].copy(), P[:, None].copy(), np.ones((n, 1)), np.full(n, np.nan), np.ones(n, bool),
                       np.arange(1, n + 1, dtype=np.int64), np.full(n, float(time_s)), P,
                       {"sigma_p": sp, "strength": st, "sigma_a": col(sigma_a)})
