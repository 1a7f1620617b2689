"""An independent active-sonar ping generator for tests: a world written from the sonar equation, not sonartrack.sim.

Nothing here imports sonartrack (it writes the files ``sonartrack active`` reads with numpy and the csv module), so
that a test on these pings checks the chain against physics written separately from our simulator, whose
assumptions the chain was tuned on. The world:

* Ownship: constant speed, heading h0, an optional turn at rate w from ``turn_start_s`` through ``turn_deg``. The
  source Tx and the line array Rx are towed ``source_tow_m`` and ``array_tow_m`` behind it on its track (a towed
  body at time t is where the ship was L / v earlier, with its heading then); ``source_tow_m = 0`` is a hull source.
* Line array: N elements d apart, element n at s_n = ((N - 1)/2 - n) d along the axis from the centre (element 0
  the front, nearest the ship), x_n = Rx + s_n a, a = [sin phi, cos phi].
* Pulse p(t): an LFM sweeping -B/2..+B/2 around f_c over tau, or a CW tone, unit modulus, complex baseband.
* An echo from a point at p (velocity v) reaches element n after T_n = (|p - Tx| + |p - x_n|) / c with the
  Doppler shift f_d = -f_c rdot_B / c, rdot_B = u_T . (v - v_T) + u_R . (v - v_R) (u_T, u_R unit vectors from Tx
  and Rx to p), so that in complex baseband at f_c

      x_n(t) += A p(t - T_n) exp(2 pi i f_d (t - T_n)) exp(-2 pi i f_c T_n)

  with |A|^2 = 1e-12 10^(RL / 10) Pa^2 and the sonar equation RL = SL - TL(r_T) - TL(r_R) + TS,
  TL(r) = 20 log10 r + alpha r / 1000 (two-way spreading and absorption, alpha in dB/km, Thorp at f_c by default).
* Reverberation (Ol'shevskii's / Urick's patch model): the sea floor around the array is cut into patches, one per
  sample of total path (c / f_s) and per angular sector seen from Rx (a random angle inside each sector, so the
  patches are random scatterers); a patch of area dA on the bistatic ellipse has mean power
  SL - TL(r_T) - TL(r_R) + S + 10 log10(dA) (S the scattering strength, dB re 1 m^2 / m^2), and amplitude
  sqrt(texture) x complex Gaussian (Rayleigh speckle, fresh each ping). The texture is 1 (Rayleigh) or Gamma(nu,
  1/nu) per square of ``patch_m`` in the world (``patch_m`` <= 0: per patch, i.e. per scatterer) (K-distributed
  with shape nu: Ward, Tough & Watts, Sea Clutter, ch. 4; Watts 1987), drawn fresh each ping or fixed in the world
  (``texture_fixed``). Patches are still: their Doppler is the platforms'. Level falls with range (~ r^-3).
  Element delays of a patch are the plane-wave ones, T_n = T - s_n cos(theta) / c, the envelope delay rounded to a
  sample; echoes are grouped by Doppler on a grid ``doppler_step_hz`` apart (nearest node).
* Persistent clutter points: fixed in the world, target strength ``clutter_ts_db``, echoing every ping.
* The direct blast: the pulse from Tx to each element straight, |Tx - x_n| / c after transmit, level
  SL - 20 log10 |Tx - Rx| (spreading only).
* Targets: constant velocity, present from ``start_s``; a target's level is given either as TS or as its
  echo-to-background ratio ``ebr_db``: the peak matched-filter power of its echo on a beam steered at it, over the
  mean background power of that beam within +-``EBR_WINDOW_S`` of it (measured on the ping without the target by
  the small beamformer here), steady or Swerling 1.
* Ambient noise: complex Gaussian per element and sample, variance 1e-12 10^(NL / 10) f_s Pa^2.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

UPA2 = 1e-12
#: half-width of the window around a target's echo over which its background is averaged (s), and the part of it
#: next to the echo left out (s)
EBR_WINDOW_S, EBR_GAP_S = 1.0, 0.1


@dataclass(frozen=True)
class Target:
    """A constant-velocity target: position at t = 0 (m), velocity (m/s), TS (dB) or echo-to-background (dB)."""

    x_m: float
    y_m: float
    vx_mps: float = 0.0
    vy_mps: float = 0.0
    ts_db: float = 10.0
    ebr_db: float | None = None
    start_s: float = -np.inf
    swerling: bool = False

    def at(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        v = np.array([self.vx_mps, self.vy_mps])
        return np.array([self.x_m, self.y_m]) + v * t_s, v


@dataclass(frozen=True)
class World:
    """The world of the pings (module doc). Defaults: small and fast (12 s of listening at 200 Hz, 16 elements)."""

    pings: int = 10
    interval_s: float = 30.0
    window_s: float = 12.0
    fs_hz: float = 200.0
    sound_speed_mps: float = 1500.0
    noise_level_db: float = 60.0
    absorption_db_per_km: float | None = None
    ship_speed_mps: float = 2.5
    ship_heading_deg: float = 0.0
    turn_start_s: float = 1e9
    turn_deg: float = 0.0
    turn_rate_deg_s: float = 0.1
    elements: int = 16
    spacing_m: float = 0.5
    source_level_db: float = 215.0
    source_tow_m: float = 300.0
    array_tow_m: float = 450.0
    pulse: str = "lfm"
    duration_s: float = 1.0
    carrier_hz: float = 1500.0
    bandwidth_hz: float = 100.0
    scattering_db: float = -30.0
    texture_shape: float | None = None
    texture_fixed: bool = False
    patch_m: float = 300.0
    sectors: int = 120
    doppler_step_hz: float = 0.25
    blast: bool = False
    clutter_xy: tuple = ()
    clutter_ts_db: float = 20.0
    targets: tuple = ()
    seed: int = 1
    extra: dict = field(default_factory=dict)

    @property
    def alpha_db_per_m(self) -> float:
        if self.absorption_db_per_km is not None:
            return self.absorption_db_per_km / 1000.0
        f2 = (self.carrier_hz / 1000.0) ** 2  # Thorp (1967), dB/km with f in kHz
        return (0.11 * f2 / (1 + f2) + 44 * f2 / (4100 + f2) + 2.75e-4 * f2 + 0.003) / 1000.0

    @property
    def samples(self) -> int:
        return int(round(self.window_s * self.fs_hz))

    def ping_times(self) -> np.ndarray:
        return np.arange(self.pings) * self.interval_s


# --- platforms -----------------------------------------------------------------------------------------------------

def ship_heading(w: World, t) -> np.ndarray:
    """Ship heading (rad) at t: h0 + w min(max(t - t_turn, 0), turn / w)."""
    dt = np.clip(np.asarray(t, float) - w.turn_start_s, 0.0, abs(w.turn_deg) / w.turn_rate_deg_s)
    return np.deg2rad(w.ship_heading_deg + np.sign(w.turn_deg) * w.turn_rate_deg_s * dt)


def ship_xy(w: World, t) -> np.ndarray:
    """Ship position (m) at t: the heading integrated (0.05 s trapezoid; origin at t = 0)."""
    t = np.atleast_1d(np.asarray(t, float))
    t0 = min(float(t.min()), 0.0)
    grid = np.arange(t0, max(float(t.max()), 0.0) + 0.1, 0.05)
    h = ship_heading(w, grid)
    v = w.ship_speed_mps * np.stack([np.sin(h), np.cos(h)], -1)
    pos = np.concatenate([[[0.0, 0.0]], np.cumsum(0.5 * (v[1:] + v[:-1]) * 0.05, axis=0)])
    pos -= np.array([np.interp(0.0, grid, pos[:, 0]), np.interp(0.0, grid, pos[:, 1])])
    return np.stack([np.interp(t, grid, pos[:, 0]), np.interp(t, grid, pos[:, 1])], -1)


def towed(w: World, t, tow_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position (m), velocity (m/s) and heading (rad) of a body towed tow_m behind the ship on its track."""
    lag = tow_m / w.ship_speed_mps
    t = np.atleast_1d(np.asarray(t, float)) - lag
    h = ship_heading(w, t)
    return ship_xy(w, t), w.ship_speed_mps * np.stack([np.sin(h), np.cos(h)], -1), h


