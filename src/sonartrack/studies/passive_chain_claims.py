"""The passive-chain study's summary and claims: each check's share or rate with its 95 % interval, and its verdict.

The checks and their requirements are studies/passive_chain.py's module doc; the requirements are declared here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sonartrack.experiment.claims import Claim
from sonartrack.studies.passive_chain_measures import (
    DIVERGED_RANGE_FACTOR,
    OUTCOMES,
    ship_names,
)
from sonartrack.studies.passive_chain_measures import (
    DIVERGED_SPEED_MPS as DIVERGED_SPEED_MPS,
)
from sonartrack.studies.passive_chain_measures import (
    direction_separation as direction_separation,
)
from sonartrack.studies.passive_chain_measures import (
    identity_through as identity_through,
)
from sonartrack.studies.passive_chain_measures import (
    running_median as running_median,
)

if TYPE_CHECKING:  # the study module imports this one
    from sonartrack.studies.passive_chain import Config

#: the checks' requirements (studies/passive_chain.py module doc)
HOLD_REQUIRED = 0.9
IDENTITY_REQUIRED = 0.8
AXIS_REQUIRED = 0.9
AXIS_BEAMWIDTHS = 2.0
CRB_FACTOR = 2.0
CRB_SHARE = 0.9
MAX_SDS = 5.0
FALSE_PER_HOUR = 1.0


def _mean_interval(x) -> list[float]:
    """[mean, low, high]: the mean over the finite values and its 95 % normal interval."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if not len(x):
        return [float("nan")] * 3
    se = float(np.std(x, ddof=1) / np.sqrt(len(x))) if len(x) > 1 else float("nan")
    m = float(np.mean(x))
    return [m, m - 1.96 * se, m + 1.96 * se]


def _share(ok) -> dict:
    """{k, n, share, low, high}: successes among the finite values (1/0) with the 95 % Clopper-Pearson interval."""
    from sonartrack.metrics.roc import binomial_share

    return binomial_share(ok)


def _poisson_upper(k: int, conf: float = 0.95) -> float:
    from scipy.stats import chi2

    return float(chi2.ppf(conf, 2 * (k + 1)) / 2.0)


def _nees_summary(nees) -> dict:
    """ANEES of n final 4-state solutions and its chi-square 95 % interval chi2(4n) / n, and the share of single
    NEES inside chi2(4)'s 95 % interval."""
    from scipy.stats import chi2

    x = np.asarray(nees, float)
    x = x[np.isfinite(x)]
    n = len(x)
    if not n:
        return {"n": 0, "anees": float("nan"), "low": float("nan"), "high": float("nan"), "inside": float("nan")}
    lo1, hi1 = chi2.ppf([0.025, 0.975], 4)
    return {"n": n, "anees": float(np.mean(x)), "low": float(chi2.ppf(0.025, 4 * n) / n),
            "high": float(chi2.ppf(0.975, 4 * n) / n), "inside": float(np.mean((x >= lo1) & (x <= hi1)))}


def _solution_summary(tr: dict[str, np.ndarray]) -> dict:
    """The TMA solutions' shares, counts and NEES (:func:`summarize`)."""
    det = tr["determined"] == 1.0
    within = np.where(det, (tr["pos_err_m"] <= CRB_FACTOR * tr["crb_sd_m"]).astype(float), np.nan)
    corr = tr.get("crb_corr_sd_m", np.full_like(tr["determined"], np.nan))  # trials before version 12: not measured
    within_corr = np.where(det & np.isfinite(corr), (tr["pos_err_m"] <= CRB_FACTOR * corr).astype(float), np.nan)
    side = tr.get("side_correct", np.full_like(tr["determined"], np.nan))
    return {
        "crb": _share(within), "crb_correlated": _share(within_corr),
        "max_sds": float(np.nanmax(np.where(det, tr["pos_sds"], np.nan), initial=0.0)),
        "over_max_sds": int(np.sum(det & (tr["pos_sds"] > MAX_SDS))),
        "solutions": int(np.sum(np.isfinite(tr["determined"]))), "determined": int(np.sum(det)),
        "ml_diverged": int(np.nansum(tr["ml_diverged"])), "ml_printed": int(np.sum(det)),
        "imm_diverged": int(np.nansum(tr["imm_diverged"])), "imm_printed": int(np.nansum(tr["imm_printed"])),
        "ml_nees": _nees_summary(tr["ml_nees"][det]),
        "imm_nees": _nees_summary(tr["imm_nees"][tr["imm_printed"] == 1.0]),
        "side_correct": _share(side), "side_unresolved": int(np.sum(np.isfinite(tr["determined"]) & np.isnan(side))),
    }


