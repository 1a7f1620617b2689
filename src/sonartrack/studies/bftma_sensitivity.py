"""Sensitivity of study P2's claim ``mgekf-divergence-end`` to the choices the paper leaves open.

Yoo & Song (paper P2) give the model only; the divergence definition, the process-noise values and the
initialisation are our choices (studies/bftma_imm.py). This study re-runs bftma-imm's scenario under
other readings of those choices and evaluates the claim "MGEKF runs diverge no more often than EKF runs,
summed over the matched filter pairs (single filter per q of the IMM bank, and the IMM; with and without
frequency)" under each. Two kinds of reading:

* **filter / scenario readings** (a re-run each, on the *same* measurements and initial draws -- common
  random numbers: every reading starts from a copy of the trial's random generator, so the default
  reading is bftma-imm's trial itself): the IMM's q bank (one single filter per q, so a bank fixes
  the pairs), the spread of the initial range guess and of f0, a zero-mean velocity prior instead of
  one drawn around the truth, the frequency noise;
* **divergence definitions** (evaluated on every reading): relative position-error threshold
  (e > thr x true range) at the end of the run, at fixed times after the target's turn, at *any*
  record after the turn, or over the *whole* last window (persistent); and consistency-based: the
  position NEES e^T P_pos^-1 e above the chi-square(2) quantile (the filter's covariance does not admit
  its error), alone or together with the 25 % error test.

Per reading and definition: the counts n_MGEKF and n_EKF over runs x pairs with Clopper-Pearson 95 %
intervals (metrics/roc.py; the pairs of one run are not independent, so these are indicative), and
the paired per-run difference D_i = sum_pairs MGEKF_i - sum_pairs EKF_i with a 95 % normal interval
for n_MGEKF - n_EKF = N mean(D) (the right interval for the claim). Also per single q and per IMM
bank, the default-reading counts, and for the explanation of the q = 1e-5 result the position error
and NEES against time (median over runs).

config -> run_trial -> summarize -> claims (none: the claim lives in bftma-imm); pictures in
report/figures/bftma_sensitivity.py.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from sonartrack.core.settings import setting
from sonartrack.studies import bftma_imm as base

STUDY_ID = "bftma-sensitivity"
TITLE = "P2 sensitivity: MGEKF vs EKF divergence under the open choices"
PAPER = "Yoo & Song, passive-sonar TMA with the IMM (paper 002, P2)"
TRIAL_VERSION = 1
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 400
QUICK_RUNS = 4
CHUNK_SIZE = 20

DEFAULT_READING = "default"
DEFAULT_DEFINITION = "end_25"


class Config(base.Config):
    """bftma-imm's scenario (every field of its Config, same defaults) plus the grid of readings."""

    runs: int = setting(RUNS, "Monte Carlo runs", unit="1", ge=1)
    extra_q_banks: list[list[float]] = setting(
        default_factory=lambda: [[1e-4, 1e-2, 1.0], [1e-3, 1e-2, 1e-1], [1e-5, 1e-1]],
        doc="IMM q banks besides imm.q_values (each also sets its single-q pairs)", unit="m^2/s^3")
    range_sd_variants_m: list[float] = setting(
        default_factory=lambda: [1000.0, 5000.0], doc="other spreads of the initial range guess", unit="m")
    zero_mean_velocity_sd_variants_mps: list[float] = setting(
        default_factory=lambda: [5.0], doc="zero-mean target-velocity priors (sd per axis) instead of a draw "
                                           "around the truth", unit="m/s")
    f0_sd_variants_hz: list[float] = setting(
        default_factory=lambda: [0.3, 3.0], doc="other standard deviations of the initial f0", unit="Hz")
    sigma_freq_variants_hz: list[float] = setting(
        default_factory=lambda: [0.05], doc="other frequency noise standard deviations (truth and filters)",
        unit="Hz")
    divergence_thresholds: list[float] = setting(
        default_factory=lambda: [0.1, 0.25, 0.5], doc="relative position-error thresholds evaluated", unit="1")
    checkpoint_times_s: list[float] = setting(
        default_factory=lambda: [1500.0, 1800.0, 2100.0], doc="checkpoints after the turn besides the end",
        unit="s")
    persist_window_s: float = setting(300.0, "persistent divergence: error above the threshold over this whole "
                                             "final window", unit="s", gt=0)
    nees_quantile: float = setting(0.999, "consistency test: position NEES above this chi-square(2) quantile",
                                   unit="1", gt=0, lt=1)

    @classmethod
    def quick(cls) -> Config:
        """CI preset: every reading and definition, 4 runs."""
        return cls(runs=QUICK_RUNS)

    def banks(self) -> list[tuple[float, ...]]:
        """The IMM q banks: imm.q_values first."""
        return [tuple(self.imm.q_values), *(tuple(b) for b in self.extra_q_banks)]

    def checkpoints_s(self) -> list[float]:
        """Checkpoint times: the start of the target's turn, the given ones, the end of the run."""
        return [self.target_turn_start_s, *self.checkpoint_times_s, float(self.times_s()[-1])]

    @property
    def chi2_threshold(self) -> float:
        """The chi-square(2) quantile: -2 ln(1 - p)."""
        return float(-2.0 * np.log1p(-self.nees_quantile))


