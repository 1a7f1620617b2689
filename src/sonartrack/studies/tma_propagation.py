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

config -> run_trial -> summarize -> claims; the pictures are ``report/figures/tma_propagation.py``.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.core.units import KNOT_MPS
from sonartrack.experiment.claims import Claim
from sonartrack.tma.settings import EmMapSettings

if TYPE_CHECKING:
    from sonartrack.sim.platforms import ManeuveringTrack

STUDY_ID = "tma-propagation"
TITLE = "TMA with SNR and a RAM propagation model in six Korean seas (EM/MAP vs bearings-only ML)"
PAPER = "Seo 2019, target motion analysis with an acoustic propagation model (paper 003, P3)"
TRIAL_VERSION = 3
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 100
QUICK_RUNS = 4
CHUNK_SIZE = 2

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


class Config(Settings):
    """The paper's scenario and our choices for what it leaves open.

    Paper values: 200 Hz, SL 140 dB, NL 73 dB, DI 12.5 dB, target depth = sensor depth; 100 frames 8 s
    apart; sigma_theta 0.5 deg, sigma_SNR 1 dB; observer with two course changes; target straight at
    initial bearing 160 deg; 100 runs per environment; SL mismatch -18..+18 dB.

    Our choices, with reasons:

    * **Environments**: the six tables of shared/data/korean_seas_environments.md (hand-built
      estimates, not climatology), sound speed by TEOS-10, fluid seabed half-spaces (East mud, Yellow
      muddy sand, South sand); TL from RAM (pyram) with Thorp absorption, on RAM's 45 m range grid.
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
    * **EM/MAP** (the ``[em_map]`` group, shared with ``sonartrack tma``): kappa 1 % (tma/em_map.py);
      latent range 3-50 km and the mean SNR from the TL *not* range-averaged (the command's defaults:
      0.5-60 km, 1 km average). Both adopted in the fidelity review, readings at least as faithful to the paper's
      text as the earlier 0.5 km and 1 km, under which both Table 2 claims failed at full size (study
      tma-sensitivity maps the readings):

      - **No TL averaging.** The paper computes the SNR from the sonar equation with RAM's TL and states
        no averaging: "Eq. (30)을 이용하여 산출한 각 해역의 각 수심에서의 거리별 SNR은 Fig. 5와 같다" (the
        SNR against range at each depth of each sea, computed with eq. (30) [SNR = SL - TL + DI - NL], is
        Fig. 5), TL being what "포물선 방정식법기반 RAM모델 ... 로 ... 전달손실을 산출하였다" (the RAM model
        computed). Its simulated truth and estimator share that TL ("음파전달모델을 이용한 TMA은 실제 환경의
        음파 전달과 음파전달모델 간의 차이에 의해서도 그 성능이 좌우 될 수 있다", left to sea trials), so the
        interference ripple is information in the paper's simulation as in ours. The 1 km average was ours
        (shared/data/korean_seas_environments.md's trial table); at 1 km a few South winter runs settle on a
        wrong range where the smoothed SNR is flat (7-16 km), giving 10.97 % there.
      - **Latent range from 3 km.** Eq. (19) integrates over a latent interval r_min..r_max the paper does
        not give; every target it places is far beyond 3 km ("표적 탐지거리가 10 km 미만인 남해에 비해 표적
        탐지거리가 20 km 또는 30 km 정도로 먼 서해와 동해"), and it explains the East Sea's tolerance of an
        under-assumed SL by the target sitting in a convergence zone: "이는 동해에서만 존재하는 음수렴 구역으로
        인해 다른 해역과 다르게 매 프레임 마다의 SNR 변화 양상이 특수하게 나타나기 때문이다. 따라서 동해의
        음수렴구역이 존재하는 탐지환경 하에서 음수렴 구역에 위치한 표적의 경우 예상되는 표적의 방사소음수준을
        낮게 설정하는 것이 더욱 정확한 TMA 결과를 얻을 수 있다." With r_min 0.5 km an under-assumed SL is
        matched best by the direct-path zone (< 3 km), which that explanation excludes; East then tolerated
        -3..+6 dB (towards over-assumed SL), against the paper's -18..+3.5.
    * **SL sweep** -18..+18 dB, 1.5 dB steps near 0 and 3-6 dB further out (the paper's Yellow Sea
      tolerances are +-1 dB), run in a random 30 % of the full runs (every quick run);
      the tolerated interval is the contiguous range of delta around 0 where the normalised range RMSE
      (start and end points pooled) stays below 10 %.
    """

    runs: int = setting(RUNS, "Monte Carlo runs (each: every environment)", unit="1", ge=1)
    environments: list[str] = setting(default_factory=lambda: list(ENVIRONMENTS), doc="shipped environments run")
    freq_hz: float = setting(200.0, "frequency of the tonal", unit="Hz", gt=0)
    sl_db: float = setting(140.0, "true source level", unit="dB")
    nl_db: float = setting(73.0, "noise level", unit="dB")
    di_db: float = setting(12.5, "directivity index", unit="dB")
    detection_threshold_db: float = setting(3.0, "SNR the target must keep on every frame of its placed track",
                                            unit="dB")
    sensor_depth_m: dict[str, float] = setting(default_factory=lambda: {"east": 200.0, "yellow": 38.0, "south": 50.0},
                                               doc="sensor (= target) depth per sea", unit="m")
    nominal_range_m: dict[str, float] = setting(
        default_factory=lambda: {"east": 29_000.0, "yellow": 25_000.0, "south": 8_000.0},
        doc="nominal initial target range per sea (the placement searches around it)", unit="m")
    n_frames: int = setting(100, "frames (bearing + SNR measurements)", unit="1", ge=5)
    frame_period_s: float = setting(8.0, "time between frames", unit="s", gt=0)
    sigma_bearing_deg: float = setting(0.5, "bearing noise standard deviation (truth and estimators)", unit="deg",
                                       gt=0)
    sigma_snr_db: float = setting(1.0, "SNR noise standard deviation (truth and EM/MAP)", unit="dB", gt=0)
    own_speed_kn: float = setting(6.0, "observer speed", unit="kn")
    own_course_deg: float = setting(90.0, "observer's initial course (clockwise from north)", unit="deg")
    own_turns: list[list[float]] = setting(default_factory=lambda: [[240.0, 260.0, -3.0], [520.0, 550.0, 3.0]],
                                           doc="observer turns: [start s, end s, rate deg/s; negative to port]")
    target_speed_kn: float = setting(6.0, "target speed", unit="kn")
    target_course_deg: float = setting(270.0, "target course (clockwise from north)", unit="deg")
    target_bearing_deg: float = setting(160.0, "target's initial bearing from the observer", unit="deg")
    em_map: EmMapSettings = setting(
        default_factory=lambda: EmMapSettings(r_min_m=3_000.0, r_max_m=50_000.0, tl_average_m=0.0),
        doc="the EM/MAP solver (shared with sonartrack tma; our latent interval and TL reading: Config doc)")
    sl_mismatch_db: list[float] = setting(
        default_factory=lambda: [-18.0, -12.0, -9.0, -6.0, -4.5, -3.0, -1.5, 0.0, 1.5, 3.0, 4.5, 6.0, 9.0, 12.0, 18.0],
        doc="assumed minus true SL of the mismatch sweep", unit="dB")
    sweep_fraction: float = setting(0.3, "share of runs that run the SL sweep", unit="1", gt=0, le=1)

    @classmethod
    def quick(cls) -> Config:
        """Demo preset: every environment, 4 runs, each with the SL sweep."""
        return cls(runs=QUICK_RUNS, sweep_fraction=1.0)

    def times_s(self) -> np.ndarray:
        return np.arange(self.n_frames) * self.frame_period_s

    def observer(self) -> ManeuveringTrack:
        from sonartrack.sim.platforms import ManeuveringTrack
        return ManeuveringTrack(0.0, 0.0, self.own_speed_kn * KNOT_MPS, np.deg2rad(self.own_course_deg),
                                tuple((a, b, np.deg2rad(r)) for a, b, r in self.own_turns))

    def sea(self, env: str) -> str:
        return env.split("-")[0]

    def target(self, r0_m: float) -> ManeuveringTrack:
        from sonartrack.sim.platforms import ManeuveringTrack
        b = np.deg2rad(self.target_bearing_deg)
        return ManeuveringTrack(r0_m * np.sin(b), r0_m * np.cos(b), self.target_speed_kn * KNOT_MPS,
                                np.deg2rad(self.target_course_deg))


