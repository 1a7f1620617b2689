"""Study P3: TMA with an acoustic propagation model in six Korean sea environments.

Seo 2019, "TMA using a propagation model" (paper 003, P3), Table 1, Fig. 7 and Table 2. One trial
simulates the scenario once in each of the six environments (East, Yellow, South Sea; summer and
winter) with bearings (sigma 0.5 deg) and SNRs (sigma 1 dB) drawn about their true values, and
solves it with

* EM/MAP (tma/em_map.py): bearings + SNR + the RAM TL curve with the true SL;
* bearings-only ML (tma/batch_ml.py, Gauss-Newton / LM) on the same bearings;
* EM/MAP again with the assumed SL off by delta (the SL-mismatch sweep), in a random share of trials.

Errors are the start-point and end-point X and Y errors normalised by the true range at that time
(%), the paper's Table 1 metric; the sweep records the normalised range error at both points.
"""

from __future__ import annotations

import functools

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from sonartrack.sim.platforms import ManeuveringTrack

STUDY_ID = "tma-propagation"
TITLE = "TMA with SNR and a RAM propagation model in six Korean seas (EM/MAP vs bearings-only ML)"
PAPER = "Seo 2019, target motion analysis with an acoustic propagation model (paper 003, P3)"
TRIAL_VERSION = 3
CHUNK_SIZE = 2

KNOT_MPS = 1852.0 / 3600.0
ENVIRONMENTS = ("east-summer", "east-winter", "yellow-summer", "yellow-winter", "south-summer", "south-winter")
#: paper Table 1, RMSE (%) of [start X, start Y, end X, end Y] normalised errors
PAPER_TABLE1 = {"east-summer": (1.88, 6.22, 0.61, 2.44), "east-winter": (0.39, 1.80, 1.09, 6.04),
                "yellow-summer": (1.13, 3.46, 0.26, 2.51), "yellow-winter": (1.40, 4.48, 0.28, 2.47),
                "south-summer": (0.30, 1.06, 0.28, 0.84), "south-winter": (0.75, 2.77, 0.58, 2.20)}
#: paper Table 2: SL mismatch (dB) with normalised range RMSE < 10 %
PAPER_TABLE2 = {"east-summer": (-18.0, 3.5), "east-winter": (-18.0, 2.0), "yellow-summer": (-0.5, 1.0),
                "yellow-winter": (-1.0, 0.5), "south-summer": (-5.0, 4.0), "south-winter": (-3.0, 2.5)}
#: the normalised error bound of the claims and of the tolerated-mismatch interval (%)
RMSE_LIMIT_PCT = 10.0