def nav_rows(w: World) -> dict:
    """The navigation every second over the pings (nav.csv's columns)."""
    t = np.arange(0.0, w.pings * w.interval_s + 1.0, 1.0)
    own, h = ship_xy(w, t), ship_heading(w, t)
    src, _, _ = towed(w, t, w.source_tow_m)
    arr, _, ha = towed(w, t, w.array_tow_m)
    return {"time_s": t, "x_m": own[:, 0], "y_m": own[:, 1], "heading_deg": np.rad2deg(h) % 360,
            "source_x_m": src[:, 0], "source_y_m": src[:, 1], "array_x_m": arr[:, 0], "array_y_m": arr[:, 1],
            "array_heading_deg": np.rad2deg(ha) % 360}


# --- signals -------------------------------------------------------------------------------------------------------

def pulse(w: World, doppler_hz: float = 0.0) -> np.ndarray:
    """p(t) exp(2 pi i f_d t) sampled at f_s (unit modulus)."""
    t = np.arange(int(round(w.duration_s * w.fs_hz))) / w.fs_hz
    phase = 2 * np.pi * doppler_hz * t
    if w.pulse == "lfm":
        phase = phase + np.pi * (w.bandwidth_hz / w.duration_s) * t * t - np.pi * w.bandwidth_hz * t
    return np.exp(1j * phase)


