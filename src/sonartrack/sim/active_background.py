"""Each target echo's expected echo-to-background ratio (EBR): its matched-filter power on its beam over the noise
plus the mean reverberation in its cell, from the simulator's own scattering model (sim/active_signals.py).

The truth column ``snr_db`` (sim/active_scene.py ``echo_snr_db``) is echo-to-noise only; on a reverberation-
limited scene an echo at 15 dB SNR can sit under the reverberation. With the pulse s(t) of length tau (unit
modulus), the matched filter y(t0) = int x(t) s*(t - t0) dt and the conventional beam of N uniform elements steered
at the echo's cone theta_0 (|b|^2 = 1 on the axis):

    echo            RL tau^2 N^2
    noise           NL tau N                                  (spectral level NL, per element, white)
    reverberation   tau^2 N^2 R,  R = int S L(x) |b(theta(x))|^2 |chi(t(x) - t0, f(x) - f0)|^2 dA

(the expected power of a Poisson field of point scatterers whose mean cross-section per m^2 is S, density x
sigma_bar in sim/active_signals.py, is the integral of its mean intensity; Ward, Tough and Watts, Sea Clutter,
ch. 4; Urick, Principles of Underwater Sound, ch. 8 for the reverberation level as an area integral), with
L(x) = 10^((SL - TL(r_T) - TL(r_R)) / 10) the two-way level of a unit cross-section at x, chi the pulse's
normalised ambiguity function (|chi(0, 0)| = 1) and f(x) the Doppler of the still scatterer at x seen by the moving
source and array. So

    EBR = RL / (NL / (tau N) + R),     ebr_db = snr_db - 10 log10(1 + R tau N / NL)

(noise only: ebr = snr). R is integrated on the bistatic ellipse of the echo's travel time t0 (foci source and
array): dA = r (dr/dt) dt da in the angle a around the array and the one-way range r from it, and the delay
integral of |chi|^2 is done first, J(df) = int |chi(u, df)|^2 du, because chi is narrow in delay:

    CW  (P1):  |chi(u, df)|^2 = (1 - |u|/tau)^2 sinc^2(df (tau - |u|))     for |u| < tau
    LFM:       |chi(u, df)|^2 = (1 - |u|/tau)^2 sinc^2((df - (B/tau) u)(tau - |u|))

(Levanon and Mozeson, Radar Signals, eqs. 3.10 and 4.9). For a CW echo off the reverberation ridge J(df) is
small (the Doppler filter at the echo's Doppler does not pass the still scatterers); for an LFM J ~ 1/B at every
Doppler of interest (the range-Doppler coupling moves a scatterer's peak, it keeps its energy). The LFM's
range-Doppler shift moves the cell by f_d tau / B (up to 0.23 s in study active-chain's family: a 50 Hz band at
1.5 kHz, 11.6 m/s of bistatic range rate): the reverberation is taken at the travel time. The echo's OWN peak does
lose: the chain's LFM replica is unshifted, and on the ridge u = f_d tau / B the sinc is 1, so its peak power is
(1 - |f_d| / B)^2 of a still echo's (Levanon and Mozeson eq. 4.9): -2.3 dB at f_d = 0.23 B. ``ebr_db`` carries
that loss (a CW's replica bank is at the echo's Doppler: none).
Expected values only (never the ping's realised echo), so "detectable" stays a property of the scene.
"""

from __future__ import annotations

import numpy as np

from sonartrack.sim.active_scene import (
    ActiveSceneSettings,
    Platforms,
    TransmissionLoss,
    echo_geometry,
    max_path_range_m,
)

#: angle steps around the array per integral (the beam's main lobe 2/N rad wide holds >= 20 of them up to 256
#: elements' 0.45 deg)
ANGLE_STEPS = 7200
#: Doppler step of the tabulated delay integral J(df), as a fraction of 1 / tau (sinc^2 varies on 1 / tau)
DOPPLER_TABLE_STEP = 0.02


