"""Are the active chain's false contacts independent from ping to ping? Streak factors of reverberation-only contacts.

Measurement only (issue 34 items 3, 5). On the reverberation-only twins of study ``active-chain`` trials (run and
cached by benchmarks/bench_active_family.py ``trial_scene`` / ``run_quiet``, the same ``--cache``), for the contacts
the tracker is given (``result.contacts`` where ``result.gated_out`` is True: despite its name, ContactTracker.step's
verdict "given to the tracker"; both mirror hypotheses; the clutter map's withholding from tentative tracks is not
in the result, hence the split by still points below):

* lambda0 = contacts per ping / A, A = pi (c t_max / 2)^2 the area they can fall in (cw_tracking.py
  ``cw_clutter_area``'s; t_max the longest travel time of the detections);
* for each contact i of ping k, the number of contacts of ping k + L (L = 1, 2, 3) in a target-like gate of it,
  d^2 = (x_j - x_i)^T S_i^-1 (x_j - x_i) < gamma (chi2_2 at the tracker's P_G 0.99, gamma 9.21), against the
  Poisson expectation lambda0 pi gamma sqrt(det S_i): ``wide`` S_i = R_i + (v L T)^2 I, v = 5 m/s, T the ping
  interval (a target of unknown velocity); ``tight`` S_i = (1 + 1/3 + (L + 1)^2 / 2) R_i (a 3-hit track's
  prediction: a straight line fitted to 3 hits one interval apart, predicted L intervals on, plus the new contact's
  R, process noise neglected). On a CW also |rr_j - rr_i| < 3 sqrt(2) sd_rr (sd_rr = c / (f_c tau) / sqrt(12), the
  resolution cell's as cw_tracking.py ``cw_rate_sd_mps``),
  the Poisson expectation then times the share of all contacts whose rr lies in that window of rr_i;
* the streak factor F_L = observed / Poisson, and the same at far lags L = 10..14 with the L = 1 gates (``far``:
  pings that share no MFTD window; what is left there is the contacts' spatial clumping and the still points'
  recurrence, not the detector's memory), so F_1 / F_far is the ping-to-ping memory alone; q_L the mean count in
  the gate per ping-k contact (q_1 is the chance a false contact "continues", to set against a target's P_D);
* split by the ping-k contact's source (``detection_kind``: "mftd", "strong" single-ping, "single") and by whether it
  lies within ``--near`` m of a still clutter point of the scene or of its mirror about the array axis.

Then the per-hit evidence of a target against each clutter density (IPDA, Musicki, Evans & Stankovic 1994 eq. 29
with one contact in the gate: Lambda = 1 - P_D P_G + P_D N(nu; 0, S) / lambda, the expectation over nu ~ N(0, S)
inside the gate, by quadrature over d^2 ~ chi2_2; S the tight gate's at L = 1 with each contact's own R, the median
over contacts), the per-ping drift P_D E[ln Lambda_hit] + (1 - P_D) ln(1 - P_D P_G) + ln p11, and the pings to gain
ln(n / f) (tracking/existence.py ``confirm_threshold_for_rate``: n = 7 tracks started a ping, f = 1 false track/h
in pings) from the initial existence: for lambda = the LFM tracker's 1e-6 setting, lambda0, and lambda0 F_1 (tight)
the streak-conditioned density a track following a streak actually meets.

Usage: ``PYTHONPATH=src python benchmarks/bench_false_streaks.py --trials 14 2 10 18 1 --minutes 30 --cache DIR``
(the chain runs once per trial and is cached; the measurement takes seconds).

Measured (2026-12-08, session 13, h13-streak on main c79db23; seed 2017; 1 h reverberation-only twins, 120 pings of
30 s; the chain ~2 min CPU a trial (CW 1-1.7 min), this script 5 s for all; ``--trials 14 2 10 18 1 11 15 --minutes
60``). tight gate (a 3-hit track's), F = observed / Poisson density in the gate, q = contacts in the gate per ping-k
contact (Poisson expectation 0.015-0.027 on the LFMs), gain = a Swerling target's (P_D 0.7) expected nats per hit,
pings = to the 6.73 nats of ln(7 x 3600 / 30) (1 false track/h, 7 tracks started a ping):

  trial (pulse, sea, points)   contacts/ping  lambda0   F1 all/mftd/strong/not-near  F2   F3  F_far  q1 all/mftd  q_far
  14 (LFM 200 Hz, K +5, 6)     20.1           1.35e-8   21.1 / 34.1 / 7.9 / 11.5    12.7  8.4  10.4   0.32 / 0.56  0.16
  2  (LFM 200 Hz, K +10, 0)    23.1           1.58e-8    5.4 / 11.2 / 3.1 / 5.4      3.5  2.8   1.5   0.12 / 0.25  0.03
  10 (LFM 200 Hz, spiky K, 6)  24.9           1.68e-8    8.3 / 16.0 / 2.1 / 5.2      5.7  3.7   3.0   0.22 / 0.43  0.08
  18 (LFM 50 Hz, Rayleigh, 14) 13.6           9.3e-9    27.8 / 28.7 / 23.2 / 28.6   12.0  6.8   7.1   0.63 / 0.66  0.16
  11 (CW, spiky K +10, 6)       1.3           1.1e-9    39 (151 contacts: ~4 pairs at L = 1, all MFTD, all near a point)
  15 (CW, K +5, 14)             1.0           8.8e-10   0 at L = 1, 77 at L = 2 (116 contacts: ~6 MFTD pairs at L = 2,
                                                        ~4 of them away from points)
  1  (CW, Rayleigh +5, 14)      0.6           6.3e-10   97 (70 contacts: ~8 pairs at L = 1, all near a point)

  gain nats/hit (pings):  tracker's 1e-6   lambda0      lambda0 F1    lambda0 F1 mftd  mixture not-near (q, kappa)
  14                      0.81 (35)        4.82 (2.2)   1.88 (7.2)    1.45 (10.5)      2.01 (6.5)  (0.12, 2.8)
  2                       0.67 (73)        4.49 (2.4)   2.84 (4.2)    2.15 (6.0)       2.11 (6.1)  (0.08, 1.8)
  10                      0.63 (102)       4.37 (2.5)   2.32 (5.4)    1.72 (8.1)       2.23 (5.7)  (0.12, 3.6)
  18                      0.22 (never)     4.41 (2.5)   1.26 (13.3)   1.23 (13.8)      0.45 (never) (0.57, 1.4)

What it says. (1) The LFM false contacts are far from Poisson: a contact of ping k has 5-28 times the mean density
of contacts in a 3-hit track's gate on ping k + 1 (MFTD contacts 11-34 times, strong single-ping ones 2-23 times); F
decays with the lag (F3 ~ F1 / 4 to F1 / 2) but stays 1.5-10 times at lags 10-14 (F_far: still points, their images
and the contacts' clumping near the array; the clutter map's job). The detector's own memory, F1 / F_far, is 2-4 on
all contacts, 4-16 away from still points (within 1.5 km of a point or its mirror: 0-47 % of the contacts). (2) As a
chance: a false MFTD contact has a successor in a 3-hit track's gate on the next ping 25-66 % of the time (Poisson:
2 %), i.e. a streak looks like a target with P_D 0.25-0.66, and in the 3-hit gate grown to lag L it still finds a
successor nearly as often at L = 2-6 (q_L 0.4-1.2 q_1), falling to q_far (0.03-0.28 for MFTD, the same L = 1 gate)
by lags 10-14; on trial 18 (50 Hz, Rayleigh) every kind of contact away from points continues 60 % of the time. (3)
So the mean density lambda0 ~1e-8 overstates a target's evidence by ln F1 ~ 1.7-3.3 nats a hit (4.4-4.8 nats/hit,
confirmation in 2.2-2.5 pings: as the 19-23 false tracks a scene of the earlier sessions showed), and the tracker's
1e-6 understates it (0.2-0.8 nats/hit, 35-100 pings or never at P_D 0.7) by ln(1e-6 / (lambda0 F1)) ~ 1.3-2.5 nats:
1e-6 is 3.5-12 times the density a track meets after a clutter hit. Against the streak-conditioned density a real
target gains 1.3-2.8 nats a hit (MFTD-conditioned 1.2-2.2), 0.5-1.6 nats a ping at P_D 0.7, confirmation in 4-14
pings (2-7 min); against the fitted mixture (below, away from still points) 2.0-2.2 nats a hit, 5.7-6.5 pings, but
on trial 18 ~0.45 nats a hit: never (there a streak is as likely to continue as a target to be detected, so position
alone cannot tell them apart within the window; only its end, F3 / F1 ~ 0.2, or amplitude, velocity or Doppler can).
(4) The CW contacts (0.6-1.3 a ping) are too few to measure a streak factor (4-8 pairs an hour): at L = 1 all are
near still points (the clutter and ridge maps' job); trial 15's ~4 MFTD pairs at L = 2 away from points are the only
CW streak seen.

The clutter model that would make the IPDA's likelihood ratio honest (Ville's bound in tracking/existence.py needs
prod Lambda to be a martingale under "no target", i.e. the denominator must be the density of the track's next
contact GIVEN its past contacts were clutter): a first-order (Markov) clutter density per track,
lambda(z | the track's last contact z_prev, its source) = lambda_b(z) + q_s N(z; z_hat, kappa S), with lambda_b the
local background (the contacts' own spatial density near the track over many pings, lambda0 F_far: a clutter map /
spatial clutter density estimate in the sense of Musicki & Evans 2004, clutter map information for data association
and track initialization, and the spatial clutter measurement density estimation the brief names as Song & Musicki
2008 -- neither paper is in /work/shared/papers, not checked against them), and q_s the chance a source-s false
contact continues (measured here: MFTD 0.25-0.66, strong single-ping 0.06-0.49, after a miss the lag-2/3 values),
kappa ~ 1-4 (the continuation is spread like a track's prediction). A pooled density that ignores the condition
cannot be right for both: too low (lambda0), false tracks confirm on streaks; too high (1e-6), targets do not.
With the gate-averaged conditional density (lambda0 F_1) a real target would gain ~1.3-2.8 nats a hit; the
mixture's q N term takes 0.4-0.8 nats of that back (the continuation is densest at the prediction, where a target's
hit lands too; the mixture column against the F1 not-near one: 2.0 vs 2.4, 2.1 vs 2.8, 2.2 vs 2.8, 0.45 vs 1.2).

Caveats: the ``near`` split is geometric (1.5 km of a scene point or its mirror), not the clutter map's verdict
(not in the result); the CW gain's range-rate factor uses the contacts' empirical rr density and
exp(-1/2) / (sqrt(4 pi) sd) for the target's (an approximation of the expectation); the tight gate neglects process
noise; the gains are expectations over a Gaussian innovation in the gate with one contact, not a tracker run.
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

import numpy as np

GAMMA = 9.21  # chi2_2 at P_G 0.99 (tracking/settings.py gate_probability)
P_G, P_D, P11 = 0.99, 0.7, 0.98
LAGS, FAR_LAGS = (1, 2, 3, 4, 5, 6), tuple(range(10, 15))
MIN_CONTACTS = 200  # fewer contacts in a split: no clutter model fitted to it


def _family():
    """benchmarks/bench_active_family.py as a module (its trial scene and cached chain run)."""
    path = Path(__file__).with_name("bench_active_family.py")
    spec = importlib.util.spec_from_file_location("bench_active_family", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def contact_table(result, scene, near_m: float) -> dict:
    """The tracker's contacts as arrays: ping index, xy, R, rr, source kind, near a still point (module doc)."""
    from sonartrack.studies.active_chain_family import is_clutter

    fam = _family()
    c, keep = result.contacts, np.asarray(result.gated_out, bool)  # True: given to the tracker (ContactTracker.step)
    ping_index = {float(t): k for k, t in enumerate(result.ping_time_s)}
    k = np.array([ping_index.get(float(t), -1) for t in c.time_s])[keep]
    xy, R, rr, t = c.xy[keep], c.R[keep], np.asarray(c.range_rate_mps, float)[keep], c.time_s[keep]
    kinds = np.asarray(result.detection_kind, object)
    kind = kinds[c.detection[keep]] if len(kinds) == len(result.detections) else np.full(len(k), "single", object)
    pts = np.array([[p.x_m, p.y_m] for p in scene.targets if is_clutter(p.name)], float).reshape(-1, 2)
    near = np.zeros(len(k), bool)
    for p in pts:
        pp = np.repeat(p[None], len(k), 0)
        mir = fam._mirror(result.geometry, t, pp)
        near |= (np.hypot(*(xy - p).T) < near_m) | (np.hypot(*(xy - mir).T) < near_m)
    return {"k": k, "xy": xy, "R": R, "rr": rr, "kind": kind.astype(str), "near": near}