def loss_db(w: World, r_m) -> np.ndarray:
    r = np.maximum(np.asarray(r_m, float), 1.0)
    return 20 * np.log10(r) + w.alpha_db_per_m * r


@dataclass(frozen=True)
class Pose:
    """Tx and Rx at a ping: positions (2,), velocities (2,), array axis a (2,) and element offsets s_n (N,)."""

    tx: np.ndarray
    vtx: np.ndarray
    rx: np.ndarray
    vrx: np.ndarray
    axis: np.ndarray
    s: np.ndarray


def pose(w: World, t_s: float) -> Pose:
    tx, vtx, _ = towed(w, t_s, w.source_tow_m)
    rx, vrx, h = towed(w, t_s, w.array_tow_m)
    s = ((w.elements - 1) / 2.0 - np.arange(w.elements)) * w.spacing_m
    return Pose(tx[0], vtx[0], rx[0], vrx[0], np.array([np.sin(h[0]), np.cos(h[0])]), s)


def doppler_hz(w: World, ps: Pose, xy, vel) -> np.ndarray:
    """f_d = -f_c rdot_B / c of points xy (E, 2) moving at vel (E, 2)."""
    ut = xy - ps.tx
    ur = xy - ps.rx
    ut /= np.linalg.norm(ut, axis=-1, keepdims=True)
    ur /= np.linalg.norm(ur, axis=-1, keepdims=True)
    rdot = np.sum(ut * (vel - ps.vtx), -1) + np.sum(ur * (vel - ps.vrx), -1)
    return -w.carrier_hz * rdot / w.sound_speed_mps


def add_point(spec: np.ndarray, w: World, delays_s: np.ndarray, amp: complex, fd_hz: float) -> None:
    """x_n += A p(t - T_n) exp(2 pi i f_d (t - T_n)) exp(-2 pi i f_c T_n), exactly, in the frequency domain."""
    n_fft = spec.shape[1]
    f = np.fft.fftfreq(n_fft, 1.0 / w.fs_hz)
    p = np.fft.fft(pulse(w, fd_hz), n_fft)
    spec += amp * p * np.exp(-2j * np.pi * np.outer(delays_s, w.carrier_hz + f))


def anti_alias(w: World, n_fft: int) -> np.ndarray:
    """The receiver's anti-alias filter before sampling: 1 within 60 % of Nyquist, a raised cosine to 0 at 90 %
    (without it a fractional delay of the pulse's sharp edges rings over the whole window, ~70 dB down: a blast at
    171 dB would leave ~100 dB everywhere, above the ambient noise)."""
    a = np.abs(np.fft.fftfreq(n_fft, 1.0 / w.fs_hz)) / (w.fs_hz / 2)
    return np.where(a < 0.6, 1.0, np.where(a > 0.9, 0.0, 0.5 * (1 + np.cos(np.pi * (a - 0.6) / 0.3))))


def point_delays(w: World, ps: Pose, xy) -> np.ndarray:
    """T_n (N,) from Tx to xy to each element (exact paths)."""
    el = ps.rx + np.outer(ps.s, ps.axis)
    return (np.linalg.norm(xy - ps.tx) + np.linalg.norm(el - xy, axis=-1)) / w.sound_speed_mps


# --- reverberation -------------------------------------------------------------------------------------------------

