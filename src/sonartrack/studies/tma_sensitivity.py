"""Sensitivity of study P3's failing claims to the choices the paper leaves open.

Seo 2019 (paper P3) leaves open the latent range interval of EM/MAP, the sensor depth, the TL range
averaging and the South Sea winter profile (studies/tma_propagation.py, Config doc). This study re-runs
tma-propagation's scenario under other readings of the first three, one factor at a time from the
study's default, for the two claims that failed at full size under the earlier readings (latent range
0.5-50 km, TL averaged over 1 km; the fidelity review adopted 3-50 km and no averaging, and the alternatives below
include the earlier values):

* ``em_map_under_10pct`` in **South winter** (the only environment over 10 % before): TL averaging window,
  sensor (= target) depth, latent range interval (r_min, r_max). Per reading: the RMSE (%) of the four
  normalised errors (start/end X/Y, paper Table 1) with a 95 % bootstrap interval over runs (and the
  chi-square interval for an RMS of zero-mean normal errors, n degrees of freedom:
  RMSE sqrt(n / chi2_{0.975,n}) .. RMSE sqrt(n / chi2_{0.025,n})), the short SL sweep near 0 (the
  tolerated interval of tma-propagation needs South winter's range RMSE < 10 % at delta = 0), and the
  flatness of the true SNR-range curve over the ranges the track covers (mean |dSNR/dr|, dB/km: the
  SNR carries range information only where the curve has a slope; eq. (9)-(11) of the paper's EM).
* ``east_tolerates_low_sl`` in **East summer and winter**: latent range interval's lower end and sensor
  depth; per reading the full SL-mismatch sweep of tma-propagation (pooled start/end normalised range
  RMSE per delta) and the tolerated interval, with 95 % bootstrap intervals on its two ends.

Common random numbers: a trial draws exactly what a tma-propagation trial draws (the sweep flag, then
bearing and SNR noise per environment in ``environments`` order), so the default reading of South
winter is tma-propagation's trial itself (same seed, same numbers); every reading reuses the same noise.
A reading re-places the target with the study's rule (tma_propagation.placement) on its own SNR curve.

config -> run_trial -> summarize -> claims (none: the claims live in tma-propagation); pictures in
report/figures/tma_sensitivity.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sonartrack.core.settings import setting
from sonartrack.studies import tma_propagation as base

STUDY_ID = "tma-sensitivity"
TITLE = "P3 sensitivity: EM/MAP accuracy in South winter and East's tolerated SL mismatch under the open choices"
PAPER = "Seo 2019, target motion analysis with an acoustic propagation model (paper 003, P3)"
TRIAL_VERSION = 1
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 100
QUICK_RUNS = 2
CHUNK_SIZE = 2

RMSE_LIMIT_PCT = base.RMSE_LIMIT_PCT


class Config(base.Config):
    """tma-propagation's scenario (every field of its Config, same defaults) plus the grid of readings."""

    runs: int = setting(RUNS, "Monte Carlo runs (South readings in each; East readings in east_fraction of them)",
                        unit="1", ge=1)
    south_env: str = setting("south-winter", "environment of the em_map_under_10pct readings")
    east_envs: list[str] = setting(default_factory=lambda: ["east-summer", "east-winter"],
                                   doc="environments of the east_tolerates_low_sl readings")
    tl_windows_m: list[float] = setting(default_factory=lambda: [500.0, 1000.0, 2000.0],
                                        doc="other TL averaging windows (South)", unit="m")
    south_depths_m: list[float] = setting(default_factory=lambda: [30.0, 80.0, 120.0],
                                          doc="other sensor (= target) depths (South)", unit="m")
    south_r_min_m: list[float] = setting(default_factory=lambda: [500.0, 2000.0],
                                         doc="other lower ends of the latent range interval (South)", unit="m")
    south_r_max_m: list[float] = setting(default_factory=lambda: [20_000.0],
                                         doc="other upper ends of the latent range interval (South)", unit="m")
    east_r_min_m: list[float] = setting(default_factory=lambda: [500.0, 10_000.0],
                                        doc="other lower ends of the latent range interval (East)", unit="m")
    east_depths_m: list[float] = setting(default_factory=lambda: [100.0, 300.0],
                                         doc="other sensor (= target) depths (East)", unit="m")
    other_envs: list[str] = setting(
        default_factory=lambda: ["yellow-summer", "yellow-winter", "south-summer", "south-winter"],
        doc="environments swept under other_r_min_m too (the claim compares East with them)")
    other_r_min_m: list[float] = setting(default_factory=lambda: [500.0],
                                         doc="latent-interval lower ends swept in other_envs", unit="m")
    south_sweep_db: list[float] = setting(default_factory=lambda: [-1.5, 0.0, 1.5],
                                          doc="SL mismatches swept in South (near 0 only)", unit="dB")
    east_fraction: float = setting(0.3, "share of runs that run the swept readings (East, other_envs: a full SL "
                                        "sweep is ~15 solves per reading; the South readings run in every run)",
                                   unit="1", gt=0, le=1)
    bootstrap: int = setting(2000, "bootstrap resamples of the runs for the intervals", unit="1", ge=10)

    @classmethod
    def quick(cls) -> Config:
        """CI preset: one East environment, a few readings, a short sweep, 2 runs (TL fields cached)."""
        return cls(runs=QUICK_RUNS, east_envs=["east-summer"], tl_windows_m=[1000.0], south_depths_m=[80.0],
                   south_r_max_m=[], east_depths_m=[], east_r_min_m=[500.0], south_sweep_db=[0.0], other_envs=[],
                   sl_mismatch_db=[-6.0, -3.0, 0.0, 3.0, 6.0], east_fraction=1.0, bootstrap=50)