def searched_area_m2(result, sound_speed_mps: float) -> float:
    """pi (c t_max / 2)^2: the area the contacts can fall in (cw_tracking.py cw_clutter_area's)."""
    return float(np.pi * (sound_speed_mps * np.max(result.detections.travel_time_s) / 2.0) ** 2)


def gate_counts(tab: dict, lag: int, interval_s: float, tight: bool, rr_window: float | None, gate_lag: int):
    """Per contact of ping k: (contacts of ping k + lag in its gate, gate area m^2, rr share) (module doc), the gate
    that of ``gate_lag`` pings on. Contacts whose ping k + lag does not exist get NaN."""
    k, xy, R, rr = tab["k"], tab["xy"], tab["R"], tab["rr"]
    n = len(k)
    obs, area, share, d2sum = np.full(n, np.nan), np.full(n, np.nan), np.ones(n), np.zeros(n)
    g = gate_lag
    S = R * (1.0 + 1.0 / 3.0 + (g + 1) ** 2 / 2.0) if tight else R + (5.0 * g * interval_s) ** 2 * np.eye(2)
    Si = np.linalg.inv(S)
    area_all = np.pi * GAMMA * np.sqrt(np.linalg.det(S))
    if rr_window is not None:
        srt = np.sort(rr)
        share = (np.searchsorted(srt, rr + rr_window) - np.searchsorted(srt, rr - rr_window)) / len(rr)
    last = k.max()
    for p in np.unique(k):
        i, j = np.nonzero(k == p)[0], np.nonzero(k == p + lag)[0]
        if p + lag > last:
            continue
        area[i] = area_all[i]
        if not len(j):
            obs[i] = 0.0
            continue
        d = xy[j][None] - xy[i][:, None]  # (ni, nj, 2)
        d2 = np.einsum("abi,aij,abj->ab", d, Si[i], d)
        ok = d2 < GAMMA
        if rr_window is not None:
            ok &= np.abs(rr[j][None] - rr[i][:, None]) < rr_window
        obs[i], d2sum[i] = ok.sum(1), np.where(ok, d2, 0.0).sum(1)
    return obs, area, share, d2sum