@functools.lru_cache(maxsize=64)
def _snr_curve(env_name: str, depth_m: float, window_m: float, freq_hz: float, rmax_m: float, sl_db: float,
               di_db: float, nl_db: float) -> tuple[np.ndarray, np.ndarray]:
    """(ranges, mean SNR) at the sensor depth, TL averaged incoherently over ``window_m`` (cached on disk and
    in memory)."""
    from sonartrack.acoustics.environment import load_environment
    from sonartrack.acoustics.sonar_equation import passive_snr_db
    from sonartrack.acoustics.transmission_loss import smooth_tl
    from sonartrack.io.environment import cached_tl_field

    f = cached_tl_field(load_environment(env_name), freq_hz, depth_m, rmax_m=rmax_m)
    line = smooth_tl(f.ranges_m, f.at_depth(depth_m), window_m)
    return f.ranges_m, passive_snr_db(sl_db, line, di_db, nl_db)


def snr_curve(config: Config, env: str):
    """(ranges (m), true mean SNR (dB)) of ``env`` at its sensor depth."""
    return _snr_curve(env, float(config.sensor_depth_m[config.sea(env)]), config.em_map.tl_average_m, config.freq_hz,
                      1.05 * config.em_map.r_max_m, config.sl_db, config.di_db, config.nl_db)