class Config(BaseModel):
    """The paper's scenario and our choices for what it leaves open.

    Paper values: 200 Hz, SL 140 dB, NL 73 dB, DI 12.5 dB, target depth = sensor depth; 100 frames 8 s
    apart; sigma_theta 0.5 deg, sigma_SNR 1 dB; observer with two course changes; target straight at
    initial bearing 160 deg; 100 runs per environment; SL mismatch -18..+18 dB.

    Our choices, with reasons:

    * **Environments**: the six tables of shared/data/korean_seas_environments.md (hand-built
      estimates, not climatology), sound speed by TEOS-10, fluid seabed half-spaces (East mud, Yellow
      muddy sand, South sand); TL from RAM (pyram) with Thorp absorption, averaged over 1 km.
    * **Sensor (= target) depth**: East Sea 200 m (the convergence zones of the East Sea appear for a
      deep sensor; at 50 m the summer direct path ends at 1.3 km and no zone forms), Yellow Sea 38 m
      (mid-water in 76 m), South Sea 50 m.
    * **Target placement**: the paper puts the South Sea target under 10 km and the Yellow and East
      Sea targets at 20-30 km. We start from those nominal ranges (South 8 km, Yellow 25 km, East 29 km:
      the first convergence zone, 27-31 km) and take the candidate initial range closest to the nominal
      one (250 m steps, within +-40 %) whose *computed* SNR stays above ``detection_threshold_db`` on
      every frame of the true track; the chosen ranges are in the summary.
    * **Geometry**: observer 6 kn, course 090, turning to 030 at 240-260 s and to 120 at 520-550 s
      (3 deg/s); target 6 kn on course 270 from bearing 160 deg.
    * **Range interval** of the EM/MAP latent range 0.5-50 km; kappa 1 % (tma/em_map.py).
    * **SL sweep** -18..+18 dB, 1.5 dB steps near 0 and 3-6 dB further out (the paper's Yellow Sea
      tolerances are +-1 dB), run in a random 30 % of the full runs (every quick run);
      the tolerated interval is the contiguous range of delta around 0 where the normalised range RMSE
      (start and end points pooled) stays below 10 %.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    runs: int = Field(100, ge=1)
    environments: list[str] = list(ENVIRONMENTS)
    freq_hz: float = Field(200.0, gt=0)
    sl_db: float = 140.0
    nl_db: float = 73.0
    di_db: float = 12.5
    detection_threshold_db: float = 3.0
    sensor_depth_m: dict[str, float] = {"east": 200.0, "yellow": 38.0, "south": 50.0}
    nominal_range_m: dict[str, float] = {"east": 29_000.0, "yellow": 25_000.0, "south": 8_000.0}
    n_frames: int = Field(100, ge=5)
    frame_period_s: float = Field(8.0, gt=0)
    sigma_bearing_deg: float = Field(0.5, gt=0)
    sigma_snr_db: float = Field(1.0, gt=0)
    own_speed_kn: float = 6.0
    own_course_deg: float = 90.0
    own_turns: list[list[float]] = [[240.0, 260.0, -3.0], [520.0, 550.0, 3.0]]
    target_speed_kn: float = 6.0
    target_course_deg: float = 270.0
    target_bearing_deg: float = 160.0
    r_min_m: float = Field(500.0, gt=0)
    r_max_m: float = Field(50_000.0, gt=0)
    sl_mismatch_db: list[float] = [-18.0, -12.0, -9.0, -6.0, -4.5, -3.0, -1.5, 0.0, 1.5, 3.0, 4.5, 6.0, 9.0, 12.0, 18.0]
    sweep_fraction: float = Field(0.3, gt=0, le=1)

    @classmethod
    def quick(cls) -> Config:
        return cls(runs=6, sweep_fraction=1.0)

    def times_s(self) -> np.ndarray:
        return np.arange(self.n_frames) * self.frame_period_s

    def observer(self) -> ManeuveringTrack:
        return ManeuveringTrack(0.0, 0.0, self.own_speed_kn * KNOT_MPS, np.deg2rad(self.own_course_deg),
                                tuple((a, b, np.deg2rad(r)) for a, b, r in self.own_turns))

    def sea(self, env: str) -> str:
        return env.split("-")[0]

    def target(self, r0_m: float) -> ManeuveringTrack:
        b = np.deg2rad(self.target_bearing_deg)
        return ManeuveringTrack(r0_m * np.sin(b), r0_m * np.cos(b), self.target_speed_kn * KNOT_MPS,
                                np.deg2rad(self.target_course_deg))


@functools.lru_cache(maxsize=32)
def _snr_curve(env_name: str, depth_m: float, freq_hz: float, rmax_m: float, sl_db: float, di_db: float,
               nl_db: float) -> tuple[np.ndarray, np.ndarray]:
    """(ranges, mean SNR) at the sensor depth, TL averaged over 1 km (cached on disk and in memory)."""
    from sonartrack.acoustics.environment import load_environment
    from sonartrack.acoustics.sonar_equation import passive_snr_db
    from sonartrack.acoustics.transmission_loss import smooth_tl, tl_field
    from sonartrack.tma.batch import TL_AVERAGE_M

    f = tl_field(load_environment(env_name), freq_hz, depth_m, rmax_m=rmax_m)
    line = smooth_tl(f.ranges_m, f.at_depth(depth_m), TL_AVERAGE_M)
    return f.ranges_m, passive_snr_db(sl_db, line, di_db, nl_db)


def snr_curve(config: Config, env: str):
    return _snr_curve(env, float(config.sensor_depth_m[config.sea(env)]), config.freq_hz, 1.05 * config.r_max_m,
                      config.sl_db, config.di_db, config.nl_db)


def prepare(config: Config) -> None:
    """Compute (or load) the six TL fields once, before the workers start."""
    for env in config.environments:
        snr_curve(config, env)


@functools.lru_cache(maxsize=32)
def _placement(config_json: str, env: str) -> tuple[float, float]:
    """(initial range, min SNR over the track) of the target in ``env`` (Config doc)."""
    config = Config.model_validate_json(config_json)
    ranges, snr = snr_curve(config, env)
    t = config.times_s()
    po, _, _ = config.observer().state(t)
    nominal = config.nominal_range_m[config.sea(env)]
    cands = np.arange(0.6 * nominal, 1.4 * nominal + 1.0, 250.0)
    cands = cands[np.argsort(np.abs(cands - nominal), kind="stable")]
    best = (float(nominal), -np.inf)
    for r0 in cands:
        pt, _, _ = config.target(r0).state(t)
        s_min = float(np.min(np.interp(np.linalg.norm(pt - po, axis=1), ranges, snr)))
        if s_min >= config.detection_threshold_db:
            return float(r0), s_min
        if s_min > best[1]:
            best = (float(r0), s_min)
    return best


def placement(config: Config, env: str) -> tuple[float, float]:
    return _placement(config.model_dump_json(), env)


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One draw of bearings and SNRs per environment; EM/MAP, ML and (sometimes) the SL sweep."""
    from sonartrack.tma.batch_ml import ml_bearings_only
    from sonartrack.tma.em_map import make_problem, solve_em_map

    t = config.times_s()
    po, _, _ = config.observer().state(t)
    sb = np.deg2rad(config.sigma_bearing_deg)
    sweep = bool(rng.random() < config.sweep_fraction)
    out: dict[str, np.ndarray] = {}
    for env in config.environments:
        ranges, snr = snr_curve(config, env)
        r0, _ = placement(config, env)
        pt, vt, _ = config.target(r0).state(t)
        d = pt - po
        rng_true = np.linalg.norm(d, axis=1)
        z = np.arctan2(d[:, 0], d[:, 1]) + rng.normal(0.0, sb, len(t))
        xi = np.interp(rng_true, ranges, snr) + rng.normal(0.0, config.sigma_snr_db, len(t))
        truth = np.array([pt[0, 0], pt[0, 1], pt[-1, 0], pt[-1, 1]])
        norm = np.array([rng_true[0], rng_true[0], rng_true[-1], rng_true[-1]])

        def errors(x0):
            end = x0[:2] + x0[2:] * (t[-1] - t[0])
            return 100.0 * (np.concatenate([x0[:2], end]) - truth) / norm

        def range_errors(x0):
            end = x0[:2] + x0[2:] * (t[-1] - t[0])
            return 100.0 * np.abs(np.array([np.linalg.norm(x0[:2] - po[0]), np.linalg.norm(end - po[-1])])
                                  - rng_true[[0, -1]]) / rng_true[[0, -1]]

        ml_x0 = None
        out[f"{env}_ml"] = np.full(4, np.nan)  # a failed ML solve (diverged towards infinite range)
        try:
            ml = ml_bearings_only(z, t, po, sb)
            if ml.converged and np.hypot(*(ml.x0[:2] - po[0])) < 5.0 * config.r_max_m:
                ml_x0 = ml.x0
                out[f"{env}_ml"] = errors(ml.x0)
        except np.linalg.LinAlgError:
            pass

        def em(shift_db):
            prob = make_problem(z, xi, t, po, sb, config.sigma_snr_db,
                                lambda r: np.interp(r, ranges, snr) + shift_db, config.r_min_m, config.r_max_m)
            return solve_em_map(prob, t0_s=0.0, extra_starts=[ml_x0], covariance=False).x0

        out[f"{env}_em"] = errors(em(0.0))
        sw = np.full((len(config.sl_mismatch_db), 2), np.nan)
        if sweep:
            for i, delta in enumerate(config.sl_mismatch_db):
                sw[i] = range_errors(em(delta))  # assumed SL = true + delta shifts the predicted SNR by delta
        out[f"{env}_sweep"] = sw
    return out