def streak_rows(tab: dict, lam0: float, interval_s: float, rr_window: float | None) -> list[dict]:
    """Streak factors per gate, lag and split (module doc)."""
    splits = {"all": np.ones(len(tab["k"]), bool)}
    for kd in np.unique(tab["kind"]):
        splits[kd] = tab["kind"] == kd
    splits["near pt"], splits["not near"] = tab["near"], ~tab["near"]
    rows = []
    for tight in (False, True):
        per_lag = {}
        for lag in LAGS + FAR_LAGS:
            per_lag[lag] = gate_counts(tab, lag, interval_s, tight, rr_window, lag if lag in LAGS else 1)
        for name, m in ((n, m) for n, m in splits.items() if m.any()):
            row = {"gate": "tight" if tight else "wide", "split": name, "n": int(m.sum())}
            for lag in LAGS + FAR_LAGS:
                obs, area, share, d2sum = per_lag[lag]
                ok = m & np.isfinite(obs)
                exp = lam0 * np.sum(area[ok] * share[ok])
                row[lag] = float(np.sum(obs[ok]) / exp) if exp > 0 else float("nan")
                row[f"exp{lag}"] = float(exp / max(ok.sum(), 1))
                row[f"q{lag}"] = float(np.mean(obs[ok])) if ok.any() else float("nan")
                row[f"d2_{lag}"] = float(np.sum(d2sum[ok]) / max(np.sum(obs[ok]), 1.0))
            far = [row[lag] for lag in FAR_LAGS if np.isfinite(row[lag])]
            row["far"] = float(np.mean(far)) if far else float("nan")
            row["memory"] = row[1] / row["far"] if row["far"] > 0 else float("inf")
            rows.append(row)
    return rows


