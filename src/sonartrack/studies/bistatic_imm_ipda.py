"""Study P4: IMM-IPDA tracking for a bistatic low-frequency active towed-array sonar.

Park, Song, Lee, "IMM-IPDA target tracking for a bistatic low-frequency active towed array sonar"
(in Korean), J. Acoust. Soc. Korea 36(3), 2017 (paper 004). One trial simulates the paper's
scenario once (100 scans of bistatic points in Poisson clutter) and runs every tracker of both
experiments on the *same* measurements (common random numbers sharpen the comparisons):

* experiment 1: IPDA small q, IPDA large q, IMM-IPDA with both;
* experiment 2: IPDA with each of three q values, IMM-IPDA with all three.

Per scan and tracker it records the CTT indicator (eq. 23), the number of confirmed false tracks,
the position error of the CTT, and the CTT's mode probabilities; per scan, the target measurement's
error in metres; per run and tracker, reported beside the paper's measures (not claimed): GOSPA and OSPA of
the confirmed tracks (metrics/ospa.py), the target's track segments, identity switches and time to confirm
(metrics/track_quality.py). config -> run_trial (simulate -> estimate) -> summarize -> claims; the figures are
report/figures/bistatic_imm_ipda.py.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numpy as np
from pydantic import model_validator

from sonartrack.core.settings import Settings, setting
from sonartrack.experiment.claims import Claim
from sonartrack.metrics.tracking import CTT_CHI2_4DOF_99, scan_ctt_measures
from sonartrack.tracking.settings import PositionTrackerSettings

if TYPE_CHECKING:
    from sonartrack.sim.bistatic_sonar import BistaticSonar
    from sonartrack.sim.platforms import ManeuveringTrack

STUDY_ID = "bistatic-imm-ipda"
TITLE = "IMM-IPDA for a bistatic active towed-array sonar"
PAPER = "Park, Song, Lee 2017, J. Acoust. Soc. Korea 36(3) (P4)"
TRIAL_VERSION = 2
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 500
QUICK_RUNS = 20
CHUNK_SIZE = 10


def _paper_tracker() -> PositionTrackerSettings:
    # the three modes of experiment 2 (small, middle, large q); the other settings are the library's,
    # which are P4's tracker (tracking/settings.py)
    return PositionTrackerSettings(q=[1e-4, 3e-3, 0.05])


class Config(Settings):
    """Scenario and tracker parameters. Paper values unless marked *choice*.

    Paper (sec. IV): 500 runs, 3000 s, T = 30 s (100 scans); ownship from the origin at 2.5 m/s,
    turning at 0.08 deg/s from 1500 s; Tx 300 m and Rx 450 m behind on the ship's track; Pd = 0.8;
    clutter 1e-6 /m^2, 40 points a scan; sigma_t = 0.01 s, sigma_c = 7.5 m/s, Tx/Rx 30 m per axis,
    bearing 0.5 deg straight and 1.5 deg turning; target 3 m/s constant velocity, approaching;
    initial mode probabilities 0.5.

    Choices (the paper's numbers for these were lost or never given):

    * geometry: ownship heading north (0 deg), turning to starboard; target from (-8500, 19500) m
      (21.3 km) at 3.0 m/s on course 160.5 deg. This puts the measurement error at ~200 m RMS at the
      start and ~330 m RMS just after the turn, closing to ~230 m at the end, matching the paper's
      Fig. 5 (220 m at the start, about 380 m after scan 50, decreasing as the target closes).
    * surveillance region: 4 km x 10 km around the target's path (x -9000..-5000, y 10000..20000),
      area 4e7 m^2, so 1e-6 /m^2 gives the paper's 40 clutter points a scan.
    * the sonar reports J Sigma J^T with the straight-running bearing error (0.5 deg) even while the
      array shakes in the turn (it does not know the shaking); the larger process noise of the IMM
      absorbs the mismatch, which is the paper's argument for IMM-IPDA.
    * q values (``tracker.q``, m^2/s^3): small 1e-4, middle 3e-3, large 0.05; they span the range where
      a single IPDA goes from tracking well before the turn to tracking poorly before it (q >= 0.2
      hardly confirms at all in this clutter). Each single IPDA uses one of them, experiment 1's
      IMM-IPDA the small and the large, experiment 2's all three.
    * the tracker's other settings (mode chain 0.99, one-point initiation with a 5 m/s velocity prior,
      existence 0.05 / confirm 0.9 / terminate 0.01, survival 0.98, gate 0.99) are the defaults of
      tracking/settings.py, where each is explained; the tracker assumes the simulated Pd and clutter.
    * CTT test threshold 13.28 (chi-square(4), 0.99) on the initiation covariance (eq. 23).
    """

    runs: int = setting(RUNS, "Monte Carlo runs", unit="1", ge=1)
    n_scans: int = setting(100, "scans per run", unit="1", ge=2)
    scan_period_s: float = setting(30.0, "scan period T", unit="s", gt=0)
    ownship_speed_mps: float = setting(2.5, "ownship speed", unit="m/s")
    ownship_heading_deg: float = setting(0.0, "ownship initial heading, clockwise from north", unit="deg")
    turn_start_s: float = setting(1500.0, "time the ownship starts turning", unit="s")
    turn_rate_deg_s: float = setting(0.08, "ownship turn rate (starboard)", unit="deg/s")
    target_x0_m: float = setting(-8500.0, "target initial x (east)", unit="m")
    target_y0_m: float = setting(19500.0, "target initial y (north)", unit="m")
    target_vx_mps: float = setting(1.0, "target velocity east", unit="m/s")
    target_vy_mps: float = setting(-2.83, "target velocity north", unit="m/s")
    tx_cable_m: float = setting(300.0, "transmitter towed this far behind the ship", unit="m")
    rx_cable_m: float = setting(450.0, "receiving array towed this far behind the ship", unit="m")
    pd: float = setting(0.8, "probability that the simulated sonar detects the target (truth)", unit="1", gt=0, le=1)
    clutter_density_per_m2: float = setting(1e-6, "density of the simulated clutter (truth)", unit="1/m^2", gt=0)
    region_m: tuple[float, float, float, float] = setting((-9000.0, -5000.0, 10000.0, 20000.0),
                                                          "clutter region x_min, x_max, y_min, y_max", unit="m")
    sound_speed_mps: float = setting(1500.0, "true mean sound speed", unit="m/s")
    sigma_time_s: float = setting(0.01, "travel-time error", unit="s")
    sigma_sound_speed_mps: float = setting(7.5, "error of the assumed sound speed", unit="m/s")
    sigma_position_m: float = setting(30.0, "Tx and Rx position error per axis", unit="m")
    sigma_bearing_deg: float = setting(0.5, "bearing error while running straight", unit="deg")
    sigma_bearing_turn_deg: float = setting(1.5, "bearing error while turning (the array shakes)", unit="deg")
    tracker: PositionTrackerSettings = setting(default_factory=_paper_tracker,
                                               doc="the trackers; q: the small, middle and large mode (three values)")
    ctt_threshold: float = setting(CTT_CHI2_4DOF_99, "CTT test threshold on eq. 23 (chi-square(4), 0.99)", unit="1")
    metric_cutoff_m: float = setting(1000.0, "cut-off c of the reported GOSPA/OSPA (p = 1, switching penalty c / 2) "
                                             "and association gate of the track segments and switches; our choice: "
                                             "about three times the measurement error after the turn", unit="m",
                                     gt=0)

    @classmethod
    def quick(cls) -> Config:
        """CI preset: the full scenario and every tracker, 20 runs."""
        return cls(runs=QUICK_RUNS)

    # ---- derived objects -------------------------------------------------------------------
    def ownship(self) -> ManeuveringTrack:
        from sonartrack.sim.platforms import ManeuveringTrack
        turn = (self.turn_start_s, self.turn_start_s + self.n_scans * self.scan_period_s,
                np.deg2rad(self.turn_rate_deg_s))
        return ManeuveringTrack(0.0, 0.0, self.ownship_speed_mps, np.deg2rad(self.ownship_heading_deg), (turn,))

    def sonar(self) -> BistaticSonar:
        from sonartrack.models.bistatic import BistaticErrors
        from sonartrack.models.clutter import Region
        from sonartrack.sim.bistatic_sonar import BistaticSonar
        errors = BistaticErrors(self.sigma_time_s, np.deg2rad(self.sigma_bearing_deg), 0.0,
                                self.sigma_sound_speed_mps, self.sigma_position_m)
        return BistaticSonar(Region(*self.region_m), self.tx_cable_m, self.rx_cable_m, self.pd,
                             self.clutter_density_per_m2, self.sound_speed_mps, errors,
                             float(np.deg2rad(self.sigma_bearing_turn_deg)))

    def times_s(self) -> np.ndarray:
        return np.arange(self.n_scans) * self.scan_period_s

    def target_states(self) -> np.ndarray:
        from sonartrack.sim.platforms import constant_velocity_track
        return constant_velocity_track(self.times_s(), self.target_x0_m, self.target_y0_m,
                                       self.target_vx_mps, self.target_vy_mps)

    def cases(self) -> dict[str, tuple[float, ...]]:
        """Tracker id -> q per mode. Experiment 1: ipda_small, ipda_large, imm2; experiment 2:
        ipda_small, ipda_mid, ipda_large, imm3."""
        small, mid, large = self.tracker.q
        return {"ipda_small": (small,), "ipda_mid": (mid,), "ipda_large": (large,), "imm2": (small, large),
                "imm3": (small, mid, large)}

    def tracker_settings(self, q: tuple[float, ...]) -> PositionTrackerSettings:
        """The study's tracker with the modes ``q``."""
        return self.tracker.with_modes(q)

    @property
    def turn_scan(self) -> int:
        return int(np.ceil(self.turn_start_s / self.scan_period_s))

    @model_validator(mode="after")
    def _three_modes(self):
        if len(self.tracker.q) != 3:
            raise ValueError("tracker.q must hold the three modes small, middle, large (m^2/s^3)")
        return self