def ambiguity_delay_integral_s(kind: str, duration_s: float, bandwidth_hz: float, doppler_hz) -> np.ndarray:
    """J(df) = int |chi(u, df)|^2 du (s) of a CW or LFM pulse (module doc), by the trapezoid rule in u.

    Parameters
    ----------
    kind : {"cw", "lfm"}
        The pulse.
    duration_s, bandwidth_hz : float
        Pulse length tau (s) and LFM sweep B (Hz; ignored for a CW).
    doppler_hz : array_like
        Doppler differences df (Hz).

    Returns
    -------
    numpy.ndarray
        J (s), shaped as ``doppler_hz``; CW at df = 0: 2 tau / 3; LFM with B tau >> 1: ~1 / B.
    """
    tau = float(duration_s)
    slope = float(bandwidth_hz) / tau if kind == "lfm" else 0.0
    steps = int(np.clip(40.0 * max(bandwidth_hz * tau if kind == "lfm" else 1.0, 1.0), 400, 40_000))
    u = np.linspace(-tau, tau, 2 * steps + 1)
    df = np.asarray(doppler_hz, float)
    out = np.empty(df.shape)
    flat, res = df.ravel(), out.reshape(-1)
    for i in range(0, flat.size, 256):  # bounded memory: 256 Dopplers x the delay grid at a time
        d = flat[i:i + 256, None]
        chi2 = (1.0 - np.abs(u) / tau) ** 2 * np.sinc((d - slope * u) * (tau - np.abs(u))) ** 2
        res[i:i + 256] = np.trapezoid(chi2, u, axis=1)
    return out


def _ellipse_points(rx_xy, tx_xy, path_m: float, angles: np.ndarray):
    """(points (A, 2), r (A,) one-way range from the array, dr/dpath (A,)) on the bistatic ellipse r_T + r_R =
    path: |d + r u| = path - r with d = rx - tx gives r = (path^2 - |d|^2) / (2 (path + d.u))."""
    d = np.asarray(rx_xy, float) - np.asarray(tx_xy, float)
    u = np.stack([np.sin(angles), np.cos(angles)], -1)
    du = u @ d
    den = path_m + du
    r = (path_m ** 2 - d @ d) / (2.0 * den)
    dr = (2.0 * path_m * den - (path_m ** 2 - d @ d)) / (2.0 * den ** 2)
    return np.asarray(rx_xy, float) + r[:, None] * u, r, dr


def beam_power(elements: int, spacing_m: float, carrier_hz: float, sound_speed_mps: float, cone_rad,
               steer_rad: float) -> np.ndarray:
    """|b|^2 of the uniform line of ``elements`` steered at cone ``steer_rad``, at cones ``cone_rad`` (1 on the axis):
    |sum_n exp(2 pi i f_c s_n (cos theta - cos theta_0) / c)|^2 / N^2 = (sin(N psi / 2) / (N sin(psi / 2)))^2."""
    psi = 2.0 * np.pi * carrier_hz * spacing_m * (np.cos(cone_rad) - np.cos(steer_rad)) / sound_speed_mps
    half = 0.5 * psi
    s = np.sin(half)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = np.where(np.abs(s) < 1e-12, 1.0, np.sin(elements * half) / (elements * s))
    return g * g


def reverberation_in_cell(scene: ActiveSceneSettings, tl: TransmissionLoss, plat: Platforms, k: int,
                          travel_s: float, cone_rad: float, doppler_hz: float, j_table) -> float:
    """R (uPa^2, module doc): the mean reverberation of ping ``k`` in the matched filter's cell (travel time
    ``travel_s``, Doppler ``doppler_hz``) on the beam steered at ``cone_rad``, per unit tau^2 N^2.

    ``j_table`` is (Doppler grid (Hz), J (s)) from :func:`ambiguity_delay_integral_s`, interpolated."""
    c = scene.sound_speed_mps
    path = travel_s * c
    baseline = float(np.hypot(*(plat.rx_xy[k] - plat.tx_xy[k])))
    if path <= baseline:
        return 0.0
    a = (np.arange(ANGLE_STEPS) + 0.5) * (2.0 * np.pi / ANGLE_STEPS)
    xy, r, dr_dpath = _ellipse_points(plat.rx_xy[k], plat.tx_xy[k], path, a)
    w = scene.waveform
    g = echo_geometry(xy, np.zeros_like(xy), plat.tx_xy[k], plat.tx_velocity[k], plat.rx_xy[k],
                      plat.rx_velocity[k], plat.array_heading_rad[k], w.carrier_hz, c)
    rv = scene.reverberation
    inside = (r >= rv.min_range_m) & (r <= max_path_range_m(scene))
    j = np.interp(g.doppler_hz - doppler_hz, *j_table)
    b2 = beam_power(scene.sonar.elements, scene.spacing_m, w.carrier_hz, c, g.cone_rad, cone_rad)
    area_per_s = r * dr_dpath * c * (2.0 * np.pi / ANGLE_STEPS)  # dA / dt per angle step (m^2/s)
    total = 0.0
    for pop in (rv.boundary, rv.volume):
        if pop.density_per_km2 <= 0:
            continue
        level = scene.sonar.source_level_db - tl.tx(g.tx_range_m, pop.depth_m) - tl.rx(g.rx_range_m, pop.depth_m)
        total += float(np.sum(np.where(inside, 10.0 ** (pop.strength_db / 10.0) * 10.0 ** (level / 10.0)
                                       * b2 * j * area_per_s, 0.0)))
    return total