@dataclass(frozen=True, slots=True)
class Reading:
    """One reading of the open choices in one environment (``sweep``: the full SL sweep, else South's)."""

    id: str
    label: str
    env: str
    depth_m: float
    window_m: float
    r_min_m: float
    r_max_m: float
    sweep: bool


def _reading(config: Config, env: str, sweep: bool, tag: str, label: str, **kw) -> Reading:
    d = {"depth_m": float(config.sensor_depth_m[config.sea(env)]), "window_m": config.em_map.tl_average_m,
         "r_min_m": config.em_map.r_min_m, "r_max_m": config.em_map.r_max_m, **kw}
    return Reading(f"{env}:{tag}", label, env, sweep=sweep, **d)


def readings(config: Config) -> list[Reading]:
    """The grid, one factor at a time from the default (the first reading of each environment)."""
    s = config.south_env
    out = [_reading(config, s, False, "default", "default (tma-propagation)")]
    out += [_reading(config, s, False, f"window_{w:g}", f"TL window {w / 1e3:g} km", window_m=w)
            for w in config.tl_windows_m]
    out += [_reading(config, s, False, f"depth_{z:g}", f"depth {z:g} m", depth_m=z) for z in config.south_depths_m]
    out += [_reading(config, s, False, f"rmin_{r:g}", f"r_min {r / 1e3:g} km", r_min_m=r) for r in config.south_r_min_m]
    out += [_reading(config, s, False, f"rmax_{r:g}", f"r_max {r / 1e3:g} km", r_max_m=r) for r in config.south_r_max_m]
    for e in config.east_envs:
        out += [_reading(config, e, True, "default", "default (tma-propagation)")]
        out += [_reading(config, e, True, f"rmin_{r:g}", f"r_min {r / 1e3:g} km", r_min_m=r)
                for r in config.east_r_min_m]
        out += [_reading(config, e, True, f"depth_{z:g}", f"depth {z:g} m", depth_m=z) for z in config.east_depths_m]
    for e in config.other_envs:  # the claim compares East's lower end with these seas' under the same reading
        out += [_reading(config, e, True, f"swept_rmin_{r:g}", f"r_min {r / 1e3:g} km (swept)", r_min_m=r)
                for r in config.other_r_min_m]
    return out


