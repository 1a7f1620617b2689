"""Multi-target bearing tracking with JPDA or amplitude-aided JPDA_A (Park, Ryu & Lee 1994, paper P0).

State per track: [bearing (deg), bearing rate (deg/s)], the cone angle of the two-sensor array
(0-180 deg from the array axis, the paper's units; kept in degrees because every parameter of the
paper is). Per scan of period T:

    predict   x = F x,  P = F P F^T + Q,  F = [[1, T], [0, 1]],  Q = q [[T^3/3, T^2/2], [T^2/2, T]]
    gate      |z - x_0| <= V / 2  (the paper's gate of width V), P_G = erf(V / (2 sqrt(2 S)))
    weights   w_tj = P_D N(z_j; x_0, S) / lambda  [x r_tj for JPDA_A],  w_t0 = 1 - P_D P_G
    marginals exact JPDA (association/jpda.py)
    update    PDA: x += K sum_j beta_j nu_j;
              P = beta_0 P + (1 - beta_0)(P - K S K^T) + K (sum_j beta_j nu_j^2 - nubar^2) K^T

with S = P_00 + sigma_p^2 and K = P H^T / S. Defaults are the paper's: T = 1 s, q = 0.1, V = 10 deg,
P(0) = [[s^2, s^2], [s^2, 2 s^2]] with s = sigma_p, amplitude threshold 5000.

Track strength for JPDA_A: "known" uses each track's model strength (the paper's synthetic runs);
"adaptive" uses eq. 9 (z_hat = 0.7 z_hat + 0.3 max amplitude in the gate, from 15000), as for real data.

Automatic initiation (``BearingTracker.auto``): a tentative track starts on every peak above
``init_amplitude`` that no track gates, with zero rate and P(0) at the initiation sigma_p;
it is confirmed after ``confirm_m`` scans with a gated peak among its first ``confirm_n``, and
dropped after ``delete_after`` consecutive scans with an empty gate (a one-point initiation with an
M-of-N confirmation).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sonartrack.association.amplitude import (
    STRENGTH_INITIAL,
    amplitude_log_ratio,
    detection_probability_above,
    update_strength,
)
from sonartrack.association.jpda import jpda_log_weights


@dataclass(frozen=True, slots=True)
class BearingTrackerConfig:
    """Tracker settings (module doc); ``amplitude`` selects JPDA_A."""

    amplitude: bool = False
    period_s: float = 1.0
    q: float = 0.1
    gate_deg: float = 10.0
    p_detect: float = 1.0
    clutter_density_per_deg: float = 2.0 / 10.0 * float(np.exp(-2.0))
    false_amplitude_rate: float = 4e-4
    amplitude_threshold: float = 5_000.0
    strength: str = "known"
    # automatic initiation (user data)
    init_amplitude: float = 7_000.0
    init_sigma_p_deg: float = 1.5
    init_amplitude_sd: float = 3_000.0
    confirm_m: int = 3
    confirm_n: int = 4
    delete_after: int = 5


@dataclass
class BearingTracks:
    """The live tracks (arrays over tracks)."""

    x: np.ndarray  # (n, 2) deg, deg/s
    P: np.ndarray  # (n, 2, 2)
    sigma_p: np.ndarray  # (n,) deg
    strength: np.ndarray  # (n,)
    sigma_a: np.ndarray  # (n,)
    ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    hits: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    age: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    misses: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    confirmed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


def initial_covariance(sigma_p_deg) -> np.ndarray:
    s2 = np.asarray(sigma_p_deg, dtype=float) ** 2
    return np.stack([np.stack([s2, s2], -1), np.stack([s2, 2 * s2], -1)], -2)


class BearingTracker:
    """JPDA / JPDA_A over a fixed set of tracks, or with automatic initiation (``auto=True``)."""

    def __init__(self, config: BearingTrackerConfig, bearings_deg=(), sigma_p_deg=(), strength=(), sigma_a=(),
                 auto: bool = False):
        n = len(bearings_deg)
        self.cfg = config
        self.auto = auto
        self._next_id = n
        x = np.zeros((n, 2))
        x[:, 0] = bearings_deg
        sp = np.broadcast_to(np.asarray(sigma_p_deg, dtype=float), (n,)).copy()
        st = np.broadcast_to(np.asarray(strength, dtype=float), (n,)).copy() if n else np.zeros(0)
        if config.strength == "adaptive":
            st[:] = STRENGTH_INITIAL
        self.tracks = BearingTracks(x, initial_covariance(sp) if n else np.zeros((0, 2, 2)), sp, st,
                                    np.broadcast_to(np.asarray(sigma_a, dtype=float), (n,)).copy() if n else np.zeros(0),
                                    np.arange(n), np.zeros(n, dtype=int), np.zeros(n, dtype=int), np.zeros(n, dtype=int),
                                    np.ones(n, dtype=bool))
        T = config.period_s
        self.F = np.array([[1.0, T], [0.0, 1.0]])
        self.Q = config.q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])

    def step(self, z_deg, amplitude) -> BearingTracks:
        """Process one scan of peaks (bearing deg, amplitude); returns the updated tracks."""
        from scipy.special import erf

        c = self.cfg
        tr = self.tracks
        z = np.asarray(z_deg, dtype=float)
        a = np.asarray(amplitude, dtype=float)
        n = len(tr.x)
        used = np.zeros(len(z), dtype=bool)
        if n:
            tr.x = tr.x @ self.F.T
            tr.P = self.F @ tr.P @ self.F.T + self.Q
            S = tr.P[:, 0, 0] + tr.sigma_p**2
            nu = z[None, :] - tr.x[:, :1]
            gated = np.abs(nu) <= c.gate_deg / 2
            pg = erf(c.gate_deg / 2 / np.sqrt(2 * S))
            if c.amplitude:
                pd_eff = detection_probability_above(c.p_detect, tr.strength, tr.sigma_a, c.amplitude_threshold)
                pd_eff = np.clip(pd_eff, 1e-6, 1.0)
                ll = np.log(c.p_detect) - 0.5 * nu**2 / S[:, None] - 0.5 * np.log(2 * np.pi * S)[:, None] \
                    - np.log(c.clutter_density_per_deg)
                ll = ll + amplitude_log_ratio(a, tr.strength, tr.sigma_a, c.false_amplitude_rate, c.amplitude_threshold)
            else:
                pd_eff = np.full(n, c.p_detect)
                if tr.strength.size:
                    pd_eff = np.clip(detection_probability_above(c.p_detect, tr.strength, np.maximum(tr.sigma_a, 1e-9),
                                                                 c.amplitude_threshold), 1e-6, 1.0)
                ll = np.log(pd_eff)[:, None] - 0.5 * nu**2 / S[:, None] - 0.5 * np.log(2 * np.pi * S)[:, None] \
                    - np.log(c.clutter_density_per_deg)
            ll = np.where(gated, ll, -np.inf)
            log_miss = np.log(np.clip(1.0 - pd_eff * pg, 1e-12, 1.0))
            beta = np.exp(jpda_log_weights(ll, log_miss))
            b0 = beta[:, 0]
            bj = beta[:, 1:]
            nubar = np.sum(bj * nu, axis=1)
            spread = np.sum(bj * nu**2, axis=1) - nubar**2
            K = tr.P[:, :, 0] / S[:, None]
            tr.x = tr.x + K * nubar[:, None]
            KSK = K[:, :, None] * K[:, None, :] * S[:, None, None]
            tr.P = tr.P - (1 - b0)[:, None, None] * KSK + K[:, :, None] * K[:, None, :] * spread[:, None, None]
            tr.P = 0.5 * (tr.P + np.swapaxes(tr.P, 1, 2))
            if c.amplitude and c.strength == "adaptive":
                amax = np.where(gated, a[None, :], -np.inf).max(axis=1, initial=-np.inf)
                tr.strength = update_strength(tr.strength, np.where(np.isfinite(amax), amax, np.nan))
            hit = gated.any(axis=1)
            used = gated.any(axis=0)
            tr.age += 1
            tr.hits += hit
            tr.misses = np.where(hit, 0, tr.misses + 1)
        if self.auto:
            self._manage(z, a, used)
        return self.tracks

    def _manage(self, z, a, used) -> None:
        c = self.cfg
        tr = self.tracks
        if len(tr.x):
            keep = tr.misses < c.delete_after
            keep &= tr.confirmed | (tr.age < c.confirm_n) | (tr.hits >= c.confirm_m)
            tr.confirmed = tr.confirmed | (tr.hits >= c.confirm_m)
            for name in ("x", "P", "sigma_p", "strength", "sigma_a", "ids", "hits", "age", "misses", "confirmed"):
                setattr(tr, name, getattr(tr, name)[keep])
        new = np.nonzero(~used & (a >= c.init_amplitude))[0]
        # one new track per cluster of nearby unused peaks (the strongest)
        chosen: list[int] = []
        for j in new[np.argsort(-a[new])]:
            if all(abs(z[j] - z[i]) > c.gate_deg / 2 for i in chosen):
                chosen.append(int(j))
        if not chosen:
            return
        k = len(chosen)
        x = np.zeros((k, 2))
        x[:, 0] = z[chosen]
        tr.x = np.concatenate([tr.x, x])
        tr.P = np.concatenate([tr.P, initial_covariance(np.full(k, c.init_sigma_p_deg))])
        tr.sigma_p = np.concatenate([tr.sigma_p, np.full(k, c.init_sigma_p_deg)])
        tr.strength = np.concatenate([tr.strength, a[chosen] if c.strength == "adaptive" else a[chosen]])
        tr.sigma_a = np.concatenate([tr.sigma_a, np.full(k, c.init_amplitude_sd)])
        tr.ids = np.concatenate([tr.ids, self._next_id + np.arange(k)])
        self._next_id += k
        tr.hits = np.concatenate([tr.hits, np.ones(k, dtype=int)])
        tr.age = np.concatenate([tr.age, np.ones(k, dtype=int)])
        tr.misses = np.concatenate([tr.misses, np.zeros(k, dtype=int)])
        tr.confirmed = np.concatenate([tr.confirmed, np.zeros(k, dtype=bool)])