def _nanmean(a, axis=0):
    a = np.asarray(a, dtype=float)
    n = np.sum(np.isfinite(a), axis=axis)
    return np.where(n > 0, np.nansum(a, axis=axis) / np.maximum(n, 1), np.nan)


def _rmse(a, axis=0):
    return np.sqrt(_nanmean(np.asarray(a, dtype=float) ** 2, axis=axis))


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    """Table 1 (mean and RMSE, EM/MAP and ML), Table 2 (tolerated SL mismatch), placements, curves."""
    deltas = np.asarray(config.sl_mismatch_db, dtype=float)
    envs = {}
    for env in config.environments:
        em, ml, sw = trials[f"{env}_em"], trials[f"{env}_ml"], trials[f"{env}_sweep"]
        r0, s_min = placement(config, env)
        pooled = sw.reshape(sw.shape[0], len(deltas) * 2)
        n_sweep = int(np.sum(np.all(np.isfinite(pooled), axis=1)))
        curve = _rmse(sw.transpose(1, 0, 2).reshape(len(deltas), -1), axis=1) if n_sweep else np.full(len(deltas), np.nan)
        ok = curve < RMSE_LIMIT_PCT
        i0 = int(np.argmin(np.abs(deltas)))
        lo = hi = None
        if ok[i0]:
            a = i0
            while a > 0 and ok[a - 1]:
                a -= 1
            b = i0
            while b < len(deltas) - 1 and ok[b + 1]:
                b += 1
            lo, hi = float(deltas[a]), float(deltas[b])
        ranges, snr = snr_curve(config, env)
        envs[env] = {
            "initial_range_m": r0, "min_snr_on_track_db": s_min,
            "sensor_depth_m": config.sensor_depth_m[config.sea(env)],
            "em_mean_pct": np.nanmean(em, axis=0).tolist(), "em_rmse_pct": _rmse(em).tolist(),
            "ml_mean_pct": _nanmean(ml).tolist(), "ml_rmse_pct": _rmse(ml).tolist(),
            "ml_failed": int(np.sum(~np.all(np.isfinite(ml), axis=1))),
            "paper_rmse_pct": list(PAPER_TABLE1.get(env, (np.nan,) * 4)),
            "sweep_runs": n_sweep, "sweep_rmse_pct": curve.tolist(),
            "tolerated_db": [lo, hi], "paper_tolerated_db": list(PAPER_TABLE2.get(env, (np.nan, np.nan))),
            "start_errors_em": em[:, :2].tolist(), "start_errors_ml": ml[:, :2].tolist(),
            "snr_ranges_km": (ranges[::4] / 1e3).tolist(), "snr_db": snr[::4].tolist(),
        }
    return {"runs": len(next(iter(trials.values()))), "deltas_db": deltas.tolist(), "environments": envs}