def prepare(config: Config) -> None:
    """Compute (or load) the six TL fields once, before the workers start."""
    for env in config.environments:
        snr_curve(config, env)


def place_target(config: Config, env: str, ranges, snr) -> tuple[float, float]:
    """(initial range, min SNR over the track) of the target on the SNR curve ``(ranges, snr)`` of ``env``
    (Config doc): the range nearest the sea's nominal, in 250 m steps within +-40 %, whose SNR stays above the
    detection threshold on every frame, or failing that the one with the highest minimum SNR."""
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


@functools.lru_cache(maxsize=32)
def _placement(config_json: str, env: str) -> tuple[float, float]:
    config = Config.model_validate_json(config_json)
    return place_target(config, env, *snr_curve(config, env))


def placement(config: Config, env: str) -> tuple[float, float]:
    return _placement(config.model_dump_json(), env)


def _normalised_errors(x0, t, truth, norm) -> np.ndarray:
    """Start and end X, Y errors of the CV track X0 in % of the true range there (paper Table 1)."""
    end = x0[:2] + x0[2:] * (t[-1] - t[0])
    return 100.0 * (np.concatenate([x0[:2], end]) - truth) / norm


def _range_errors(x0, t, po, rng_true) -> np.ndarray:
    """|estimated - true| range at the start and at the end, in % of the true range."""
    end = x0[:2] + x0[2:] * (t[-1] - t[0])
    est = np.array([np.linalg.norm(x0[:2] - po[0]), np.linalg.norm(end - po[-1])])
    return 100.0 * np.abs(est - rng_true[[0, -1]]) / rng_true[[0, -1]]


def _ml_x0(config: Config, z, t, po, sb):
    """The bearings-only ML X0, or None when it failed (diverged towards infinite range)."""
    from sonartrack.tma.batch_ml import ml_bearings_only

    try:
        ml = ml_bearings_only(z, t, po, sb)
    except np.linalg.LinAlgError:
        return None
    if ml.converged and np.hypot(*(ml.x0[:2] - po[0])) < 5.0 * config.em_map.r_max_m:
        return ml.x0
    return None