def snr_curve(config: Config, r: Reading) -> tuple[np.ndarray, np.ndarray]:
    """(ranges (m), true mean SNR (dB)) of a reading; the field always reaches 1.05 x the study's r_max, so
    an r_max reading changes the latent interval only, not the TL field."""
    return base._snr_curve(r.env, r.depth_m, r.window_m, config.freq_hz, 1.05 * config.em_map.r_max_m, config.sl_db,
                           config.di_db, config.nl_db)


def placement(config: Config, r: Reading) -> tuple[float, float]:
    """(initial range, min SNR on the track): tma_propagation's placement rule on the reading's curve."""
    return base.place_target(config, r.env, *snr_curve(config, r))

def prepare(config: Config) -> None:
    """Compute (or load) every reading's TL field once, before the workers start."""
    for r in readings(config):
        snr_curve(config, r)


def deltas_of(config: Config, r: Reading) -> list[float]:
    return list(config.sl_mismatch_db) if r.sweep else list(config.south_sweep_db)


def _reading_trial(config: Config, r: Reading, noise: tuple[np.ndarray, np.ndarray], t, po) -> dict:
    """tma_propagation._environment_trial for one reading, with the trial's noise (common random numbers)."""
    ranges, snr = snr_curve(config, r)
    r0, _ = placement(config, r)
    obs = base.observe(config, ranges, snr, r0, t, po, noise)
    sb = np.deg2rad(config.sigma_bearing_deg)
    cfg = config.model_copy(update={"em_map": config.em_map.model_copy(update={"r_max_m": r.r_max_m})})
    ml_x0 = base._ml_x0(cfg, obs.z, t, po, sb)
    em_x0 = base.em_map_x0(config, obs, t, po, ranges, snr, ml_x0, r.r_min_m, r.r_max_m)
    x0 = em_x0(0.0)
    deltas = deltas_of(config, r)
    sw = np.array([base._range_errors(x0 if dl == 0.0 else em_x0(dl), t, po, obs.range_m) for dl in deltas])
    return {"em": base._normalised_errors(x0, t, obs.truth, obs.norm), "sweep": sw}


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Draw what a tma-propagation trial draws, then solve every reading on that noise."""
    t = config.times_s()
    po, _, _ = config.observer().state(t)
    rng.random()  # tma-propagation's sweep flag: drawn to keep the sequence; every reading sweeps here
    sb = np.deg2rad(config.sigma_bearing_deg)
    noise = {env: (rng.normal(0.0, sb, len(t)), rng.normal(0.0, config.sigma_snr_db, len(t)))
             for env in config.environments}
    swept = bool(rng.random() < config.east_fraction)  # drawn after tma-propagation's draws: they stay equal
    out: dict[str, np.ndarray] = {}
    for r in readings(config):
        if r.sweep and not swept:
            res = {"em": np.full(4, np.nan), "sweep": np.full((len(deltas_of(config, r)), 2), np.nan)}
        else:
            res = _reading_trial(config, r, noise[r.env], t, po)
        for key, value in res.items():
            out[f"{r.id}_{key}"] = value
    return out


# ---------------------------------------------------------------------------------------------- summary


def _boot_indices(n: int, config: Config) -> np.ndarray:
    """Bootstrap resamples of the run indices (fixed seed: the summary is a function of the trials)."""
    return np.random.default_rng(20261129).integers(0, n, size=(config.bootstrap, n))


def _interval(values) -> list[float]:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return [float(np.quantile(v, 0.025)), float(np.quantile(v, 0.975))] if len(v) else [np.nan, np.nan]


def chi2_rms_interval(rmse: float, n: int) -> list[float]:
    """95 % interval of an RMS of n zero-mean normal errors: RMSE sqrt(n / chi2 quantiles (n dof))."""
    from scipy.stats import chi2

    return [float(rmse * np.sqrt(n / chi2.ppf(0.975, n))), float(rmse * np.sqrt(n / chi2.ppf(0.025, n)))]


def curve_flatness(config: Config, r: Reading) -> dict:
    """The SNR-range curve over the track's true ranges: span, SNR span and mean |dSNR/dr| (dB/km)."""
    ranges, snr = snr_curve(config, r)
    r0, s_min = placement(config, r)
    t = config.times_s()
    po, _, _ = config.observer().state(t)
    pt, _, _ = config.target(r0).state(t)
    rt = np.linalg.norm(pt - po, axis=1)
    lo, hi = float(rt.min()), float(rt.max())
    inside = (ranges >= lo) & (ranges <= hi)
    slope = np.abs(np.gradient(snr[inside], ranges[inside])) * 1e3 if inside.sum() > 2 else np.array([np.nan])
    s_track = np.interp(rt, ranges, snr)
    keep = ranges <= max(2.0 * hi, 15_000.0)
    step = max(1, int(keep.sum() // 400))
    return {"initial_range_m": r0, "min_snr_on_track_db": s_min, "track_range_km": [lo / 1e3, hi / 1e3],
            "snr_span_on_track_db": float(s_track.max() - s_track.min()),
            "mean_abs_slope_db_per_km": float(np.mean(slope)),
            "curve_km": (ranges[keep][::step] / 1e3).tolist(), "curve_db": snr[keep][::step].tolist()}


def _ran(a: np.ndarray) -> np.ndarray:
    """The runs (axis 0) that ran the reading (an East reading skipped in a run is all NaN there)."""
    a = np.asarray(a, dtype=float)
    return a[~np.all(np.isnan(a.reshape(len(a), -1)), axis=1)]


def _accuracy(trials: dict, config: Config, r: Reading) -> dict:
    """RMSE (%) per component with intervals, and the largest component with its bootstrap interval."""
    from sonartrack.metrics.statistics import rmse_over_runs

    em = _ran(trials[f"{r.id}_em"])
    idx = _boot_indices(len(em), config)
    rmse = rmse_over_runs(em)
    boot = np.sqrt(np.nanmean(em[idx] ** 2, axis=1))  # (B, 4)
    worst = float(np.max(rmse))
    worst_ci = _interval(np.max(boot, axis=1))
    n = int(np.sum(np.all(np.isfinite(em), axis=1)))
    return {"runs": len(em), "em_rmse_pct": rmse.tolist(), "em_rmse_ci_pct": [_interval(boot[:, k]) for k in range(4)],
            "em_rmse_chi2_ci_pct": [chi2_rms_interval(float(v), n) for v in rmse],
            "worst_pct": worst, "worst_ci_pct": worst_ci,
            "under_10pct": _verdict(worst_ci[1] < RMSE_LIMIT_PCT, worst_ci[0] >= RMSE_LIMIT_PCT)}


def _verdict(holds: bool, fails: bool) -> str:
    return "holds" if holds else "fails" if fails else "undecided"


def _sweep(trials: dict, config: Config, r: Reading) -> dict:
    """Pooled range RMSE per SL mismatch, the tolerated interval and bootstrap intervals on its ends."""
    from sonartrack.metrics.statistics import rmse_over_runs

    deltas = np.asarray(deltas_of(config, r), dtype=float)
    sw = _ran(trials[f"{r.id}_sweep"])  # (runs, deltas, 2)
    idx = _boot_indices(len(sw), config)
    pooled = sw.transpose(1, 0, 2)  # (deltas, runs, 2)
    curve = rmse_over_runs(pooled.reshape(len(deltas), -1), axis=1)
    boot = np.sqrt(np.nanmean(pooled[:, idx, :] ** 2, axis=(2, 3))).T  # (B, deltas)
    ends = np.array([[np.nan if e is None else e for e in base.tolerated_interval(deltas, c)] for c in boot])
    lo, hi = base.tolerated_interval(deltas, curve)
    return {"sweep_runs": len(sw), "deltas_db": deltas.tolist(), "sweep_rmse_pct": curve.tolist(),
            "sweep_rmse_ci_pct": [_interval(boot[:, k]) for k in range(len(deltas))],
            "tolerated_db": [lo, hi], "tolerated_lower_ci_db": _interval(ends[:, 0]),
            "tolerated_upper_ci_db": _interval(ends[:, 1]),
            "share_without_interval": float(np.mean(np.isnan(ends[:, 0]))),
            "leaning": _leaning(lo, hi)}


def _leaning(lo: float | None, hi: float | None) -> str:
    """Which way the tolerated interval reaches further: 'under' (|lower| > upper, the paper's East), 'over',
    'symmetric', or 'none' (no interval)."""
    if lo is None or hi is None:
        return "none"
    return "under" if -lo > hi else "over" if -lo < hi else "symmetric"


def _why(row: dict, r: Reading) -> str:
    """A one-line reason from the numbers (the curve's flatness, or where the sweep breaks)."""
    f = row["flatness"]
    txt = (f"SNR slope {f['mean_abs_slope_db_per_km']:.2f} dB/km over {f['track_range_km'][0]:.1f}-"
           f"{f['track_range_km'][1]:.1f} km (span {f['snr_span_on_track_db']:.1f} dB)")
    if r.sweep:
        lo, hi = row["tolerated_db"]
        txt += "; no interval" if lo is None else f"; tolerated {lo:+g}..{hi:+g} dB"
    elif 0.0 in row["deltas_db"]:
        txt += f"; range RMSE at 0 dB {row['sweep_rmse_pct'][row['deltas_db'].index(0.0)]:.1f} %"
    return txt


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    """Per reading: accuracy (RMSE with intervals), the SL sweep, the curve's flatness; and the table."""
    n = len(next(iter(trials.values())))
    rows = []
    for r in readings(config):
        row = {"id": r.id, "label": r.label, "env": r.env, "sweep": r.sweep, "depth_m": r.depth_m,
               "window_m": r.window_m, "r_min_m": r.r_min_m, "r_max_m": r.r_max_m,
               **_accuracy(trials, config, r), **_sweep(trials, config, r),
               "flatness": curve_flatness(config, r)}
        row["why"] = _why(row, r)
        rows.append(row)
    return {"runs": n, "rmse_limit_pct": RMSE_LIMIT_PCT, "paper_tolerated_db": base.PAPER_TABLE2,
            "paper_rmse_pct": base.PAPER_TABLE1, "readings": rows, "table": table(rows)}


def table(rows: list[dict]) -> list[dict]:
    """Reading -> number with interval -> claim holds or not -> why (one row per reading)."""
    out = []
    for w in rows:
        if w["sweep"]:
            lo, hi = w["tolerated_db"]
            num = "none" if lo is None else (f"{lo:+g}..{hi:+g} dB (lower 95 % {w['tolerated_lower_ci_db'][0]:+g}.."
                                             f"{w['tolerated_lower_ci_db'][1]:+g})")
            verdict = {"none": "no interval", "under": "towards under-assumed SL (paper)",
                       "over": "towards over-assumed SL", "symmetric": "symmetric"}[w["leaning"]]
            claim = "east_tolerates_low_sl"
        else:
            num = f"{w['worst_pct']:.2f} % [{w['worst_ci_pct'][0]:.2f}, {w['worst_ci_pct'][1]:.2f}]"
            verdict, claim = w["under_10pct"], "em_map_under_10pct"
        out.append({"reading": f"{w['env']}: {w['label']}", "claim": claim, "number": num, "verdict": verdict,
                    "why": w["why"]})
    return out


def claims(summary: dict, config: Config) -> list:
    """None: the claims live in tma-propagation; this study is their evidence."""
    return []