@dataclass(frozen=True, slots=True)
class Variant:
    """A filter / scenario reading that needs its own run: Config overrides, an optional zero-mean velocity
    prior (sd m/s), and whether it runs every bank (the default) or imm.q_values only."""

    id: str
    label: str
    overrides: tuple[tuple[str, float], ...] = ()
    zero_mean_velocity_sd: float | None = None
    all_banks: bool = False


def variants(config: Config) -> list[Variant]:
    out = [Variant(DEFAULT_READING, "default (bftma-imm)", all_banks=True)]
    out += [Variant(f"range_sd_{v:g}", f"range guess sd {v:g} m", (("init_sigma_range_m", v),))
            for v in config.range_sd_variants_m]
    out += [Variant(f"velocity_prior_{v:g}", f"velocity prior 0 ± {v:g} m/s", zero_mean_velocity_sd=v)
            for v in config.zero_mean_velocity_sd_variants_mps]
    out += [Variant(f"f0_sd_{v:g}", f"initial f0 sd {v:g} Hz", (("init_sigma_f0_hz", v),))
            for v in config.f0_sd_variants_hz]
    out += [Variant(f"sigma_f_{v:g}", f"sigma_f {v:g} Hz", (("sigma_freq_hz", v),))
            for v in config.sigma_freq_variants_hz]
    return out


def _qkey(q: float) -> str:
    return f"q{q:g}"


def variant_cases(config: Config, variant: Variant) -> dict[str, tuple[str, str, tuple[float, ...]]]:
    """Case id -> (measurements, filter, q per mode): a single filter per q, an IMM per bank."""
    banks = config.banks() if variant.all_banks else config.banks()[:1]
    qs = sorted({q for b in banks for q in b})
    out = {}
    for meas in base.MEASUREMENTS:
        for filt in base.FILTERS:
            out.update({f"{meas}_{filt}_{_qkey(q)}": (meas, filt, (q,)) for q in qs})
            out.update({f"{meas}_{filt}_imm{i}": (meas, filt, b) for i, b in enumerate(banks)})
    return out


def readings(config: Config) -> list[dict]:
    """Columns of the grid: (reading id, label, variant id, bank index)."""
    bank_label = ", ".join(f"{q:g}" for q in config.banks()[0])
    out = [{"id": DEFAULT_READING, "label": f"default: q bank {bank_label}", "variant": DEFAULT_READING, "bank": 0}]
    for i, b in enumerate(config.banks()[1:], start=1):
        out.append({"id": f"bank{i}", "label": "q bank " + ", ".join(f"{q:g}" for q in b), "variant": DEFAULT_READING,
                    "bank": i})
    out += [{"id": v.id, "label": v.label, "variant": v.id, "bank": 0} for v in variants(config)[1:]]
    return out


