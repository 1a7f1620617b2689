"""Sensitivity of study P1's failing claims to the choices the paper leaves open.

Im & Kim 1996 (paper P1) leave open the plane size, how the prior density of eq. 19 meets a cell
(printed: N(v; w_k, B_k) at the cell centre, "centre"; ours: N(v; w_k, B_k + R), "smoothed") and
whether the statistic sums over the N tracks kept after the last frame (eq. 20, ``final="kept"``, the
mftd study's default since the fidelity review) or over all N x M branches of that frame (``final="branches"``, its
earlier default). This study re-runs the mftd study's claims

* ``pd_falls_with_sigma_a``          Pd(sigma_a) falls step by step at N = 10 (Fig. 5),
* ``pd_falls_with_sigma_a_large_n``  the same at N = 100,
* ``pd_rises_with_n_and_saturates``  Pd rises with N and is within 1.96 SE of Pd(N_max) before N_max (Fig. 6)

under every reading plane x density x final, at Pfa = 1e-2 (or the lowest the H0 trials support),
with the mftd study's tests (``mftd.trend_verdict`` and ``mftd.saturation_verdict``: a step counts when
larger than 1.96 paired SE of the difference, from a bootstrap of the trials that re-estimates the
thresholds; the verdict with the unpaired binomial SE of metrics/roc.py ``rise_is_significant`` is given
beside it) and Clopper-Pearson intervals on each Pd.

Planes: a sigma_a = 4 m/s^2 target changes its range-rate by T sigma_a = 8 m/s (sd) per frame and must
stay on the plane for K frames, so every plane keeps at least the mftd study's 64 Doppler cells (11.3 m/s)
and the number of cells M is varied through the range extent: 2, 4, 16, 32 range x 64 Doppler cells
(M = 128, 256, 1024, 2048; on 2 x 64 the first pruning at N = 100 keeps 100 of 128 cells, so it is no
longer the bottleneck). One plane, 2 x 256 (M = 512, 45 m/s), widens the Doppler span instead: on 64
Doppler cells the sigma_a = 4 prediction (sd ~ 8 m/s a frame) is about as wide as the plane, so the
sigma_a = 4 prior is nearly flat there and the target is conditioned to stay on it. A plane of 32 Doppler
cells (5.6 m/s) would not hold a sigma_a = 4 target at all (rejection would keep only slow tracks, a
different target population). The short range extents (2 and 4 cells, 109 and 218 m) condition the
targets to small range-rates as well (a 5 m/s target crosses 50 m in the 5 frame intervals).

Common random numbers: one trial draws the Swerling-1 echo amplitudes once (shared by every plane),
per plane one noise stack and one target track per sigma_a (shared by every density / final reading
and every N on that plane). Every trial runs H0 and H1.

Also per plane and sigma_a: the rank of the true first cell among frame 1's cells (with N kept
tracks it survives the first pruning iff fewer than N noise cells beat it), the quantity behind the
failing claims on 16 x 64.

config -> run_trial -> summarize -> claims (none: the claims live in mftd; this study maps the
readings); pictures in report/figures/mftd_sensitivity.py.
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.detection.mftd import MftdDetector, MftdSettings
from sonartrack.models.range_doppler import CwPlaneSettings
from sonartrack.studies import mftd

STUDY_ID = "mftd-sensitivity"
TITLE = "P1 sensitivity: the sigma_a and N claims under plane size, prior density and final decision"
PAPER = "Im & Kim 1996, multiframe target detection for guidance sonar (paper 001, P1)"
TRIAL_VERSION = 1
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 5000
QUICK_RUNS = 200
CHUNK_SIZE = 50

#: the Pfa at which the claims compare curves (raised to the lowest Pfa the H0 trials support)
PFA_CLAIM = 1e-2
#: the claims mapped (ids as in studies/mftd.py)
CLAIM_IDS = ("pd_falls_with_sigma_a", "pd_falls_with_sigma_a_large_n", "pd_rises_with_n_and_saturates")


class Config(Settings):
    """The mftd study's defaults (plane cells, K, detector) and the grid of readings.

    Monte Carlo size: 5000 trials, each with H0 and H1 (the threshold at Pfa = 1e-2 rests on 50 H0
    exceedances; Pd to +-0.014 at 95 %). A trial runs 5 planes x 4 readings x 9 curves x (H0, H1) = 360
    detections, ~0.1 s on one core, so the full study takes ~4 min on 2 free workers (measured: 17 min with
    the two cores shared with other jobs). The quick preset (200 trials, one plane) runs in ~2 s.
    """

    runs: int = setting(RUNS, "Monte Carlo trials (each gives one H0 and one H1 statistic per reading and curve)",
                        unit="1", ge=1)
    planes: list[list[int]] = setting(default_factory=lambda: [[2, 64], [4, 64], [2, 256], [16, 64], [32, 64]],
                                      doc="planes as [range cells, Doppler cells]", unit="1")
    n_frames: int = setting(6, "frames K", unit="1", ge=1)
    plane: CwPlaneSettings = setting(default_factory=CwPlaneSettings, doc="cell geometry (paper sec. V)")
    detector: MftdSettings = setting(default_factory=lambda: mftd.Config().detector,
                                     doc="the default detector (as in mftd; the readings set density and final)")
    # the mftd study's families, declared once there
    sigma_a_family_mps2: list[float] = mftd.Config.model_fields["sigma_a_family_mps2"]
    n_family: list[int] = mftd.Config.model_fields["n_family"]
    large_n: int = mftd.Config.model_fields["large_n"]
    prior_densities: list[str] = setting(default_factory=lambda: ["smoothed", "centre"],
                                         doc="prior density readings ('smoothed', 'centre')", unit="1")
    finals: list[str] = setting(default_factory=lambda: ["branches", "kept"],
                                doc="final decision readings ('branches', 'kept' = eq. 20)", unit="1")
    bootstrap: int = setting(1000, "bootstrap resamples of the trials for the paired SE of a step (as in mftd)",
                             unit="1", ge=10)

    @classmethod
    def quick(cls) -> Config:
        """CI preset: the small plane only, two sigma_a, three N; every density / final reading."""
        return cls(runs=QUICK_RUNS, planes=[[4, 64]], sigma_a_family_mps2=[0.25, 4.0], n_family=[1, 10, 30], large_n=30)

    def readings(self) -> list[dict]:
        """Every plane x density x final: id, plane, density, final (the default reading first per plane)."""
        return [{"id": reading_id(p, d, f), "plane": list(p), "prior_density": d, "final": f}
                for p in self.planes for d in self.prior_densities for f in self.finals]

    def curves(self) -> list[tuple[float, int]]:
        """(sigma_a, N) run under each reading: both sigma_a families and the N family, no duplicates."""
        d = self.detector
        out = [(a, d.n_tracks) for a in self.sigma_a_family_mps2]
        out += [(a, self.large_n) for a in self.sigma_a_family_mps2]
        out += [(d.sigma_a_mps2, n) for n in self.n_family]
        return list(dict.fromkeys(out))


def reading_id(plane, density: str, final: str) -> str:
    return f"{plane[0]}x{plane[1]}_{density}_{final}"


def default_reading(config: Config) -> str:
    """Id of the reading that is the mftd study's default (its plane, and the detector's density and final)."""
    m = mftd.Config()
    return reading_id([m.n_range, m.n_doppler], config.detector.prior_density, config.detector.final)


def plane_id(plane) -> str:
    return f"{plane[0]}x{plane[1]}"


def curve_id(reading: str, sigma_a: float, n_tracks: int) -> str:
    return f"{reading}__a{sigma_a:g}_n{n_tracks}"


def _first_ranks(y_first: np.ndarray, tracks: dict, echo0: float, sigmas) -> np.ndarray:
    """Per sigma_a: how many noise cells of frame 1 beat the target's echo there."""
    out = np.empty(len(sigmas))
    for s, a in enumerate(sigmas):
        i, j = tracks[a].cells[0]
        y = y_first.copy()
        y[i, j] = echo0
        out[s] = float((y > y[i, j]).sum())
    return out


