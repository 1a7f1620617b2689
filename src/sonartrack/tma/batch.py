"""Batch TMA on a user's record: bearings-only ML, or EM/MAP with SNR and a propagation model (paper P3).

:func:`solve_batch` is what ``sonartrack tma --method ml|em-map`` calls. For ``em-map`` the mean SNR
against range is xi_bar(r) = SL - TL(r) + DI - NL with TL from RAM (``acoustics/``) for the named
environment (or a profile file), source and receiver at ``depth_m``, averaged over 1 km.
"""

from __future__ import annotations

import warnings

import numpy as np

from sonartrack.core.errors import InputError, require
from sonartrack.tma.batch_ml import BatchEstimate, check_observability, ml_bearings_only
from sonartrack.tma.records import BearingRecord, OwnshipTrack, TmaSolution

#: TL range average (m): a passive sonar integrates over the interference pattern
TL_AVERAGE_M = 1_000.0


class UnobservableWarning(UserWarning):
    """Range is not observable from bearings alone (the ownship has not maneuvered)."""


def snr_model(env_name: str, sl_db: float, freq_hz: float, depth_m: float | None, r_max_m: float,
              nl_db: float | None = None, di_db: float | None = None):
    """xi_bar(r) for an environment name or profile path: (callable, environment, depth used)."""
    from pathlib import Path

    from sonartrack.acoustics.environment import load_environment, read_profile
    from sonartrack.acoustics.sonar_equation import DI_DB, NL_DB, passive_snr_db
    from sonartrack.acoustics.transmission_loss import smooth_tl, tl_field

    env = read_profile(env_name) if Path(env_name).suffix.lower() in (".toml", ".csv") else load_environment(env_name)
    z = float(depth_m) if depth_m is not None else min(50.0, env.water_depth_m / 2.0)
    require(0 < z < env.water_depth_m, f"depth {z:g} m is outside the water column of {env.name} (0..{env.water_depth_m:g} m)")
    f = tl_field(env, freq_hz, z, rmax_m=r_max_m)
    line = smooth_tl(f.ranges_m, f.at_depth(z), TL_AVERAGE_M)
    nl = NL_DB if nl_db is None else nl_db
    di = DI_DB if di_db is None else di_db

    def xi_bar(r):
        return passive_snr_db(sl_db, np.interp(r, f.ranges_m, line), di, nl)

    return xi_bar, env, z


def estimate_to_solution(est: BatchEstimate, time_s) -> TmaSolution:
    x, P = est.state_at(time_s)
    return TmaSolution(np.asarray(time_s, dtype=float), x, P, est.method)


def solve_batch(record: BearingRecord, ownship: OwnshipTrack, method: str, *, sigma_bearing_rad: float,
                sigma_snr_db: float = 1.0, env: str | None = None, sl_db: float | None = None, freq_hz: float = 200.0,
                depth_m: float | None = None, r_min_m: float = 500.0, r_max_m: float = 60_000.0,
                nl_db: float | None = None, di_db: float | None = None) -> TmaSolution:
    """Batch TMA of a whole record: ``method`` 'ml' (bearings only) or 'em-map' (bearings + SNR + TL)."""
    require(method in ("ml", "em-map"), f"unknown batch method '{method}': choose ml or em-map")
    t = np.asarray(record.time_s, dtype=float)
    own = ownship.position_at(t)
    if method == "ml":
        est = ml_bearings_only(record.bearing_rad, t, own, sigma_bearing_rad)
        return estimate_to_solution(est, t)
    from sonartrack.tma.em_map import make_problem, solve_em_map

    if record.snr_db is None:
        raise InputError("em-map needs measured SNR: add an snr_db column to the bearings file")
    if env is None or sl_db is None:
        raise InputError("em-map needs a propagation model: give --env NAME (or a profile file) and --sl DB")
    msg = check_observability(t - t[0], own)
    ml_start = None
    if msg:
        warnings.warn(msg.replace("use a record with a course or speed change, or em-map with SNR",
                                  "em-map relies on the SNR for range"), UnobservableWarning, stacklevel=2)
    else:
        try:
            ml_start = ml_bearings_only(record.bearing_rad, t, own, sigma_bearing_rad).x0
        except (InputError, np.linalg.LinAlgError):
            ml_start = None
    xi_bar, _, _ = snr_model(env, sl_db, freq_hz, depth_m, r_max_m * 1.05, nl_db, di_db)
    prob = make_problem(record.bearing_rad, record.snr_db, t, own, sigma_bearing_rad, sigma_snr_db, xi_bar, r_min_m, r_max_m)
    est = solve_em_map(prob, t0_s=float(t[0]), extra_starts=[ml_start])
    if not np.all(np.isfinite(est.covariance)):
        raise InputError("em-map found no well-defined solution (flat likelihood): check the SL, environment and depth")
    return estimate_to_solution(est, t)