def patches(w: World, ps: Pose, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Reverberation patches of one ping: positions (E, 2), total-path delay sample k (E,), mean power (E,) Pa^2.

    Patch j of sample k lies on the ellipse of total path R_B = c k / f_s around Tx and Rx at world bearing psi from
    Rx: r_R = (R_B^2 - D^2) / (2 (R_B - D cos chi)) (chi: angle between psi and Rx -> Tx), its area the ring between
    R_B and R_B + c / f_s over the sector, 0.5 (r_R(R_B + dR)^2 - r_R(R_B)^2) dpsi."""
    c, fs = w.sound_speed_mps, w.fs_hz
    base = ps.tx - ps.rx
    dist = float(np.hypot(*base))
    k = np.arange(int(np.floor(dist / c * fs)) + 2, w.samples)  # R_B > D: a proper ellipse
    dpsi = 2 * np.pi / w.sectors
    psi = (np.arange(w.sectors)[None, :] + rng.uniform(0, 1, (k.size, w.sectors))) * dpsi  # bearing from Rx
    u = np.stack([np.sin(psi), np.cos(psi)], -1)
    cos_chi = (u @ base) / max(dist, 1e-9)

    def r_rx(rb):
        return (rb**2 - dist**2) / (2 * (rb - dist * cos_chi))

    rb = (k * c / fs)[:, None]
    r1, r2 = r_rx(rb), r_rx(rb + c / fs)
    area = 0.5 * (r2**2 - r1**2) * dpsi
    xy = ps.rx + r1[..., None] * u
    r_t = rb - r1
    level = w.source_level_db - loss_db(w, r_t) - loss_db(w, r1) + w.scattering_db + 10 * np.log10(area)
    power = UPA2 * 10 ** (level / 10)
    kk = np.broadcast_to(k[:, None], psi.shape)
    return xy.reshape(-1, 2), kk.reshape(-1), power.reshape(-1)


def texture(w: World, xy: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Gamma(nu, 1/nu) per ``patch_m`` square of the world (1 for Rayleigh); fixed in the world or fresh per ping."""
    if w.texture_shape is None:
        return np.ones(len(xy))
    if w.patch_m <= 0:  # every scatterer its own texture: a few per resolution cell, a heavy tail uncorrelated in range
        return rng.gamma(w.texture_shape, 1.0 / w.texture_shape, len(xy))
    cell = np.floor(xy / w.patch_m).astype(np.int64)
    uniq, inv = np.unique(cell, axis=0, return_inverse=True)
    if w.texture_fixed:
        g = np.array([np.random.default_rng([w.seed, 7919, int(a) + 2**20, int(b) + 2**20]).gamma(
            w.texture_shape, 1.0 / w.texture_shape) for a, b in uniq])
    else:
        g = rng.gamma(w.texture_shape, 1.0 / w.texture_shape, len(uniq))
    return g[inv.reshape(-1)]


def add_reverberation(spec: np.ndarray, w: World, ps: Pose, rng: np.random.Generator) -> None:
    """The patches' echoes (module doc): impulse trains per element at their delay samples, carrier phase exact per
    element (plane wave), convolved with the pulse shifted to their Doppler node."""
    xy, k, power = patches(w, ps, rng)
    keep = power > 0
    xy, k, power = xy[keep], k[keep], power[keep]
    amp = np.sqrt(power * texture(w, xy, rng)) * (rng.standard_normal(len(k)) + 1j * rng.standard_normal(len(k)))
    amp /= np.sqrt(2.0)
    ur = xy - ps.rx
    ur /= np.linalg.norm(ur, axis=-1, keepdims=True)
    cos_theta = ur @ ps.axis
    order = np.argsort(np.rint(doppler_hz(w, ps, xy, np.zeros_like(xy)) / w.doppler_step_hz), kind="stable")
    node = np.rint(doppler_hz(w, ps, xy[order], np.zeros((len(order), 2))) / w.doppler_step_hz).astype(np.int64)
    k, amp, cos_theta = k[order], amp[order], cos_theta[order]
    t_el = (k / w.fs_hz)[None, :] - np.outer(ps.s, cos_theta) / w.sound_speed_mps  # (N, E) element delays
    phase = 2 * np.pi * np.mod(w.carrier_hz * t_el, 1.0)
    weight = amp[None, :] * (np.cos(phase) - 1j * np.sin(phase))
    n_fft = spec.shape[1]
    edges = np.flatnonzero(np.diff(node)) + 1
    for lo, hi in zip(np.r_[0, edges], np.r_[edges, len(node)], strict=True):
        train = np.zeros((w.elements, n_fft), complex)
        for n in range(w.elements):
            train[n] = (np.bincount(k[lo:hi], weight[n, lo:hi].real, n_fft)
                        + 1j * np.bincount(k[lo:hi], weight[n, lo:hi].imag, n_fft))
        spec += np.fft.fft(train, axis=1) * np.fft.fft(pulse(w, node[lo] * w.doppler_step_hz), n_fft)


def add_blast(spec: np.ndarray, w: World, ps: Pose) -> None:
    """The source's direct arrival at each element (module doc): level SL - 20 log10 |Tx - Rx|, no Doppler (the
    source and the array move together)."""
    el = ps.rx + np.outer(ps.s, ps.axis)
    dist = np.linalg.norm(el - ps.tx, axis=-1)
    level = w.source_level_db - 20 * np.log10(max(float(np.hypot(*(ps.tx - ps.rx))), 1.0))
    add_point(spec, w, dist / w.sound_speed_mps, np.sqrt(UPA2 * 10 ** (level / 10)), 0.0)


def blast_level_db(w: World, t_s: float = 0.0) -> float:
    """Level of the direct blast at the array centre (dB re 1 uPa^2)."""
    ps = pose(w, t_s)
    return w.source_level_db - 20 * np.log10(max(float(np.hypot(*(ps.tx - ps.rx))), 1.0))


# --- targets and pings ---------------------------------------------------------------------------------------------

def beam_mf_power(spec: np.ndarray, w: World, ps: Pose, cos_theta: float, fd_hz: float) -> np.ndarray:
    """|z(t)|^2 of a true-time-delay beam steered at cos(theta), matched-filtered at Doppler f_d (the calibration of
    ``ebr_db``; lag t = sample index / f_s)."""
    n_fft = spec.shape[1]
    f = np.fft.fftfreq(n_fft, 1.0 / w.fs_hz)
    tau = -ps.s * cos_theta / w.sound_speed_mps
    beam = np.sum(spec * np.exp(2j * np.pi * np.outer(tau, w.carrier_hz + f)), axis=0)
    z = np.fft.ifft(beam * np.conj(np.fft.fft(pulse(w, fd_hz), n_fft)))
    return np.abs(z) ** 2


def target_amplitude(w: World, tgt: Target, spec_bg: np.ndarray, unit: np.ndarray, ps: Pose, xy, fd: float,
                     t_centre: float, rng) -> tuple[complex, float]:
    """The echo's complex amplitude (Pa) and its echo-to-background ratio (dB) on its beam (module doc)."""
    ur = (xy - ps.rx) / np.linalg.norm(xy - ps.rx)
    cos_t = float(ur @ ps.axis)
    lag = np.arange(spec_bg.shape[1]) / w.fs_hz
    near = np.abs(lag - t_centre)
    peak = float(beam_mf_power(unit, w, ps, cos_t, fd)[near < 2.0 / max(w.bandwidth_hz, 1 / w.duration_s)].max())
    ring = (near > EBR_GAP_S + w.duration_s * (w.pulse == "cw")) & (near < EBR_WINDOW_S + w.duration_s
                                                                    * (w.pulse == "cw")) & (lag < w.window_s)
    bg = float(beam_mf_power(spec_bg, w, ps, cos_t, fd)[ring].mean())
    if tgt.ebr_db is not None:
        rms = np.sqrt(10 ** (tgt.ebr_db / 10) * bg / peak)
    else:
        lvl = w.source_level_db - loss_db(w, np.linalg.norm(xy - ps.tx)) - loss_db(w, np.linalg.norm(xy - ps.rx))
        rms = np.sqrt(UPA2 * 10 ** ((lvl + tgt.ts_db) / 10))
    g = rng.standard_normal(2)
    a = rms * (g[0] + 1j * g[1]) / np.sqrt(2) if tgt.swerling else rms * np.exp(1j * np.arctan2(g[1], g[0]))
    return complex(a), float(10 * np.log10(rms**2 * peak / bg))


def ping(w: World, k: int) -> tuple[np.ndarray, list[dict]]:
    """Ping k (0-based): samples (N, M) complex64 in Pa, sample 0 at the transmit time, and its truth rows."""
    rng = np.random.default_rng([w.seed, k])
    t0 = k * w.interval_s
    ps = pose(w, t0)
    m, n_pulse = w.samples, int(round(w.duration_s * w.fs_hz))
    n_fft = 1 << int(np.ceil(np.log2(m + n_pulse + 1)))
    spec = np.zeros((w.elements, n_fft), complex)
    add_reverberation(spec, w, ps, rng)
    if w.blast:
        add_blast(spec, w, ps)
    for cxy in w.clutter_xy:
        xy = np.asarray(cxy, float)
        lvl = w.source_level_db - loss_db(w, np.linalg.norm(xy - ps.tx)) - loss_db(w, np.linalg.norm(xy - ps.rx))
        add_point(spec, w, point_delays(w, ps, xy), np.sqrt(UPA2 * 10 ** ((lvl + w.clutter_ts_db) / 10))
                  * np.exp(2j * np.pi * rng.uniform()), float(doppler_hz(w, ps, xy[None], np.zeros((1, 2)))[0]))
    spec *= anti_alias(w, n_fft)
    noise = np.zeros((w.elements, n_fft), complex)
    noise[:, :m] = (rng.standard_normal((w.elements, m)) + 1j * rng.standard_normal((w.elements, m))) * np.sqrt(
        UPA2 * 10 ** (w.noise_level_db / 10) * w.fs_hz / 2)
    spec += np.fft.fft(noise, axis=1)
    rows = []
    for i, tgt in enumerate(w.targets):
        xy, vel = tgt.at(t0)
        delays = point_delays(w, ps, xy)
        t_centre = (np.linalg.norm(xy - ps.tx) + np.linalg.norm(xy - ps.rx)) / w.sound_speed_mps
        if t0 < tgt.start_s or delays.max() + w.duration_s > w.window_s:
            continue
        fd = float(doppler_hz(w, ps, xy[None], vel[None])[0])
        unit = np.zeros_like(spec)
        add_point(unit, w, delays, 1.0, fd)
        a, ebr = target_amplitude(w, tgt, spec, unit, ps, xy, fd, t_centre, rng)
        spec += a * unit
        ur = (xy - ps.rx) / np.linalg.norm(xy - ps.rx)
        rows.append({"ping": k + 1, "time_s": t0, "target": i, "x_m": xy[0], "y_m": xy[1], "travel_time_s": t_centre,
                     "cone_deg": float(np.rad2deg(np.arccos(np.clip(ur @ ps.axis, -1, 1)))), "doppler_hz": fd,
                     "ebr_db": ebr})
    return np.fft.ifft(spec, axis=1)[:, :m].astype(np.complex64), rows


def ping_table_rows(w: World) -> dict:
    """The ping table's columns (systems/active/scene_files.py's layout)."""
    n = w.pings
    return {"ping": np.arange(1, n + 1), "transmit_time_s": w.ping_times(),
            "file": [f"pings/ping_{i:04d}.npy" for i in range(1, n + 1)], "waveform": [w.pulse] * n,
            "fc_hz": [w.carrier_hz] * n, "bandwidth_hz": [w.bandwidth_hz if w.pulse == "lfm" else 0.0] * n,
            "duration_s": [w.duration_s] * n, "fs_hz": [w.fs_hz] * n, "channels": [w.elements] * n,
            "samples": [w.samples] * n}


def _write_csv(path: Path, columns: dict) -> None:
    keys = list(columns)
    buf = io.StringIO()
    wr = csv.writer(buf, lineterminator="\n")
    wr.writerow(keys)
    for row in zip(*(columns[k] for k in keys), strict=True):
        wr.writerow([f"{v:.9g}" if isinstance(v, float | np.floating) else v for v in row])
    path.write_text(buf.getvalue())


def write_world(w: World, folder) -> list[dict]:
    """Write the pings, ping_table.csv, nav.csv (and world_truth.csv) into ``folder``; returns the truth rows."""
    folder = Path(folder)
    (folder / "pings").mkdir(parents=True, exist_ok=True)
    truth = []
    for k in range(w.pings):
        x, rows = ping(w, k)
        np.save(folder / f"pings/ping_{k + 1:04d}.npy", x)
        truth += rows
    _write_csv(folder / "nav.csv", nav_rows(w))
    if truth:
        _write_csv(folder / "world_truth.csv", {key: [r[key] for r in truth] for key in truth[0]})
    _write_csv(folder / "ping_table.csv", ping_table_rows(w))
    return truth