def hit_gain_nats(S_det_sqrt: np.ndarray, lam: float, rate_term: np.ndarray | float = 1.0) -> float:
    """E[ln Lambda] of a hit: Lambda = 1 - P_D P_G + P_D N(nu; 0, S) rate_term / lambda, nu ~ N(0, S) within the
    gate (d^2 ~ chi2_2 truncated at gamma: density exp(-d^2/2)/2 / P_G), averaged over the contacts' S."""
    d2 = np.linspace(0.0, GAMMA, 401)
    w = np.exp(-d2 / 2.0) / 2.0 / P_G
    w /= np.trapezoid(w, d2)
    dens = np.exp(-d2 / 2.0)[None] / (2.0 * np.pi * np.asarray(S_det_sqrt, float)[:, None])
    lr = 1.0 - P_D * P_G + P_D * dens * np.asarray(rate_term, float).reshape(-1, 1) / lam
    return float(np.mean(np.trapezoid(np.log(lr) * w[None], d2, axis=1)))


def truncated_scale(mean_d2: float) -> float:
    """kappa such that d^2 = kappa X, X ~ chi2_2 truncated at gamma / kappa, has this mean: the spread of a streak's
    continuation about the ping-k contact, as a multiple of the gate's S (large: uniform over the gate)."""
    def mean(kappa):
        t = GAMMA / kappa
        return kappa * (2.0 - t * np.exp(-t / 2.0) / (1.0 - np.exp(-t / 2.0)))
    lo, hi = 1e-3, 1e3
    if mean_d2 >= mean(hi):
        return hi
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if mean(mid) < mean_d2 else (lo, mid)
    return float(np.sqrt(lo * hi))