def _run_plane(config: Config, plane, echo: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Every reading and curve on one plane: shared noise stack and target tracks (common random numbers)."""
    from sonartrack.models.swerling import sample_cells
    from sonartrack.sim.range_doppler import simulate_target

    grid = config.plane.grid(*plane)
    K, d = config.n_frames, config.detector
    y0 = sample_cells(rng, (K, grid.n_range, grid.n_doppler))
    curves = config.curves()
    sigmas = sorted({a for a, _ in curves} | set(config.sigma_a_family_mps2))
    tracks = {a: simulate_target(rng, grid, d.period_s, a, K) for a in sigmas}
    amplitude = 2.0 * (1.0 + d.snr) * echo
    kk = np.arange(K)
    out = {f"first_rank_{plane_id(plane)}": _first_ranks(y0[0], tracks, amplitude[0], config.sigma_a_family_mps2)}
    for dens in config.prior_densities:
        for fin in config.finals:
            rid = reading_id(plane, dens, fin)
            for a, n in curves:
                det = MftdDetector(grid, d.model_copy(update={"sigma_a_mps2": a, "n_tracks": n,
                                                              "prior_density": dens, "final": fin}))
                y1 = y0.copy()
                cells = tracks[a].cells
                y1[kk, cells[:, 0], cells[:, 1]] = amplitude
                cid = curve_id(rid, a, n)
                out[f"h0_{cid}"] = np.asarray(det.detect(y0, checked=True).statistic)
                out[f"h1_{cid}"] = np.asarray(det.detect(y1, checked=True).statistic)
    return out


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One trial: unit Swerling-1 echo draws shared by every plane, then each plane's readings."""
    echo = rng.exponential(1.0, config.n_frames)
    out: dict[str, np.ndarray] = {}
    for plane in config.planes:
        out.update(_run_plane(config, plane, echo, rng))
    return out


# -- summary -------------------------------------------------------------------------------------
def claim_pfa(n_h0: int) -> float:
    """PFA_CLAIM, or the lowest Pfa ``n_h0`` target-absent trials support if that is higher."""
    from sonartrack.metrics.roc import min_pfa

    return max(PFA_CLAIM, min_pfa(n_h0))


def _point(trials, cid: str, pfa: float) -> dict:
    from sonartrack.metrics.roc import roc_curve
    c = roc_curve(trials[f"h0_{cid}"], trials[f"h1_{cid}"], [pfa])
    return {"pd": float(c.pd[0]), "pd_low": float(c.pd_low[0]), "pd_high": float(c.pd_high[0]),
            "pfa_achieved": float(c.pfa_achieved[0]), "n_h1": int(c.n_h1)}


def _reading_cell(trials, config: Config, reading: dict, pfa: float, kept: dict) -> dict:
    """One reading: Pd points of both sigma_a families and the N family, and the three claims' verdicts."""
    rid, d = reading["id"], config.detector
    fam = {"sigma": [(a, d.n_tracks) for a in config.sigma_a_family_mps2],
           "sigma_large_n": [(a, config.large_n) for a in config.sigma_a_family_mps2],
           "n": [(d.sigma_a_mps2, n) for n in config.n_family]}
    points = {k: [_point(trials, curve_id(rid, a, n), pfa) for a, n in v] for k, v in fam.items()}
    pd = {k: [p["pd"] for p in v] for k, v in points.items()}
    names = {k: [curve_id(rid, a, n) for a, n in v] for k, v in fam.items()}
    mini = _mftd_summary(trials, points, names, pfa, config)
    sig = {}
    for k in ("sigma", "sigma_large_n"):
        ok, against, unpaired = mftd.trend_verdict(mini, names[k], pfa, increasing=False)
        sig[k] = {"holds": ok, "against": against, "unpaired_holds": unpaired,
                  "paired_se": [mftd._step_se(mini, a, b) for a, b in zip(names[k][:-1], names[k][1:], strict=True)]}
    ok_n, sat = mftd.saturation_verdict(mini, names["n"], config.n_family, pfa, 0)
    ok_nu, sat_u = mftd.saturation_verdict(mini, names["n"], config.n_family, pfa, 1)
    pk = kept[plane_id(reading["plane"])]
    return {**reading, "points": points,
            "claims": {"pd_falls_with_sigma_a": {**sig["sigma"], "pd": pd["sigma"],
                                                 "first_cell_kept": pk[str(d.n_tracks)]},
                       "pd_falls_with_sigma_a_large_n": {**sig["sigma_large_n"], "pd": pd["sigma_large_n"],
                                                         "first_cell_kept": pk[str(config.large_n)]},
                       "pd_rises_with_n_and_saturates": {"holds": ok_n, "saturated_from_n": sat, "pd": pd["n"],
                                                         "unpaired_holds": ok_nu, "unpaired_saturated_from_n": sat_u,
                                                         "first_cell_kept": [pk[str(n)][_sigma_index(config)]
                                                                             for n in config.n_family]}}}


def _mftd_summary(trials, points: dict, names: dict, pfa: float, config: Config) -> dict:
    """The part of an mftd summary its verdicts read: the curves' Pd at ``pfa`` and the bootstrap covariance."""
    curves = {nm: {"pfa": [pfa], "pd": [p["pd"]], "n_h1": p["n_h1"]}
              for k in names for nm, p in zip(names[k], points[k], strict=True)}
    order = list(curves)
    boot = mftd.pd_bootstrap(trials, order, pfa, config.bootstrap)
    return {"curves": curves, "steps": {"pfa": pfa, "names": order,
                                        "covariance": np.atleast_2d(np.cov(boot, rowvar=False)).tolist()}}


def _sigma_index(config: Config) -> int:
    a = config.detector.sigma_a_mps2
    return config.sigma_a_family_mps2.index(a) if a in config.sigma_a_family_mps2 else 0


def first_cell_kept(trials, config: Config) -> dict:
    """plane -> N -> per sigma_a of the family: share of trials whose true first cell survives the first
    pruning (rank < N)."""
    ns = sorted({*config.n_family, config.detector.n_tracks, config.large_n})
    out = {}
    for p in config.planes:
        rank = np.asarray(trials[f"first_rank_{plane_id(p)}"], dtype=float)
        out[plane_id(p)] = {str(n): np.mean(rank < n, axis=0).tolist() for n in ns}
    return out


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    """Per reading the Pd points (95 % Clopper-Pearson) and claim verdicts; the table; first-cell survival."""
    runs = int(np.asarray(trials[next(iter(trials))]).shape[0])
    pfa = claim_pfa(runs)
    kept = first_cell_kept(trials, config)
    cells = [_reading_cell(trials, config, r, pfa, kept) for r in config.readings()]
    ids = {c["id"] for c in cells}
    table = [{"reading": c["id"], "claim": cid, "holds": c["claims"][cid]["holds"], "pd": c["claims"][cid]["pd"]}
             for c in cells for cid in CLAIM_IDS]
    summary = {"runs": runs, "pfa": pfa, "sigma_a_family_mps2": list(config.sigma_a_family_mps2),
               "n_family": list(config.n_family), "n_default": config.detector.n_tracks, "large_n": config.large_n,
               "planes": {plane_id(p): {"n_cells": p[0] * p[1]} for p in config.planes},
               "first_cell_kept": kept, "readings": cells, "table": table,
               "default_reading": default_reading(config) if default_reading(config) in ids else None}
    summary["findings"] = findings(summary)
    return summary


def _step_counts(summary: dict, cid: str) -> list[int]:
    """Per step of a sigma_a family: in how many readings it is a significant fall."""
    from sonartrack.metrics.roc import rise_is_significant

    n_steps = len(summary["sigma_a_family_mps2"]) - 1
    out = [0] * n_steps
    for c in summary["readings"]:
        pd, n = c["claims"][cid]["pd"], c["points"]["sigma"][0]["n_h1"]
        for i in range(n_steps):
            out[i] += rise_is_significant(pd[i + 1], pd[i], n)
    return out


def findings(summary: dict) -> list[str]:
    """Per claim: the readings under which it holds, which steps fail, and the first-pruning survival
    (printed under the table figure)."""
    out, a = [], summary["sigma_a_family_mps2"]
    for cid in CLAIM_IDS:
        held = [c["id"] for c in summary["readings"] if c["claims"][cid]["holds"]]
        unpaired = [c["id"] for c in summary["readings"] if c["claims"][cid]["unpaired_holds"]]
        line = f"{cid}: holds in {len(held)} of {len(summary['readings'])} readings" + (
            f" ({', '.join(held)})" if held else "")
        if cid != "pd_rises_with_n_and_saturates":
            line += "; significant falls per step (unpaired SE) " + ", ".join(
                f"{a[i]:g}->{a[i + 1]:g}: {k}" for i, k in enumerate(_step_counts(summary, cid)))
        line += "; with the unpaired SE it holds in " + (", ".join(unpaired) or "none")
        out.append(line)
    n0 = str(summary["n_default"])
    out.append("true first cell kept by the first pruning (sigma_a-blind: the first frame has a flat prior), "
               + "; ".join(f"{p}: N={n0} {v[n0][0]:.0%}, N={summary['large_n']} {v[str(summary['large_n'])][0]:.0%}"
                           for p, v in summary["first_cell_kept"].items()))
    return out


def claims(summary: dict, config: Config) -> list:
    """None: the claims under test are mftd's; this study maps them over the readings."""
    return []