@dataclass(frozen=True, slots=True)
class Observation:
    """One trial's data in one sea: bearings ``z`` (rad) and SNRs ``xi`` (dB) at the frame times, and the truth."""

    z: np.ndarray
    xi: np.ndarray
    truth: np.ndarray  # [x, y] at the first frame, then at the last (m)
    norm: np.ndarray  # the true range at those frames, per component (m)
    range_m: np.ndarray  # true range at every frame (m)


def observe(config: Config, ranges, snr, r0_m: float, t, po, noise) -> Observation:
    """Bearings and SNRs of the target placed at ``r0_m`` on the curve ``(ranges, snr)``; ``noise`` =
    (bearing noise (rad), SNR noise (dB)) per frame, drawn by the caller (so readings can share them)."""
    pt, _, _ = config.target(r0_m).state(t)
    d = pt - po
    range_m = np.linalg.norm(d, axis=1)
    return Observation(z=np.arctan2(d[:, 0], d[:, 1]) + noise[0], xi=np.interp(range_m, ranges, snr) + noise[1],
                       truth=np.array([pt[0, 0], pt[0, 1], pt[-1, 0], pt[-1, 1]]),
                       norm=np.array([range_m[0], range_m[0], range_m[-1], range_m[-1]]), range_m=range_m)


def em_map_x0(config: Config, obs: Observation, t, po, ranges, snr, ml_x0, r_min_m: float, r_max_m: float):
    """``x0(shift_db)``: the EM/MAP X0 with the SNR model shifted by ``shift_db`` (assumed SL = true + shift)."""
    from sonartrack.tma.em_map import make_problem, solve_em_map

    sb, em = np.deg2rad(config.sigma_bearing_deg), config.em_map

    def x0(shift_db):
        def snr_model(r):
            return np.interp(r, ranges, snr) + shift_db

        prob = make_problem(obs.z, obs.xi, t, po, sb, config.sigma_snr_db, snr_model, r_min_m, r_max_m, kappa=em.kappa)
        return solve_em_map(prob, t0_s=0.0, extra_starts=[ml_x0], max_iter=em.max_iter, covariance=False).x0

    return x0


def _environment_trial(config: Config, env: str, rng: np.random.Generator, t, po, sweep: bool) -> dict:
    """One draw of bearings and SNRs in ``env``; EM/MAP, ML and (if ``sweep``) the SL sweep."""
    ranges, snr = snr_curve(config, env)
    r0, _ = placement(config, env)
    sb = np.deg2rad(config.sigma_bearing_deg)
    noise = (rng.normal(0.0, sb, len(t)), rng.normal(0.0, config.sigma_snr_db, len(t)))
    obs = observe(config, ranges, snr, r0, t, po, noise)
    ml_x0 = _ml_x0(config, obs.z, t, po, sb)
    em_x0 = em_map_x0(config, obs, t, po, ranges, snr, ml_x0, config.em_map.r_min_m, config.em_map.r_max_m)
    sw = np.full((len(config.sl_mismatch_db), 2), np.nan)
    x0_true_sl = em_x0(0.0)
    out = {"ml": np.full(4, np.nan) if ml_x0 is None else _normalised_errors(ml_x0, t, obs.truth, obs.norm),
           "em": _normalised_errors(x0_true_sl, t, obs.truth, obs.norm), "sweep": sw}
    if sweep:
        for i, delta in enumerate(config.sl_mismatch_db):
            # no mismatch is the solve above (same data, same model): not solved twice
            sw[i] = _range_errors(x0_true_sl if delta == 0.0 else em_x0(delta), t, po, obs.range_m)
    return out


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One draw of bearings and SNRs per environment; EM/MAP, ML and (sometimes) the SL sweep."""
    t = config.times_s()
    po, _, _ = config.observer().state(t)
    sweep = bool(rng.random() < config.sweep_fraction)
    out: dict[str, np.ndarray] = {}
    for env in config.environments:
        for key, value in _environment_trial(config, env, rng, t, po, sweep).items():
            out[f"{env}_{key}"] = value
    return out


def _mean_over_runs(a) -> np.ndarray:
    """Mean over runs (axis 0) of the finite entries, NaN where no run has one (metrics/statistics.py rule)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # "mean of empty slice": NaN is the answer
        return np.nanmean(np.asarray(a, dtype=float), axis=0)