def mixture_gain_nats(S_det_sqrt: np.ndarray, lam_b: float, q: float, kappa: float) -> float:
    """E[ln Lambda] of a hit against the streak-conditioned clutter density lambda(z | the track's last contact) =
    lambda_b + q N(z; z_hat, kappa S) (a background plus the last contact's continuation, if it was clutter), nu ~
    N(0, S) in the gate (as :func:`hit_gain_nats`)."""
    d2 = np.linspace(0.0, GAMMA, 401)
    w = np.exp(-d2 / 2.0)
    w /= np.trapezoid(w, d2)
    sq = np.asarray(S_det_sqrt, float)[:, None]
    target = np.exp(-d2 / 2.0)[None] / (2.0 * np.pi * sq)
    clutter = lam_b + q * np.exp(-d2 / (2.0 * kappa))[None] / (2.0 * np.pi * kappa * sq)
    lr = 1.0 - P_D * P_G + P_D * target / clutter
    return float(np.mean(np.trapezoid(np.log(lr) * w[None], d2, axis=1)))


def confirm_pings(gain_hit: float, interval_s: float, started_per_ping: float = 7.0) -> tuple[float, float]:
    """(drift nats per ping, pings to gain ln(n / f)) for a target with P_D (module doc)."""
    need = np.log(started_per_ping * 3600.0 / interval_s)
    drift = P_D * gain_hit + (1.0 - P_D) * np.log(1.0 - P_D * P_G) + np.log(P11)
    return float(drift), float(need / drift) if drift > 0 else float("inf")


def evidence(tab: dict, lam0: float, interval_s: float, rows: list[dict], rr_window: float | None,
             rr_sd: float | None) -> list[tuple]:
    cw = rr_window is not None
    """The per-hit gain and pings to confirm against each clutter density (module doc)."""
    S_det_sqrt = np.sqrt(np.linalg.det(tab["R"] * (1.0 + 1.0 / 3.0 + 2.0)))
    rate_term = 1.0
    if rr_window is not None:  # the contact's rr: target N(0, 2 sd^2) over the clutter's rr density at rr_i
        srt = np.sort(tab["rr"])
        f_rr = (np.searchsorted(srt, tab["rr"] + rr_window) - np.searchsorted(srt, tab["rr"] - rr_window)) / (
            len(srt) * 2.0 * rr_window)
        rate_term = np.exp(-0.5) / (np.sqrt(2.0 * np.pi * 2.0) * rr_sd) / np.maximum(f_rr, 1e-12)
    F = {r["split"]: r for r in rows if r["gate"] == "tight"}
    F.setdefault("not near", F["all"])
    out = []
    tracker = ("tracker's (lambda0)", lam0) if cw else ("tracker's 1e-6", 1e-6)  # CW: the contacts' own density
    for label, lam in (tracker, ("lambda0", lam0), ("far (clumping)", lam0 * F["all"]["far"]),
                       ("streak F1", lam0 * F["all"][1]), ("streak F1 mftd", lam0 * F.get("mftd", F["all"])[1]),
                       ("streak F1 strong", lam0 * F.get("strong", F["all"])[1]),
                       ("F1 not near", lam0 * F["not near"][1]), ("F3 not near", lam0 * F["not near"][3])):
        if not lam > 0:  # no contact in any gate: too few contacts to say
            continue
        g = hit_gain_nats(S_det_sqrt, lam, rate_term)
        drift, pings = confirm_pings(g, interval_s)
        out.append((label, lam, g, drift, pings))
    for split in ("all", "not near"):
        a = F[split]
        if a["n"] < MIN_CONTACTS or not a["far"] > 0:
            continue
        far_q = float(np.mean([a[f"q{lag}"] for lag in FAR_LAGS]))
        far_d2 = float(np.mean([a[f"d2_{lag}"] for lag in FAR_LAGS]))
        q = max(a["q1"] - far_q, 0.0)
        mean_c = (a["q1"] * a["d2_1"] - far_q * far_d2) / q if q > 0 else GAMMA / 2.0
        kappa = truncated_scale(mean_c)
        lam_b = lam0 * max(a["far"], 1e-3)
        g = mixture_gain_nats(S_det_sqrt, lam_b, q, kappa) + (np.log(np.mean(rate_term)) if cw else 0.0)
        drift, pings = confirm_pings(g, interval_s)
        out.append((f"mix {split[:4]} q{q:.2f} k{kappa:.1f}", lam_b, g, drift, pings))
    return out