EXPERIMENTS = {"exp1": ("ipda_small", "ipda_large", "imm2"), "exp2": ("ipda_small", "ipda_mid", "ipda_large", "imm3")}
LABELS = {"ipda_small": "IPDA small q", "ipda_mid": "IPDA middle q", "ipda_large": "IPDA large q",
          "imm2": "IMM-IPDA (2 q)", "imm3": "IMM-IPDA (3 q)"}


# ---- simulate -> estimate ----------------------------------------------------------------------
class _TowingShip:
    """The ownship with its towed bodies' true positions kept per (time, cable): every run of a study tows
    along the same track, so they are computed once per process instead of once per run (same numbers)."""

    def __init__(self, ship: ManeuveringTrack):
        self.ship, self.turns, self._towed = ship, ship.turns, {}

    def towed(self, t_s: float, cable_m: float):
        key = (float(t_s), float(cable_m))
        if key not in self._towed:
            self._towed[key] = self.ship.towed(t_s, cable_m)
        return self._towed[key]


@functools.lru_cache(maxsize=4)
def _towing(ship: ManeuveringTrack) -> _TowingShip:
    return _TowingShip(ship)


def simulate(config: Config, rng: np.random.Generator):
    """The scans of one run (sim/bistatic_sonar.py) and the target's true states (n_scans, 4)."""
    from sonartrack.sim.bistatic_sonar import simulate_scan

    ship, sonar = _towing(config.ownship()), config.sonar()
    truth = config.target_states()
    return [simulate_scan(rng, sonar, ship, float(t), truth[k, :2]) for k, t in enumerate(config.times_s())], truth