def tolerated_interval(deltas, curve) -> tuple[float | None, float | None]:
    """The contiguous range of SL mismatch around 0 where the normalised range RMSE stays below 10 %
    ((None, None) when it is not below 10 % at 0 itself)."""
    ok = np.asarray(curve) < RMSE_LIMIT_PCT
    i0 = int(np.argmin(np.abs(deltas)))
    if not ok[i0]:
        return None, None
    a = i0
    while a > 0 and ok[a - 1]:
        a -= 1
    b = i0
    while b < len(deltas) - 1 and ok[b + 1]:
        b += 1
    return float(deltas[a]), float(deltas[b])


def _environment_summary(trials: dict[str, np.ndarray], config: Config, env: str, deltas) -> dict:
    from sonartrack.metrics.statistics import rmse_over_runs
    em, ml, sw = trials[f"{env}_em"], trials[f"{env}_ml"], trials[f"{env}_sweep"]
    r0, s_min = placement(config, env)
    n_sweep = int(np.sum(np.all(np.isfinite(sw.reshape(sw.shape[0], len(deltas) * 2)), axis=1)))
    # start and end points pooled: one RMSE per mismatch over every run and both points
    curve = (rmse_over_runs(sw.transpose(1, 0, 2).reshape(len(deltas), -1), axis=1) if n_sweep
             else np.full(len(deltas), np.nan))
    ranges, snr = snr_curve(config, env)
    return {"initial_range_m": r0, "min_snr_on_track_db": s_min,
            "sensor_depth_m": config.sensor_depth_m[config.sea(env)],
            "em_mean_pct": _mean_over_runs(em).tolist(), "em_rmse_pct": rmse_over_runs(em).tolist(),
            "ml_mean_pct": _mean_over_runs(ml).tolist(), "ml_rmse_pct": rmse_over_runs(ml).tolist(),
            "ml_failed": int(np.sum(~np.all(np.isfinite(ml), axis=1))),
            "paper_rmse_pct": list(PAPER_TABLE1.get(env, (np.nan,) * 4)),
            "sweep_runs": n_sweep, "sweep_rmse_pct": curve.tolist(),
            "tolerated_db": list(tolerated_interval(deltas, curve)),
            "paper_tolerated_db": list(PAPER_TABLE2.get(env, (np.nan, np.nan))),
            "start_errors_em": em[:, :2].tolist(), "start_errors_ml": ml[:, :2].tolist(),
            "snr_ranges_km": (ranges[::4] / 1e3).tolist(), "snr_db": snr[::4].tolist()}


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    """Table 1 (mean and RMSE, EM/MAP and ML), Table 2 (tolerated SL mismatch), placements, curves."""
    deltas = np.asarray(config.sl_mismatch_db, dtype=float)
    envs = {env: _environment_summary(trials, config, env, deltas) for env in config.environments}
    return {"runs": len(next(iter(trials.values()))), "deltas_db": deltas.tolist(), "environments": envs}


def as_floats(x) -> np.ndarray:
    """A summary list as floats (JSON turns NaN, e.g. an RMSE over no successful run, into None)."""
    return np.array([np.nan if v is None else v for v in x], dtype=float)