def summarize(trials: dict[str, np.ndarray], config: Config) -> dict:
    names = ship_names(config)
    tr = {k: np.asarray(v, float) for k, v in trials.items()}
    n_false = int(np.sum(tr["false_targets_noise"]) + np.sum(tr["false_targets_ships"]))
    hours = float(np.sum(tr["hours"])) * 2.0  # each trial: a ship scene and a noise-only scene
    outcome = tr["crossing_outcome"] if "crossing_outcome" in tr else tr["identity_kept"]  # trial version 5: 1/0
    kept = np.where(np.isfinite(outcome), (outcome == 1.0).astype(float), np.nan)
    axis_ok = np.where(np.isfinite(tr["axis_error_deg"]),
                       (tr["axis_error_deg"] <= AXIS_BEAMWIDTHS * tr["beamwidth_deg"]).astype(float), np.nan)
    return {
        "ships": names, "scenes": tr["scene"].tolist(),
        "hold": {n: _mean_interval(tr["hold"][:, s]) for s, n in enumerate(names)},
        "hold_all": _mean_interval(tr["hold"].ravel()),
        "hold_pairs_at_least": _share(np.where(np.isfinite(tr["hold"]), tr["hold"] >= HOLD_REQUIRED, np.nan)),
        "identity": _share(kept),
        "identity_crossed": _share(np.where(tr["crossing_crossed"] == 1.0, kept, np.nan)),
        "crossing_outcomes": {name: int(np.sum(outcome == code)) for code, name in OUTCOMES.items()},
        "axis": _share(axis_ok), "axis_one_target": _share(tr["axis_one_target"]),
        "axis_error_deg": _mean_interval(tr["axis_error_deg"]),
        **_solution_summary(tr),
        "ospa_cone_deg": _mean_interval(tr["ospa_cone_deg"]), "gospa_cone_deg": _mean_interval(tr["gospa_cone_deg"]),
        "gospa_switches": _mean_interval(tr["gospa_switches"]),
        "ospa_position_m": _mean_interval(tr["ospa_position_m"]),
        "segments": {n: _mean_interval(tr["segments"][:, s]) for s, n in enumerate(names)},
        "switches": {n: _mean_interval(tr["switches"][:, s]) for s, n in enumerate(names)},
        "narrowband_targets": int(np.sum(tr.get("narrowband_targets", np.zeros(1)))),
        "false_targets": n_false, "hours": hours,
        "false_per_hour": n_false / hours, "false_per_hour_upper95": _poisson_upper(n_false) / hours,
    }


def _num(v) -> float:
    """A summary number (JSON stores NaN as null) as a float."""
    return float("nan") if v is None else float(v)


def _fmt_interval(v) -> str:
    a, b, c = (_num(x) for x in v)
    return f"{a:.2f} [{b:.2f}, {c:.2f}]"


def _fmt_share(d: dict) -> str:
    if not d["n"]:
        return "none to judge"
    return f"{d['k']} of {d['n']} = {_num(d['share']):.2f} [{_num(d['low']):.2f}, {_num(d['high']):.2f}]"


def _fmt_nees(name: str, d: dict) -> str:
    if not d["n"]:
        return f"{name} NEES: no solution"
    return (f"{name} ANEES {_num(d['anees']):.1f} of {d['n']} (chi-square 95 % {_num(d['low']):.2f}-"
            f"{_num(d['high']):.2f}; {_num(d['inside']):.0%} single NEES inside chi2(4) 95 %)")


def _share_holds(d: dict, required: float) -> bool:
    return d["n"] > 0 and _num(d["share"]) >= required


SHARE_TOLERANCE = "point estimate against the requirement; 95 % Clopper-Pearson interval shown"


def _hold_claim(summary: dict) -> Claim:
    v = summary["hold_all"]
    return Claim(id="ships-held", paper=f"ours: every ship held by a confirmed track >= {HOLD_REQUIRED:.0%} of the "
                                        "time its SNR is above the detection threshold",
                 text="mean over (run, ship) pairs of the share of the ship's detectable windows held by a confirmed "
                      f"track within match_deg (or a beamwidth, if wider) of its cone angle >= {HOLD_REQUIRED}",
                 ours=f"all {_fmt_interval(v)}; " + "; ".join(f"{n} {_fmt_interval(x)}" for n, x in
                                                               summary["hold"].items())
                      + f"; pairs held >= {HOLD_REQUIRED}: {_fmt_share(summary['hold_pairs_at_least'])}"
                      + f"; (report) OSPA of the tracks' cone angles {_num(summary['ospa_cone_deg'][0]):.2f} deg, "
                        f"GOSPA {_num(summary['gospa_cone_deg'][0]):.2f} deg with "
                        f"{_num(summary['gospa_switches'][0]):.1f} switches per run; track segments / identity "
                        "switches per ship " + ", ".join(f"{n} {_num(summary['segments'][n][0]):.1f} / "
                                                         f"{_num(summary['switches'][n][0]):.1f}" for n in
                                                         summary["ships"]),
                 holds=np.isfinite(_num(v[0])) and _num(v[0]) >= HOLD_REQUIRED,
                 tolerance="point estimate against the requirement; 95 % normal interval over (run, ship) pairs")