def track_case(config: Config, q: tuple[float, ...], scans, truth) -> dict[str, np.ndarray]:
    """One tracker over the scans; per scan: CTT indicator, confirmed false tracks, CTT error, mode probabilities."""
    from sonartrack.tracking.configurations import position_tracker

    n = len(scans)
    tracker = position_tracker(config.tracker_settings(q))
    out = {"ctt": np.zeros(n, bool), "cft": np.zeros(n, np.int64), "err": np.full(n, np.nan),
           "mu": np.full((n, 3), np.nan)}
    confirmed = []  # (time, track id, x, y) of the confirmed tracks, for the set metrics
    for k, s in enumerate(scans):
        snap = tracker.step(s.time_s, s.z, s.R)
        has, n_false, e, i = scan_ctt_measures(truth[k], snap.x, snap.P_init, snap.confirmed, snap.existence,
                                               config.ctt_threshold)
        out["ctt"][k], out["cft"][k], out["err"][k] = has, n_false, e
        if i >= 0:
            out["mu"][k, : len(q)] = snap.mu[i]
        c = snap.confirmed
        confirmed.append(np.column_stack([np.full(int(c.sum()), s.time_s), snap.track_id[c], snap.x[c, :2]]))
    return out | set_metrics(config, truth, np.concatenate(confirmed) if confirmed else np.zeros((0, 4)))


