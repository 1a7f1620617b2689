"""The tma system's run function: a bearings record and the ownship track in, a solved record out.

:func:`run_tma` is :func:`sonartrack.tma.solve.solve_tma` (every method: sequential ``ekf``, ``mgekf``,
``imm-ekf``, ``imm-mgekf`` on bearings or bearings + frequency, paper P2; batch ``ml`` and ``em-map``, paper P3)
with what the system adds: em-map's environment looked up from ``settings.batch.env``, a shipped
environment's name or a profile file (:func:`tma_environment`), and with ``legs`` the record's zigs and legs
(tma/leg_solution.py: the zig detector and the leg-wise ML with its own verdict, the bearing sd the one given or
estimated from the legs' residuals) and the observer advice from the current leg when it is determined
(:func:`with_legs`).
"""

from __future__ import annotations

from dataclasses import replace

from sonartrack.tma.records import BearingRecord, OwnshipTrack
from sonartrack.tma.settings import TmaSettings
from sonartrack.tma.solve import TmaResult, solve_tma


def tma_environment(settings: TmaSettings):
    """em-map's environment: a shipped one by name or a profile file (io/environment.py), else None.

    Parameters
    ----------
    settings : TmaSettings
        The method (sequential methods need no environment) and ``batch.env``.

    Returns
    -------
    Environment or None
        The sound-speed profile and bottom of the propagation model, or None when none is needed or given.
    """
    if settings.is_sequential or settings.batch.env is None:
        return None
    from sonartrack.io.environment import environment_from_name_or_file

    return environment_from_name_or_file(settings.batch.env)


def run_tma(record: BearingRecord, ownship: OwnshipTrack, settings: TmaSettings | None = None, *,
            environment=None, tl_store=None, legs: bool = False) -> TmaResult:
    """Solve a bearings (+ frequency, SNR) record for the target's track.

    Parameters
    ----------
    record : BearingRecord
        Measurement times (s), bearings (rad, true, from the ownship), optional frequencies (Hz) and SNRs (dB).
    ownship : OwnshipTrack
        Ownship times (s) and positions x east, y north (m) covering the record.
    settings : TmaSettings, optional
        The system's settings (default: imm-mgekf on bearings).
    environment : Environment, optional
        em-map's propagation environment; by default :func:`tma_environment` of the settings.
    tl_store : FieldStore, optional
        Cache of TL fields for em-map (e.g. io/environment.py's ``TLDiskCache``); none by default.
    legs : bool
        Find the record's zigs and legs and advise from the current one (:func:`with_legs`).

    Returns
    -------
    TmaResult
        The target solution over time (state in m and m/s, covariances), the solver's warnings and, per method,
        the emitted frequency (Hz) or the IMM mode probabilities.
    """
    settings = TmaSettings() if settings is None else settings
    if environment is None:
        environment = tma_environment(settings)
    result = solve_tma(record, ownship, settings, environment=environment, tl_store=tl_store)
    return with_legs(result, sigma_given=settings.sigma_bearing_deg is not None) if legs else result


def with_legs(result: TmaResult, *, sigma_given: bool) -> TmaResult:
    """``result`` with its record's zigs and legs and the advice from the current leg (module doc).

    Parameters
    ----------
    result : TmaResult
        A solved record; its settings' ``sigma_bearing_deg`` is the sd it used.
    sigma_given : bool
        That sd was given; else it was estimated from the record's constant-velocity residuals, and the legs'
        residuals estimate it again (tma/leg_solution.py).

    Returns
    -------
    TmaResult
        With ``legs`` and ``advice`` (None when the current leg is not determined).
    """
    from sonartrack.tma.leg_solution import current_advice, solve_legs

    legs = solve_legs(result.record, result.ownship, result.settings.sigma_bearing_deg, given=sigma_given)
    return replace(result, legs=legs, advice=current_advice(legs, result.record, result.ownship))