def _arr(x) -> np.ndarray:
    """A summary list as floats (JSON turns NaN, e.g. an RMSE over no successful run, into None)."""
    return np.array([np.nan if v is None else v for v in x], dtype=float)


def claims(summary: dict, config: Config) -> list[dict]:
    envs = summary["environments"]
    out = []
    worst = {e: float(np.max(_arr(v["em_rmse_pct"]))) for e, v in envs.items()}
    out.append({"id": "em_map_under_10pct", "text": "EM/MAP normalised RMSE (start/end, X/Y) below 10 % in every environment with the true SL",
                "paper": "Table 1: 0.26-6.22 %",
                "ours": "; ".join(f"{e} {w:.2f} %" for e, w in worst.items()),
                "tolerance": "every component < 10 %", "holds": bool(all(w < RMSE_LIMIT_PCT for w in worst.values()))})
    cmp = {e: (float(np.mean(_arr(v["em_rmse_pct"]))), float(np.mean(_arr(v["ml_rmse_pct"]))), v["ml_failed"])
           for e, v in envs.items()}
    # ML that failed (diverged) in some runs is worse there whatever its RMSE over the rest
    ok = all(np.isfinite(a) and (f > 0 or not np.isfinite(b) or a <= 1.1 * b) for a, b, f in cmp.values())
    out.append({"id": "em_map_not_worse_than_ml", "text": "EM/MAP at least as accurate as bearings-only ML on the same data",
                "paper": "the SNR and the propagation model improve on bearings-only TMA",
                "ours": "; ".join(f"{e} {a:.2f} vs {b:.2f} %" + (f" (ML diverged in {f}/{summary['runs']} runs)" if f else "")
                                  for e, (a, b, f) in cmp.items()),
                "tolerance": "mean RMSE of EM/MAP <= 1.1 x ML's in each environment (Monte Carlo error of an RMSE over "
                             f"{summary['runs']} runs is ~{100 / np.sqrt(2 * summary['runs']):.0f} %)",
                "holds": bool(ok)})
    lows = {e: v["tolerated_db"][0] for e, v in envs.items()}
    east = [lows[e] for e in lows if e.startswith("east")]
    other = [lows[e] for e in lows if not e.startswith("east")]
    if not east or not other or any(v is None for v in east + other):
        holds = False  # a sea not run, or a case with no tolerated interval at all
    else:
        holds = max(east) < min(other)
    fmt = lambda v: "none" if v[0] is None else f"{v[0]:+g}..{v[1]:+g} dB"  # noqa: E731
    out.append({"id": "east_tolerates_low_sl", "text": "the tolerated SL-mismatch interval reaches further towards "
                "under-assumed SL in the East Sea than in the Yellow and South Seas",
                "paper": "Table 2: East -18..+3.5/+2; Yellow -0.5..+1, -1..+0.5; South -5..+4, -3..+2.5",
                "ours": "; ".join(f"{e} {fmt(v['tolerated_db'])}" for e, v in envs.items()),
                "tolerance": "the lower ends, on the sweep's grid (1.5 dB steps near 0)",
                "holds": bool(holds)})
    widths = {e: (None if v["tolerated_db"][0] is None else v["tolerated_db"][1] - v["tolerated_db"][0]) for e, v in envs.items()}
    east_w = [widths[e] for e in widths if e.startswith("east")]
    other_w = [widths[e] for e in widths if not e.startswith("east")]
    holds_w = bool(east_w) and bool(other_w) and None not in east_w and \
        min(east_w) > max([w for w in other_w if w is not None], default=-1.0)
    out.append({"id": "east_tolerates_wider_mismatch", "text": "the East Sea (convergence zones) tolerates a wider SL "
                "mismatch than the Yellow and South Seas (width of the tolerated interval)",
                "paper": "Table 2: East 21.5 and 20 dB wide; Yellow 1.5 dB; South 9 and 5.5 dB",
                "ours": "; ".join(f"{e} {'none' if w is None else f'{w:g} dB'}" for e, w in widths.items()),
                "tolerance": "every East case wider than every other case", "holds": bool(holds_w)})
    return out