def definitions(config: Config) -> list[dict]:
    """Rows of the grid: where (checkpoint index, 'any' or 'persist'), threshold (None: none), nees test."""
    cps = config.checkpoints_s()
    out = []
    for thr in config.divergence_thresholds:
        pct = f"{thr:.0%}"
        out.append({"id": f"end_{thr * 100:g}", "label": f"end, e > {pct}", "where": len(cps) - 1, "thr": thr,
                    "nees": False})
        out += [{"id": f"t{c:g}_{thr * 100:g}", "label": f"t = {c:g} s, e > {pct}", "where": j + 1, "thr": thr,
                 "nees": False} for j, c in enumerate(config.checkpoint_times_s)]
        out.append({"id": f"any_{thr * 100:g}", "label": f"any time after turn, e > {pct}", "where": "any",
                    "thr": thr, "nees": False})
        out.append({"id": f"persist_{thr * 100:g}", "label": f"whole last {config.persist_window_s:g} s, e > {pct}",
                    "where": "persist", "thr": thr, "nees": False})
    chi = f"NEES > {config.chi2_threshold:.1f}"
    out.append({"id": "end_nees", "label": f"end, {chi}", "where": len(cps) - 1, "thr": None, "nees": True})
    out.append({"id": "end_25_nees", "label": f"end, e > 25% and {chi}", "where": len(cps) - 1, "thr": 0.25,
                "nees": True})
    return out


# ---------------------------------------------------------------------------------------------
# one trial
# ---------------------------------------------------------------------------------------------
def _variant_config(config: Config, variant: Variant) -> Config:
    return config.model_copy(update=dict(variant.overrides)) if variant.overrides else config


def _zero_mean_velocity(config: Config, init: dict, zb, zf, vo, sd: float) -> dict:
    """The initial estimates with the drawn range kept but a zero-mean target-velocity prior of sd ``sd``."""
    from sonartrack.tma.sequential_bf import initial_estimate

    out = {}
    for meas, (x0, _) in init.items():
        out[meas] = initial_estimate(float(zb[0]), float(zf[0]) if meas == "bf" else None, vo[0],
                                     range_m=float(np.hypot(*x0[:2])), sigma_range_m=config.init_sigma_range_m,
                                     sigma_bearing_rad=float(np.deg2rad(config.sigma_bearing_deg)),
                                     target_velocity_mps=(0.0, 0.0), sigma_target_velocity_mps=sd,
                                     sigma_f0_hz=config.init_sigma_f0_hz, c=config.sound_speed_mps)
    return out


def _position_nees(x, P, dp) -> np.ndarray:
    """e^T P_pos^-1 e for position errors dp (n, 2) and covariances P (n, >=2, >=2), closed-form 2 x 2 inverse."""
    a, b, d = P[:, 0, 0], P[:, 0, 1], P[:, 1, 1]
    det = a * d - b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        return (d * dp[:, 0] ** 2 - 2 * b * dp[:, 0] * dp[:, 1] + a * dp[:, 1] ** 2) / det


def _case_stats(config: Config, rel_err, nees, rec, k_cp) -> tuple[np.ndarray, np.ndarray]:
    """Relative error at the checkpoints, its maximum after the turn and minimum over the final window (on the
    record grid); NEES at the checkpoints. NaN (a failed filter) propagates: it counts as diverged."""
    t = config.times_s()
    after = rec[rec >= k_cp[0]]
    last = rec[t[rec] >= t[-1] - config.persist_window_s - 1e-9]
    stats = np.concatenate([rel_err[k_cp], [np.max(rel_err[after]), np.min(rel_err[last])]])
    return stats, nees[k_cp]