def doppler_table(scene: ActiveSceneSettings, max_doppler_hz: float):
    """(Doppler grid (Hz), J (s)) over +-``max_doppler_hz`` at steps DOPPLER_TABLE_STEP / tau."""
    w = scene.waveform
    step = DOPPLER_TABLE_STEP / w.duration_s
    n = int(np.ceil(max_doppler_hz / step)) + 1
    grid = np.arange(-n, n + 1) * step
    return grid, ambiguity_delay_integral_s(w.kind, w.duration_s, w.bandwidth_hz, grid)


def echo_background_db(scene: ActiveSceneSettings, tl: TransmissionLoss, plat: Platforms, truth: dict) -> np.ndarray:
    """ebr_db for every row of the truth table (sim/active_scene.py ``target_truth``): snr_db - 10 log10(1 + R tau N
    / NL) (module doc); NaN where the echo's travel time is past the listening window (no cell to compare).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene.
    tl : TransmissionLoss
        Its transmission loss.
    plat : Platforms
        The platforms at the ping times (the truth's pings, 1-based ``ping`` rows into it).
    truth : dict
        The truth table (ping, travel_time_s, cone_deg, doppler_hz, snr_db).

    Returns
    -------
    numpy.ndarray
        (rows,) EBR (dB).
    """
    snr = np.asarray(truth["snr_db"], float)
    out = np.full(snr.shape, np.nan)
    if not snr.size:
        return out
    travel = np.asarray(truth["travel_time_s"], float)
    dop = np.asarray(truth["doppler_hz"], float)
    scat_max = 2.0 * scene.waveform.carrier_hz * float(np.max(np.hypot(*plat.rx_velocity.T))) \
        / scene.sound_speed_mps * 1.5 + 1.0
    table = doppler_table(scene, float(np.max(np.abs(dop))) + scat_max)
    noise = 10.0 ** (scene.noise_level_db / 10.0) / (scene.waveform.duration_s * scene.sonar.elements)
    peak_db = lfm_peak_loss_db(scene.waveform, dop)
    for i in np.nonzero(travel < scene.ping_interval_s)[0]:
        rev = reverberation_in_cell(scene, tl, plat, int(truth["ping"][i]) - 1, travel[i],
                                    np.deg2rad(float(truth["cone_deg"][i])), dop[i], table)
        out[i] = snr[i] + peak_db[i] - 10.0 * np.log10(1.0 + rev / noise)
    return out


def lfm_peak_loss_db(waveform, doppler_hz) -> np.ndarray:
    """10 log10 of an echo's matched-filter peak power at Doppler ``doppler_hz`` over a still echo's (dB, <= 0): an
    LFM's 20 log10(1 - |f_d| / B) (module doc; -300 dB past |f_d| >= B), 0 for a CW."""
    fd = np.abs(np.asarray(doppler_hz, float))
    if waveform.kind != "lfm":
        return np.zeros(fd.shape)
    return 20.0 * np.log10(np.clip(1.0 - fd / waveform.bandwidth_hz, 1e-15, 1.0))