def _accuracy_claims(summary: dict) -> list[Claim]:
    envs, runs = summary["environments"], summary["runs"]
    worst = {e: float(np.max(as_floats(v["em_rmse_pct"]))) for e, v in envs.items()}
    cmp = {e: (float(np.mean(as_floats(v["em_rmse_pct"]))), float(np.mean(as_floats(v["ml_rmse_pct"]))),
               v["ml_failed"]) for e, v in envs.items()}
    # ML that failed (diverged) in some runs is worse there whatever its RMSE over the rest
    ok = all(np.isfinite(a) and (f > 0 or not np.isfinite(b) or a <= 1.1 * b) for a, b, f in cmp.values())
    return [
        Claim(id="em_map_under_10pct", paper="Table 1: 0.26-6.22 %",
              text="EM/MAP normalised RMSE (start/end, X/Y) below 10 % in every environment with the true SL",
              ours="; ".join(f"{e} {w:.2f} %" for e, w in worst.items()), tolerance="every component < 10 %",
              holds=all(w < RMSE_LIMIT_PCT for w in worst.values())),
        Claim(id="em_map_not_worse_than_ml", paper="the SNR and the propagation model improve on bearings-only TMA",
              text="EM/MAP at least as accurate as bearings-only ML on the same data",
              ours="; ".join(f"{e} {a:.2f} vs {b:.2f} %" + (f" (ML diverged in {f}/{runs} runs)" if f else "")
                             for e, (a, b, f) in cmp.items()),
              tolerance="mean RMSE of EM/MAP <= 1.1 x ML's in each environment (Monte Carlo error of an RMSE over "
                        f"{runs} runs is ~{100 / np.sqrt(2 * runs):.0f} %)",
              holds=ok)]


def _east_vs_others(values: dict) -> tuple[list, list]:
    """The values of the East Sea cases and of the other cases."""
    return ([v for e, v in values.items() if e.startswith("east")],
            [v for e, v in values.items() if not e.startswith("east")])


def _interval_text(v) -> str:
    return "none" if v[0] is None else f"{v[0]:+g}..{v[1]:+g} dB"


def _mismatch_claims(summary: dict) -> list[Claim]:
    envs = summary["environments"]
    east, other = _east_vs_others({e: v["tolerated_db"][0] for e, v in envs.items()})
    # a sea not run, or a case with no tolerated interval at all, fails the claim
    holds_low = bool(east) and bool(other) and None not in east + other and max(east) < min(other)
    widths = {e: (None if v["tolerated_db"][0] is None else v["tolerated_db"][1] - v["tolerated_db"][0])
              for e, v in envs.items()}
    east_w, other_w = _east_vs_others(widths)
    holds_w = (bool(east_w) and bool(other_w) and None not in east_w
               and min(east_w) > max([w for w in other_w if w is not None], default=-1.0))
    return [
        Claim(id="east_tolerates_low_sl",
              paper="Table 2: East -18..+3.5/+2; Yellow -0.5..+1, -1..+0.5; South -5..+4, -3..+2.5",
              text="the tolerated SL-mismatch interval reaches further towards under-assumed SL in the East Sea than "
                   "in the Yellow and South Seas",
              ours="; ".join(f"{e} {_interval_text(v['tolerated_db'])}" for e, v in envs.items()),
              tolerance="the lower ends, on the sweep's grid (1.5 dB steps near 0)", holds=holds_low),
        Claim(id="east_tolerates_wider_mismatch",
              paper="Table 2: East 21.5 and 20 dB wide; Yellow 1.5 dB; South 9 and 5.5 dB",
              text="the East Sea (convergence zones) tolerates a wider SL mismatch than the Yellow and South Seas "
                   "(width of the tolerated interval)",
              ours="; ".join(f"{e} {'none' if w is None else f'{w:g} dB'}" for e, w in widths.items()),
              tolerance="every East case wider than every other case", holds=holds_w)]


def claims(summary: dict, config: Config) -> list[Claim]:
    """The paper's Tables 1 and 2 as checks on our numbers (tolerances in each claim)."""
    return [*_accuracy_claims(summary), *_mismatch_claims(summary)]