def report(i: int, result, scene, args) -> None:
    """Print one trial's table."""
    tab = contact_table(result, scene, args.near)
    interval = float(np.median(np.diff(result.ping_time_s)))
    area = searched_area_m2(result, scene.sound_speed_mps)
    n_pings = len(result.ping_time_s)
    lam0 = len(tab["k"]) / (n_pings * area)
    cw = scene.waveform.kind == "cw"
    rr_window = rr_sd = None
    if cw:
        w = scene.waveform  # the chain's sd: the resolution cell 1 / tau in range rate / sqrt(12) (cw_rate_sd_mps)
        rr_sd = scene.sound_speed_mps / (w.carrier_hz * w.duration_s) / np.sqrt(12.0)
        rr_window = 3.0 * np.sqrt(2.0) * rr_sd
    kinds = {str(kd): int(np.sum(tab["kind"] == kd)) for kd in np.unique(tab["kind"])}
    print(f"trial {i} ({scene.waveform.kind}, {n_pings} pings of {interval:.0f} s): {len(tab['k']) / n_pings:.1f} "
          f"contacts/ping {kinds}, near a point {tab['near'].mean():.0%}, A {area:.2e} m^2, lambda0 {lam0:.2e} /m^2"
          + (f", rr window +-{rr_window:.2f} m/s" if cw else ""))
    rows = streak_rows(tab, lam0, interval, rr_window)
    print(f"  {'gate':5s} {'split':9s} {'n':>5s} " + " ".join(f"{'F' + str(lag):>6s}" for lag in LAGS[:3]) +
          "  F_far F1/Ffar Poisson(L=1) " + " ".join(f"{'q' + str(lag):>5s}" for lag in LAGS) + " q_far")
    for r in rows:
        print(f"  {r['gate']:5s} {r['split']:9s} {r['n']:5d} " + " ".join(f"{r[lag]:6.1f}" for lag in LAGS[:3]) +
              f" {r['far']:6.1f} {r['memory']:7.1f} {r['exp1']:12.3f} " +
              " ".join(f"{r[f'q{lag}']:5.2f}" for lag in LAGS) + f" {np.mean([r[f'q{lag}'] for lag in FAR_LAGS]):5.2f}")
    print("  per-hit evidence of a target (pd 0.7, 3-hit prediction), pings to ln(7 x 3600/T) "
          f"= {np.log(7 * 3600 / interval):.2f} nats:")
    for label, lam, g, drift, pings in evidence(tab, lam0, interval, rows, rr_window, rr_sd):
        print(f"    {label:22s} lambda {lam:.2e}: {g:5.2f} nats/hit, {drift:5.2f} nats/ping, {pings:5.1f} pings")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, nargs="+", default=[14, 2, 10, 18, 1])
    ap.add_argument("--seed", type=int, default=2017, help="the study's master seed")
    ap.add_argument("--minutes", type=float, default=30.0, help="length of each twin (min)")
    ap.add_argument("--cache", type=Path, default=Path("/tmp/bench_active_family"))
    ap.add_argument("--near", type=float, default=1500.0, help="near a still point or its mirror: within this (m; "
                    "bench_active_family.py's --gate)")
    args = ap.parse_args()
    from sonartrack.studies.active_chain import Config

    fam, config = _family(), Config()
    for i in args.trials:
        scene, _ = fam.trial_scene(config, args.seed, i, args.minutes)
        result, sec = fam.run_quiet(config, scene, args.cache)
        report(i, result, scene, args)


if __name__ == "__main__":
    main()