def _run_variant(config: Config, variant: Variant, rng: np.random.Generator, series: bool) -> dict:
    from sonartrack.metrics.tma_errors import tma_errors
    from sonartrack.models.relative_motion import observer_inputs
    from sonartrack.tma.imm_mgekf import run_imm_bf
    cfg = _variant_config(config, variant)
    t, po, vo, pt, vt, zb, zf = base.simulate(cfg, rng)
    init = base.initial_estimates(cfg, rng, zb, zf, po, vo, pt, vt)
    if variant.zero_mean_velocity_sd is not None:
        init = _zero_mean_velocity(cfg, init, zb, zf, vo, variant.zero_mean_velocity_sd)
    u = observer_inputs(t, po, vo)
    rec = cfg.record_index()
    k_cp = np.searchsorted(t, np.asarray(cfg.checkpoints_s()) - 1e-9)
    true_range = np.hypot(*(pt - po).T)
    own, truth = np.concatenate([po, vo], axis=-1), np.concatenate([pt, vt], axis=-1)
    out: dict[str, np.ndarray] = {}
    for case, (meas, filt, qs) in variant_cases(cfg, variant).items():
        x0, P0 = init[meas]
        x, P, _, _ = run_imm_bf(t, zb, zf if meas == "bf" else None, u, x0, P0, base.case_model(cfg, filt, qs))
        rel_err = tma_errors(x[:, :4] + own, truth)["position_m"] / true_range
        nees = _position_nees(x, P, x[:, :2] + po - pt)
        out[f"{variant.id}__{case}__rel"], out[f"{variant.id}__{case}__nees"] = _case_stats(cfg, rel_err, nees, rec,
                                                                                            k_cp)
        if series and len(qs) == 1 and qs[0] in cfg.imm.q_values:
            out[f"series__{case}__rel"], out[f"series__{case}__nees"] = rel_err[rec], nees[rec]
    return out


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One Monte Carlo run: every reading from a copy of the same generator (common random numbers; the
    default reading draws exactly what a bftma-imm trial with this generator draws)."""
    out: dict[str, np.ndarray] = {}
    for variant in variants(config):
        out.update(_run_variant(config, variant, copy.deepcopy(rng), series=variant.id == DEFAULT_READING))
    return out


# ---------------------------------------------------------------------------------------------
# summary
# ---------------------------------------------------------------------------------------------
def diverged_flags(trials: dict, prefix: str, definition: dict, config: Config) -> np.ndarray:
    """Per-run divergence of one case (``prefix`` = '<variant>__<case>') under one definition (bool, runs)."""
    rel = np.asarray(trials[f"{prefix}__rel"], float)
    nees = np.asarray(trials[f"{prefix}__nees"], float)
    n_cp, where, thr = nees.shape[1], definition["where"], definition["thr"]
    if where in ("any", "persist"):
        return ~(rel[:, n_cp if where == "any" else n_cp + 1] <= thr)
    flag = np.ones(rel.shape[0], bool)
    if thr is not None:
        flag &= ~(rel[:, where] <= thr)
    if definition["nees"]:
        flag &= ~(nees[:, where] <= config.chi2_threshold)
    return flag


def reading_pairs(config: Config, reading: dict) -> list[tuple[str, str]]:
    """The matched (MGEKF, EKF) case prefixes of a reading: a single filter per q of its bank, and its IMM."""
    names = [_qkey(q) for q in config.banks()[reading["bank"]]] + [f"imm{reading['bank']}"]
    return [(f"{reading['variant']}__{m}_mgekf_{n}", f"{reading['variant']}__{m}_ekf_{n}")
            for m in base.MEASUREMENTS for n in names]


def _cell(trials: dict, config: Config, reading: dict, definition: dict) -> dict:
    """Counts, Clopper-Pearson intervals and the paired difference of one reading under one definition."""
    from sonartrack.metrics.roc import binomial_interval
    from sonartrack.metrics.statistics import paired_difference

    pairs = reading_pairs(config, reading)
    mg = sum(diverged_flags(trials, a, definition, config).astype(int) for a, _ in pairs)
    ekf = sum(diverged_flags(trials, b, definition, config).astype(int) for _, b in pairs)
    runs, total = len(mg), len(mg) * len(pairs)
    m, se = paired_difference(mg, ekf)
    (mg_lo, ekf_lo), (mg_hi, ekf_hi) = binomial_interval([mg.sum(), ekf.sum()], total)
    return {"n_mgekf": int(mg.sum()), "n_ekf": int(ekf.sum()), "total": total,
            "mgekf_ci": [float(mg_lo) * total, float(mg_hi) * total],
            "ekf_ci": [float(ekf_lo) * total, float(ekf_hi) * total],
            "diff": int(mg.sum() - ekf.sum()), "diff_ci": [runs * (m - 1.96 * se), runs * (m + 1.96 * se)],
            "holds": bool(mg.sum() <= ekf.sum())}


def _per_pair(trials: dict, config: Config, defs: dict) -> dict:
    """Default reading, every single q and IMM bank: [n_MGEKF, n_EKF] per measurement set and definition."""
    cases = variant_cases(config, variants(config)[0])
    names = sorted({c.split("_", 2)[2] for c in cases},
                   key=lambda n: (1, int(n[3:])) if n.startswith("imm") else (0, float(n[1:])))
    out = {}
    for did in ("end_25", "any_25", "persist_25", "end_nees"):
        d = defs[did]
        out[did] = {n: {m: [int(diverged_flags(trials, f"{DEFAULT_READING}__{m}_{f}_{n}", d, config).sum())
                            for f in ("mgekf", "ekf")] for m in base.MEASUREMENTS} for n in names}
    banks = {f"imm{i}": "IMM " + ", ".join(f"{q:g}" for q in b) for i, b in enumerate(config.banks())}
    return {"names": names, "labels": {n: banks.get(n, f"q = {n[1:]}") for n in names}, "counts": out}


def _series(trials: dict, config: Config) -> dict:
    """Position error / range and position NEES against time, default reading (median and quartiles)."""
    out = {}
    for key in sorted(k for k in trials if k.startswith("series__") and k.endswith("__rel")):
        case = key.split("__")[1]
        rel = np.asarray(trials[key], float)
        nees = np.asarray(trials[f"series__{case}__nees"], float)
        with np.errstate(invalid="ignore"):
            q25, q50, q75 = np.nanpercentile(rel, [25, 50, 75], axis=0)
            out[case] = {"rel_q25": q25.tolist(), "rel_median": q50.tolist(), "rel_q75": q75.tolist(),
                         "nees_median": np.nanmedian(nees, axis=0).tolist(),
                         "frac_inconsistent": np.mean(~(nees <= config.chi2_threshold), axis=0).tolist()}
    return out


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    """The grid (reading x definition), the one-factor-at-a-time table, per-pair counts, error/NEES series."""
    defs = {d["id"]: d for d in definitions(config)}
    reads = readings(config)
    cells = {r["id"]: {did: _cell(trials, config, r, d) for did, d in defs.items()} for r in reads}
    table = [{"reading": r["label"], "definition": defs[DEFAULT_DEFINITION]["label"],
              **cells[r["id"]][DEFAULT_DEFINITION]} for r in reads]
    table += [{"reading": reads[0]["label"], "definition": d["label"], **cells[DEFAULT_READING][did]}
              for did, d in defs.items() if did != DEFAULT_DEFINITION]
    runs = int(np.asarray(trials[next(iter(trials))]).shape[0])
    summary = {"runs": runs, "chi2_threshold": config.chi2_threshold,
            "readings": [{"id": r["id"], "label": r["label"], "pairs": len(reading_pairs(config, r))} for r in reads],
            "definitions": [{"id": d["id"], "label": d["label"]} for d in defs.values()],
            "default_reading": DEFAULT_READING, "default_definition": DEFAULT_DEFINITION,
            "cells": cells, "table": table, "per_pair": _per_pair(trials, config, defs),
            "time_s": config.times_s()[config.record_index()].tolist(), "turn_time_s": config.target_turn_start_s,
            "series": _series(trials, config)}
    summary["findings"] = findings(summary)
    return summary


def findings(summary: dict) -> list[str]:
    """The study's conclusions as sentences computed from its numbers (printed under the table figure)."""
    cells, reads, defs = summary["cells"], summary["readings"], summary["definitions"]
    held = [(r["label"], d["label"]) for r in reads for d in defs if cells[r["id"]][d["id"]]["holds"]]
    pp, runs = summary["per_pair"], summary["runs"]
    out = [f"holds in {len(held)} of {len(reads) * len(defs)} cells; under the default definition in "
           f"{sum(cells[r['id']][summary['default_definition']]['holds'] for r in reads)} of {len(reads)} readings; "
           "definitions that hold on the default reading: "
           + ("; ".join(d for r, d in held if r == reads[0]["label"]) or "none")]
    worse, better, lag = [], [], []
    for n in pp["names"]:
        for m in ("bf", "b"):
            mg, ek = pp["counts"]["end_25"][n][m]
            tag = f"{pp['labels'][n]} ({m}) {mg}/{ek}"
            (worse if mg > ek else better if mg < ek else []).append(tag)
            ek_any = pp["counts"]["any_25"][n][m][1]
            if ek_any - ek >= runs // 4:
                lag.append(f"{pp['labels'][n]} ({m}) {ek_any} vs {ek}")
    out.append("end, e > 25 %, MGEKF/EKF diverged: MGEKF worse in " + ", ".join(worse) + "; better in "
               + ", ".join(better))
    out.append("EKF above 25 % at some record after the turn vs at the end (transients that recover): "
               + (", ".join(lag) or "none"))
    return out


def claims(summary: dict, config: Config) -> list:
    """None: the claim under test is bftma-imm's ``mgekf-divergence-end``; this study maps its readings."""
    return []