def _share_claims(summary: dict) -> list[Claim]:
    i, a, c = summary["identity"], summary["axis"], summary["crb"]
    return [
        Claim(id="crossing-identities", paper=f"ours: identities kept through crossings in cone angle in >= "
                                              f"{IDENTITY_REQUIRED:.0%} of crossings",
              text="crossings (two ships within one beam of the array) whose two ships are followed by the same "
                   f"two targets before and after, share >= {IDENTITY_REQUIRED}",
              ours=f"{_fmt_share(i)} (of those crossing in order: {_fmt_share(summary['identity_crossed'])}); "
                   + ", ".join(f"{n} {k}" for n, k in summary["crossing_outcomes"].items()),
              holds=_share_holds(i, IDENTITY_REQUIRED), tolerance=SHARE_TOLERANCE),
        Claim(id="axis-bearing", paper=f"ours: true bearing after an array-axis crossing within {AXIS_BEAMWIDTHS:g} "
                                       f"beamwidths of the truth in >= {AXIS_REQUIRED:.0%}",
              text="axis crossings whose following target's true bearings (median, 20 s to crossing_window_s + 20 s "
                   f"after) lie within {AXIS_BEAMWIDTHS:g} beamwidths, share >= {AXIS_REQUIRED}",
              ours=f"{_fmt_share(a)}; mean median error {_fmt_interval(summary['axis_error_deg'])} deg; one target "
                   f"through the crossing {_fmt_share(summary['axis_one_target'])}",
              holds=_share_holds(a, AXIS_REQUIRED), tolerance=SHARE_TOLERANCE),
        Claim(id="ml-near-crb", paper=f"ours: ML final position within {CRB_FACTOR:g}x the CRB in >= {CRB_SHARE:.0%} "
                                      f"of determined solutions, none off by more than {MAX_SDS:g} of its own sds",
              text=f"determined final ML solutions of targets following a ship with error <= {CRB_FACTOR:g} x CRB "
                   f"position sd, share >= {CRB_SHARE}; and none with a position Mahalanobis distance > {MAX_SDS:g}",
              ours=f"{_fmt_share(c)}; {summary['over_max_sds']} over {MAX_SDS:g} sds (largest "
                   f"{_num(summary['max_sds']):.1f}); {summary['determined']} of {summary['solutions']} determined; "
                   f"(report) within {CRB_FACTOR:g}x the CRB of AR(1) errors with the peaks' own lag-1 correlation "
                   f"{_fmt_share(summary['crb_correlated'])}; "
                   f"{_fmt_nees('ML', summary['ml_nees'])}, {_fmt_nees('IMM-MGEKF', summary['imm_nees'])}; "
                   f"OSPA of the determined positions {_num(summary['ospa_position_m'][0]):.0f} m; side right "
                   f"{_fmt_share(summary['side_correct'])}, {summary['side_unresolved']} unresolved",
              holds=_share_holds(c, CRB_SHARE) and summary["over_max_sds"] == 0, tolerance=SHARE_TOLERANCE),
    ]


def _diverged_claim(summary: dict) -> Claim:
    n_ml, n_imm = summary["ml_diverged"], summary["imm_diverged"]
    return Claim(id="no-diverged", paper="ours: no printed solution has diverged",
                 text="final ML and IMM-MGEKF rows printed with a range that are not finite, beyond "
                      f"{DIVERGED_RANGE_FACTOR:g}x the true range or faster than 60 kn: 0",
                 ours=f"ML {n_ml} of {summary['ml_printed']} printed, IMM-MGEKF {n_imm} of {summary['imm_printed']} "
                      "printed",
                 holds=n_ml == 0 and n_imm == 0, tolerance="a count: none allowed")


def _false_claim(summary: dict) -> Claim:
    return Claim(id="false-targets", paper="ours: noise-only recordings give at most 1 confirmed false target "
                                           "per hour",
                 text="confirmed targets following no ship, per hour of recording (noise-only scenes and the ship "
                      "scenes together) <= 1",
                 ours=f"{summary['false_targets']} in {summary['hours']:.1f} h = {summary['false_per_hour']:.2f} per "
                      f"hour (95 % upper bound {summary['false_per_hour_upper95']:.2f})",
                 holds=summary["false_per_hour"] <= FALSE_PER_HOUR, tolerance="point estimate; Poisson upper bound "
                                                                              "shown")


def claims(summary: dict, config: Config) -> list[Claim]:
    return [_hold_claim(summary), *_share_claims(summary), _diverged_claim(summary), _false_claim(summary)]