def figures(summary: dict, config: Config) -> dict:
    import matplotlib.pyplot as plt

    from sonartrack.acoustics.environment import load_environment

    figs = {"scenario": _scenario_figure(summary, config)}
    envs = summary["environments"]

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.5))
    for ax, sea in zip(axes, ("east", "yellow", "south")):
        for env in [e for e in config.environments if e.startswith(sea)]:
            e = load_environment(env)
            ax.plot(e.sound_speed_mps, e.depth_m, label=env)
        ax.invert_yaxis()
        ax.set(xlabel="sound speed (m/s)", ylabel="depth (m)", title=f"{sea.title()} Sea profiles (TEOS-10)")
        if ax.lines:
            ax.legend(fontsize=7)
    fig.tight_layout()
    figs["sound_speed"] = fig

    fig, axes = plt.subplots(2, 3, figsize=(15, 7))
    from sonartrack.acoustics.transmission_loss import tl_field

    for ax, env in zip(axes.T.ravel(), config.environments):
        depth = config.sensor_depth_m[config.sea(env)]
        f = tl_field(load_environment(env), config.freq_hz, depth, rmax_m=1.05 * config.r_max_m)
        im = ax.pcolormesh(f.ranges_m / 1e3, f.depths_m, f.tl_db, vmin=50, vmax=110, cmap="jet_r", shading="auto")
        ax.invert_yaxis()
        ax.set(title=f"TL {env}, source {depth:g} m", xlabel="range (km)", ylabel="depth (m)")
        fig.colorbar(im, ax=ax, label="TL (dB)")
    fig.tight_layout()
    figs["tl_fields"] = fig

    fig, ax = plt.subplots(figsize=(9, 4.5))
    for env, v in envs.items():
        line, = ax.plot(v["snr_ranges_km"], v["snr_db"], lw=1, label=env)
        ax.axvline(v["initial_range_m"] / 1e3, color=line.get_color(), ls=":", lw=1)
    ax.axhline(config.detection_threshold_db, color="k", lw=0.8)
    ax.set(xlabel="range (km)", ylabel="SNR (dB)", title="SNR = SL - TL + DI - NL at the sensor depth "
           "(dotted: the target's initial range)", ylim=(-40, 60))
    ax.legend(fontsize=7)
    figs["snr_vs_range"] = fig

    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    for ax, env in zip(axes.T.ravel(), config.environments):
        em = np.array([_arr(r) for r in envs[env]["start_errors_em"]]).reshape(-1, 2)
        ml = np.array([_arr(r) for r in envs[env]["start_errors_ml"]]).reshape(-1, 2)
        ax.plot(ml[:, 0], ml[:, 1], "x", ms=4, label="bearings-only ML")
        ax.plot(em[:, 0], em[:, 1], "o", ms=3, label="EM/MAP")
        ax.axhline(0, color="k", lw=0.5)
        ax.axvline(0, color="k", lw=0.5)
        ax.set(title=f"start-point errors {env}", xlabel="X error (% of range)", ylabel="Y error (% of range)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    figs["error_scatter"] = fig

    fig, ax = plt.subplots(figsize=(9, 4.5))
    d = summary["deltas_db"]
    for env, v in envs.items():
        ax.plot(d, _arr(v["sweep_rmse_pct"]), "o-", ms=3, label=env)
    ax.axhline(RMSE_LIMIT_PCT, color="k", ls="--", lw=0.8)
    ax.set(yscale="log", xlabel="assumed SL - true SL (dB)", ylabel="normalised range RMSE (%)",
           title="SL mismatch (paper Fig. 7)")
    ax.legend(fontsize=7)
    figs["sl_mismatch"] = fig
    return figs


def _scenario_figure(summary: dict, config: Config):
    import matplotlib.pyplot as plt

    t = config.times_s()
    po, _, _ = config.observer().state(t)
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.plot(po[:, 0] / 1e3, po[:, 1] / 1e3, "k-", lw=2, label="observer (two course changes)")
    for env, v in summary["environments"].items():
        if env.endswith("summer"):
            pt, _, _ = config.target(v["initial_range_m"]).state(t)
            ax.plot(pt[:, 0] / 1e3, pt[:, 1] / 1e3, "-", label=f"target, {config.sea(env)} Sea ({v['initial_range_m'] / 1e3:.1f} km)")
            ax.plot(pt[0, 0] / 1e3, pt[0, 1] / 1e3, "o", color=ax.lines[-1].get_color())
    ax.set(xlabel="x east (km)", ylabel="y north (km)", aspect="equal",
           title=f"{config.n_frames} frames x {config.frame_period_s:g} s; target from bearing {config.target_bearing_deg:g} deg")
    ax.legend(fontsize=7)
    return fig