def set_metrics(config: Config, truth, confirmed) -> dict[str, np.ndarray]:
    """GOSPA (mean over the scans, m) and OSPA of the confirmed tracks against the target, and the target's track
    segments, identity switches and time to confirm (module doc of metrics/track_quality.py).

    Parameters
    ----------
    config : Config
        The study (``metric_cutoff_m``).
    truth : ndarray, shape (n_scans, 4)
        The target's true states.
    confirmed : ndarray, shape (N, 4)
        Rows (time s, track id, x m, y m) of the confirmed tracks at every scan.

    Returns
    -------
    dict of str to ndarray
        ``gospa_m``, ``ospa_m``, ``segments``, ``switches``, ``confirm_s``: one value each (arrays of shape (1,)).
    """
    from sonartrack.metrics.ospa import gospa_over_time, ospa_over_time
    from sonartrack.metrics.track_quality import associate_tracks, identity_switches, time_to_confirm, track_segments

    t, c = config.times_s(), config.metric_cutoff_m
    ids = np.zeros(len(t), np.int64)
    est_t, est_id, est_xy = confirmed[:, 0], confirmed[:, 1].astype(np.int64), confirmed[:, 2:4]
    g = gospa_over_time(t, ids, truth[:, :2], est_t, est_id, est_xy, c, 1.0, 0.5 * c)
    o = ospa_over_time(t, truth[:, :2], est_t, est_xy, c, 1.0)[1]
    a = associate_tracks(t, ids, truth[:, :2], est_t, est_id, est_xy, c, p=1.0)
    return {"gospa_m": np.array([np.mean(g.distance)]), "ospa_m": np.array([np.mean(o)]),
            "segments": track_segments(a).astype(float), "switches": identity_switches(a).astype(float),
            "confirm_s": time_to_confirm(a)}


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One Monte Carlo run: simulate the scans once, run every tracker on them."""
    scans, truth = simulate(config, rng)
    meas_err = np.full((config.n_scans, 2), np.nan)
    for k, s in enumerate(scans):
        if s.is_target.any():
            meas_err[k] = s.z[s.is_target][0] - truth[k, :2]
    out = {"meas_error_xy": meas_err, "n_measurements": np.array([len(s.z) for s in scans])}
    for case, q in config.cases().items():
        out.update({f"{case}_{key}": v for key, v in track_case(config, q, scans, truth).items()})
    return out


# ---- summarize -----------------------------------------------------------------------------------
#: the reported (not claimed) per-run measures of :func:`set_metrics`
SET_METRICS = ("gospa_m", "ospa_m", "segments", "switches", "confirm_s")


def _nanmean_quiet(a, axis=0):
    """Mean over runs ignoring NaN; all-NaN columns give NaN without a warning."""
    a = np.asarray(a, float)
    n = np.sum(np.isfinite(a), axis=axis)
    return np.where(n > 0, np.nansum(a, axis=axis) / np.maximum(n, 1), np.nan)


def _window_mean(a, lo, hi):
    return float(_nanmean_quiet(np.asarray(a, float)[lo:hi]))


def _case_summary(trials, case: str, q, k0: int) -> dict:
    from sonartrack.metrics.statistics import rmse_over_runs
    ctt = trials[f"{case}_ctt"].astype(float)
    per_run_before, per_run_after, per_run_all = ctt[:, :k0].mean(axis=1), ctt[:, k0:].mean(axis=1), ctt.mean(axis=1)
    rmse = rmse_over_runs(trials[f"{case}_err"])
    return {
        "label": LABELS[case], "q": list(q),
        "ctt_rate": ctt.mean(axis=0).tolist(),
        "cft_per_scan": trials[f"{case}_cft"].mean(axis=0).tolist(),
        "range_rmse_m": rmse.tolist(),
        "mode_prob": np.asarray(_nanmean_quiet(trials[f"{case}_mu"][..., : len(q)])).tolist(),
        "ctt_before": float(per_run_before.mean()), "ctt_after": float(per_run_after.mean()),
        "ctt_all": float(per_run_all.mean()),
        "per_run_before": per_run_before.tolist(), "per_run_after": per_run_after.tolist(),
        "per_run_all": per_run_all.tolist(),
        "cft_mean": float(trials[f"{case}_cft"].mean()),
        "rmse_before_m": float(_nanmean_quiet(rmse[:k0])), "rmse_after_m": float(_nanmean_quiet(rmse[k0:])),
        # reported, not claimed: set metrics and track-level measures (set_metrics), means over the runs
        **{key: float(_nanmean_quiet(np.ravel(trials[f"{case}_{key}"]))) for key in SET_METRICS},
        "never_confirmed": float(np.mean(np.isnan(np.ravel(trials[f"{case}_confirm_s"])))),
    }


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    """Per-scan curves (over runs) and before/after-turn averages with their standard errors."""
    from sonartrack.metrics.statistics import rmse_over_runs

    k0 = config.turn_scan
    err_xy = trials["meas_error_xy"]
    err_m = np.hypot(err_xy[..., 0], err_xy[..., 1])
    bias = _nanmean_quiet(err_xy)  # (n_scans, 2)
    return {"runs": len(err_xy), "turn_scan": k0, "n_scans": config.n_scans,
            "meas_error_rms_m": rmse_over_runs(err_m).tolist(),
            "meas_error_mean_m": _nanmean_quiet(err_m).tolist(),
            "meas_bias_m": np.hypot(bias[:, 0], bias[:, 1]).tolist(),
            "clutter_per_scan": float(np.mean(trials["n_measurements"]) - config.pd),
            "cases": {case: _case_summary(trials, case, q, k0) for case, q in config.cases().items()}}


# ---- claims --------------------------------------------------------------------------------------
TOLERANCE = "2 standard errors of the paired per-run difference (Monte Carlo noise)"


def _paired(summary, a, b, key):
    """Mean and standard error of the paired per-run difference a - b (metrics/statistics.py)."""
    from sonartrack.metrics.statistics import paired_difference

    return paired_difference(summary["cases"][a][key], summary["cases"][b][key])


def _windows(config: Config):
    """The scans just before the turn and the second half of the scans after it."""
    k0, n = config.turn_scan, config.n_scans
    return slice(max(0, k0 - 20), k0), slice(k0 + (n - k0) // 2, n)


def _imm_best_claims(summary) -> list[Claim]:
    out = []
    for exp, imm in (("exp1", "imm2"), ("exp2", "imm3")):
        singles = [c for c in EXPERIMENTS[exp] if c != imm]
        best = max(singles, key=lambda c: summary["cases"][c]["ctt_all"])
        m, se = _paired(summary, imm, best, "per_run_all")
        mb, _ = _paired(summary, imm, best, "per_run_before")
        ma, _ = _paired(summary, imm, best, "per_run_after")
        out.append(Claim(f"{exp}-imm-best", "IMM-IPDA has the best CTT rate overall (Figs. 6, 9)",
                         f"{exp}: CTT rate of {LABELS[imm]} >= best single IPDA ({LABELS[best]}) over the whole run",
                         f"{summary['cases'][imm]['ctt_all']:.3f} vs {summary['cases'][best]['ctt_all']:.3f} "
                         f"(diff {m:+.3f} ± {se:.3f}; before turn {mb:+.3f}, after {ma:+.3f})", m >= -2 * se,
                         TOLERANCE))
    return out


def _single_q_claims(summary, config: Config) -> list[Claim]:
    from sonartrack.metrics.statistics import mean_and_standard_error
    pre, late = _windows(config)
    small = summary["cases"]["ipda_small"]
    r_pre = _window_mean(small["ctt_rate"], pre.start, pre.stop)
    r_late = _window_mean(small["ctt_rate"], late.start, late.stop)
    _, se = mean_and_standard_error(small["per_run_before"])  # noise scale for the drop
    out = [Claim("small-q-loses", "small-q IPDA degrades after the ownship turn (Figs. 6, 9)",
                 f"IPDA small q: CTT rate in scans {late.start}-{late.stop - 1} is below its rate in scans "
                 f"{pre.start}-{pre.stop - 1}", f"{r_late:.3f} after vs {r_pre:.3f} before", r_late < r_pre - 2 * se,
                 TOLERANCE)]
    m, se = _paired(summary, "imm2", "ipda_large", "per_run_before")
    out.append(Claim("large-q-before", "large-q IPDA tracks poorly before the turn (Fig. 6)",
                     "CTT rate before the turn: IPDA large q below IMM-IPDA",
                     f"{summary['cases']['ipda_large']['ctt_before']:.3f} vs "
                     f"{summary['cases']['imm2']['ctt_before']:.3f} "
                     f"(IMM - large {m:+.3f} ± {se:.3f})", m > 2 * se, TOLERANCE))
    return out


def _mode_claims(summary, config: Config) -> list[Claim]:
    pre, late = _windows(config)
    paper = "mode probability moves to larger q after the turn (Figs. 8, 11)"
    out = []
    for imm in ("imm2", "imm3"):
        mu = np.asarray(summary["cases"][imm]["mode_prob"], float)
        if mu.ndim != 2 or not np.isfinite(mu).any():
            out.append(Claim(f"{imm}-mode", paper, "no confirmed true track: mode probabilities undefined", "n/a",
                             False))
            continue
        big_before = _window_mean(mu[:, -1], pre.start, pre.stop)
        big_after = _window_mean(mu[:, -1], late.start, late.stop)
        out.append(Claim(f"{imm}-mode", paper,
                         f"{LABELS[imm]}: mean probability of the largest-q mode rises from scans {pre.start}-"
                         f"{pre.stop - 1} to scans {late.start}-{late.stop - 1}",
                         f"{big_before:.3f} -> {big_after:.3f}",
                         big_after > big_before, "strict increase of the run-averaged probability"))
    return out


def _measurement_claim(summary, config: Config) -> Claim:
    k0 = config.turn_scan
    e = np.asarray(summary["meas_error_rms_m"], float)
    start, before, after = (float(np.nanmean(e[:5])), float(np.nanmean(e[max(0, k0 - 5):k0])),
                            float(np.nanmean(e[k0:k0 + 5])))
    return Claim("meas-error", "measurement error ~220 m at the start, ~380 m after the turn (Fig. 5)",
                 "RMS measurement error at scans 0-4 within 20 % of 220 m, and at least 1.3x larger just after the "
                 "turn than just before it",
                 f"start {start:.0f} m, before turn {before:.0f} m, after turn {after:.0f} m",
                 abs(start - 220.0) <= 44.0 and after >= 1.3 * before,
                 "20 % on the start value (the paper's is one run read off a plot); factor 1.3 on the rise")


def claims(summary: dict, config: Config) -> list[Claim]:
    """The paper's results as checks on our numbers (tolerances: 2 standard errors of paired differences)."""
    return (_imm_best_claims(summary) + _single_q_claims(summary, config) + _mode_claims(summary, config)
            + [_measurement_claim(summary, config)])
