"""The complex-baseband samples of one ping at each hydrophone: target echoes, reverberation, ambient noise.

Every echo (a target or a scatterer) is the transmitted pulse s(t) (acoustics/matched_filter.py), delayed by
its bistatic travel time to element n, T_n = t + tau_n (tau_n = -s_n cos(theta) / c, the plane-wave delay
from its cone angle theta, sim/array_signals.py's convention), Doppler-shifted by f_d = -f_c rdot_B / c and
scaled by its level (sim/active_scene.py):

    x_n(t) = sum_echoes A s(t - T_n) exp(2 pi i f_d (t - T_n)) exp(-2 pi i f_c T_n),    |A|^2 = 10^(RL/10) uPa^2

(complex baseband at f_c, |x|^2 = mean-square pressure, in Pa). Sample 0 is the transmit time; the window
holds T f_s samples (the whole ping interval). The direct blast from the source is not simulated (the
receiver blanks it; the front end drops delays below its ``blank_s``).

* Targets: exact, in the frequency domain: X_n(f) += A exp(-2 pi i (f_c + f) T_n) S_d(f), with S_d the FFT of
  s(t) exp(2 pi i f_d t), zero-padded past the window (no wrap). A is complex Gaussian per ping
  (Swerling 1, paper P1) or of fixed modulus (``steady``), with a uniform phase.
* Reverberation: each ping draws fresh Poisson fields of seabed and volume point scatterers over the annulus
  min_range_m .. (c T / 2 + baseline) around the array (everything that can echo within the window), uniform
  in range and angle: the density falls as 1 / r (stated at 10 km), so every resolution cell (whose area
  grows as r) holds the same mean number of scatterers and the work is spread evenly over the cells. Each
  has cross-section sigma = sigma_bar(r) g e, g ~ Gamma(nu, 1/nu) (texture), e ~ Exp(1) (speckle): sigma is
  K-distributed with mean sigma_bar(r) = 10^(S/10) / density(r) (so density x sigma_bar is the scattering
  strength S per m^2 at every range; Ward, Tough and Watts, Sea Clutter, ch. 4); with about one scatterer
  per cell or fewer, the background is heavy-tailed.
  Scatterers are stationary (their Doppler comes from the moving source and array). Thousands of echoes
  are vectorised: the carrier phase exp(-2 pi i f_c T_n) is exact at every element; the envelope delay is the
  array centre's, rounded to the nearest sample (errors <= 1 / (2 f_s) from the rounding and <= (N - 1) d /
  (2 c) across the array, each 2.5 ms at the defaults, a quarter of the LFM's resolution 1 / B: the
  reverberation's beams are the narrowband ones, its envelope a little smeared); the Doppler is
  split linearly between the two nearest nodes of a grid ``doppler_step_hz`` apart; per node the delays are
  binned into an impulse train per element (np.bincount) and convolved with the node's Doppler-shifted pulse
  by FFT: one FFT per node and element.
* Ambient noise: independent complex Gaussian per element and sample, variance 10^(NL/10) f_s uPa^2 (the
  spectral level NL flat over the f_s-wide baseband).

A fresh field per ping (not a fixed seabed) because the ship moves ~80 m (> 50 wavelengths) between pings,
which decorrelates the speckle; P4's clutter model is likewise independent from scan to scan.
"""

from __future__ import annotations

import numpy as np

from sonartrack.acoustics.active_beams import plane_wave_delays_s
from sonartrack.acoustics.matched_filter import Waveform, fft_length
from sonartrack.sim.active_scene import (
    ActiveSceneSettings,
    Platforms,
    ScattererSettings,
    TransmissionLoss,
    echo_geometry,
    max_path_range_m,
    target_motion,
)

#: (1 uPa)^2 in Pa^2: levels in dB re 1 uPa become pascals
UPA2_PA2 = 1e-12
#: scatterer densities are stated at this range from the array (m); they fall as 1 / r (module doc)
REFERENCE_RANGE_M = 10_000.0


def element_offsets(scene: ActiveSceneSettings) -> np.ndarray:
    """s_n = ((N - 1)/2 - n) d, front positive (m).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene (N elements, spacing d in m).

    Returns
    -------
    numpy.ndarray
        (N,) offset of each element from the array centre along the axis (m), element 0 the front.
    """
    n = scene.sonar.elements
    return ((n - 1) / 2.0 - np.arange(n)) * scene.spacing_m


def draw_scatterers(pop: ScattererSettings, centre_xy, r_min: float, r_max: float,
                    rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """One population of scatterers in an annulus (module doc).

    Uniform in range and angle: density rho(r) = rho_ref r_ref / r, so a resolution cell (area ~ r) holds the
    same number of scatterers at every range; sigma_bar(r) = 10^(S/10) / rho(r) keeps the strength per m^2.

    Parameters
    ----------
    pop : ScattererSettings
        Density at 10 km (per km^2), strength (dB re 1 m^2/m^2), K shape.
    centre_xy : array_like (2,)
        Centre of the annulus (m).
    r_min, r_max : float
        Radii of the annulus (m).
    rng : numpy.random.Generator
        Stream (count, ranges, angles, textures, speckle in that order).

    Returns
    -------
    xy : ndarray (E, 2)
        Positions (m).
    sigma : ndarray (E,)
        Cross-sections (m^2), K-distributed.
    """
    rho_ref = pop.density_per_km2 / 1e6
    n_mean = rho_ref * REFERENCE_RANGE_M * 2.0 * np.pi * max(r_max - r_min, 0.0)
    n = int(rng.poisson(n_mean)) if n_mean > 0 else 0
    r = rng.uniform(r_min, r_max, n)
    a = rng.uniform(0.0, 2.0 * np.pi, n)
    sigma_bar = 10.0 ** (pop.strength_db / 10.0) * r / (rho_ref * REFERENCE_RANGE_M) if n else r
    sigma = sigma_bar * rng.gamma(pop.shape, 1.0 / pop.shape, n) * rng.exponential(1.0, n)
    xy = np.asarray(centre_xy, dtype=float) + np.stack([r * np.sin(a), r * np.cos(a)], axis=-1)
    return xy, sigma


def _echo_delays(scene: ActiveSceneSettings, travel_s: np.ndarray, cone_rad: np.ndarray) -> np.ndarray:
    """T_n = t + tau_n (E, N): travel time to each element (s)."""
    return travel_s[:, None] + plane_wave_delays_s(cone_rad, element_offsets(scene), scene.sound_speed_mps)


def _element_phasors(scene: ActiveSceneSettings, travel_s: np.ndarray, cone_rad: np.ndarray,
                     carrier_hz: float) -> np.ndarray:
    """exp(-2 pi i f_c T_n) (N, E) complex64, T_n = t + tau_n on the uniform line.

    tau_n = tau_0 + n kappa (kappa = d cos(theta) / c), so the phasors are the first one times the n-th power of
    exp(-2 pi i f_c kappa): N - 1 products instead of N complex exponentials (numpy's complex exp is slow), the
    phases reduced modulo one cycle in double precision first."""
    kappa = scene.spacing_m * np.cos(cone_rad) / scene.sound_speed_mps
    tau0 = -0.5 * (scene.sonar.elements - 1) * kappa
    first = 2.0 * np.pi * np.mod(carrier_hz * (travel_s + tau0), 1.0)
    step = 2.0 * np.pi * np.mod(carrier_hz * kappa, 1.0)
    out = np.empty((scene.sonar.elements, travel_s.size), dtype=np.complex64)
    out[0] = np.cos(first) - 1j * np.sin(first)
    b = (np.cos(step) - 1j * np.sin(step)).astype(np.complex64)
    for n in range(1, scene.sonar.elements):
        np.multiply(out[n - 1], b, out=out[n])
    return out


def _node_trains(k: np.ndarray, weights: np.ndarray, n_fft: int) -> np.ndarray:
    """Impulse trains (N, n_fft) complex64: weights (N, E) placed at samples k (E,) (summed where they meet)."""
    train = np.empty((weights.shape[0], n_fft), dtype=np.complex64)
    for n, w in enumerate(weights):
        train[n] = np.bincount(k, w.real, minlength=n_fft) + 1j * np.bincount(k, w.imag, minlength=n_fft)
    return train


def add_scatterers(spectrum: np.ndarray, scene: ActiveSceneSettings, travel_s: np.ndarray, cone_rad: np.ndarray,
                   amplitude: np.ndarray, doppler_hz: np.ndarray, waveform: Waveform) -> None:
    """Add the echoes of many scatterers to the element spectra (N, F) in place (module doc).

    Parameters
    ----------
    spectrum : numpy.ndarray
        (N, F) complex element spectra (FFT order), added to in place.
    scene : ActiveSceneSettings
        Sample rate, window, array and the Doppler node step of the reverberation.
    travel_s : numpy.ndarray
        (E,) travel times to the array centre (s); echoes outside the window are skipped.
    cone_rad : numpy.ndarray
        (E,) cone angles from the array's forward axis (rad, 0 = ahead).
    amplitude : numpy.ndarray
        (E,) complex amplitudes (Pa).
    doppler_hz : numpy.ndarray
        (E,) Doppler shifts (Hz).
    waveform : Waveform
        The pulse.

    Returns
    -------
    None
        ``spectrum`` is changed in place.
    """
    from scipy import fft as sfft

    n_fft = spectrum.shape[1]
    fs = scene.sample_rate_hz
    k = np.rint(travel_s * fs).astype(np.int64)
    keep = np.nonzero((k >= 0) & (k < scene.samples_per_ping))[0]
    if not keep.size:
        return
    step = scene.reverberation.doppler_step_hz
    node = np.floor(doppler_hz[keep] / step).astype(np.int64)
    order = keep[np.argsort(node, kind="stable")]
    node = np.sort(node, kind="stable")
    beta = (doppler_hz[order] / step - node).astype(np.float32)
    w = amplitude[order].astype(np.complex64) * _element_phasors(scene, travel_s[order], cone_rad[order],
                                                                 waveform.carrier_hz)
    k = k[order]
    t = np.arange(waveform.n_samples(fs)) / fs
    pulse = waveform.replica(fs)
    first, last = int(node[0]), int(node[-1])
    edges = np.searchsorted(node, np.arange(first, last + 2))  # echoes of node g: edges[g - first] .. next
    for g in range(first, last + 2):
        lo = slice(*edges[g - first: g - first + 2]) if g <= last else slice(0, 0)  # g is their lower node
        hi = slice(*edges[g - first - 1: g - first + 1]) if g > first else slice(0, 0)  # g is their upper node
        weights = np.concatenate([w[:, lo] * (1.0 - beta[lo]), w[:, hi] * beta[hi]], axis=1)
        train = _node_trains(np.concatenate([k[lo], k[hi]]), weights, n_fft)
        shifted = np.fft.fft(pulse * np.exp(2j * np.pi * g * step * t), n_fft).astype(np.complex64)
        spectrum += sfft.fft(train, axis=1, workers=1) * shifted


def add_target(spectrum: np.ndarray, scene: ActiveSceneSettings, delays_s: np.ndarray, amplitude: complex,
               doppler_hz: float, waveform: Waveform) -> None:
    """Add one echo exactly in the frequency domain (module doc), in place.

    Parameters
    ----------
    spectrum : ndarray (N, F)
        Element spectra (FFT order) to add to.
    scene : ActiveSceneSettings
        Sample rate and window.
    delays_s : ndarray (N,)
        Travel time to each element (s); an echo outside the window is skipped.
    amplitude : complex
        Complex amplitude (Pa).
    doppler_hz : float
        Doppler shift (Hz).
    waveform : Waveform
        The pulse.
    """
    n_fft = spectrum.shape[1]
    fs = scene.sample_rate_hz
    if not (float(np.min(delays_s)) >= 0.0 and float(np.max(delays_s)) < scene.samples_per_ping / fs):
        return
    f = np.fft.fftfreq(n_fft, 1.0 / fs)
    pulse = np.fft.fft(waveform.replica(fs, doppler_hz), n_fft)
    phase = 2.0 * np.pi * np.mod((waveform.carrier_hz + f)[None, :] * delays_s[:, None], 1.0)
    spectrum += (amplitude * pulse) * (np.cos(phase) - 1j * np.sin(phase))  # real cos/sin: numpy's complex exp is slow


def reverberation_echoes(scene: ActiveSceneSettings, plat: Platforms, k: int, tl: TransmissionLoss,
                         rng: np.random.Generator):
    """(travel times (E,) s, cone angles (E,) rad, complex amplitudes (E,) Pa, Dopplers (E,) Hz) of ping ``k``'s
    fresh scatterers.

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene (boundary and volume populations, source level, carrier, sound speed).
    plat : Platforms
        The platforms at the ping times.
    k : int
        The ping (0-based row of ``plat``).
    tl : TransmissionLoss
        The scene's one-way transmission loss.
    rng : numpy.random.Generator
        Stream of the scatterers and their phases.

    Returns
    -------
    tuple of numpy.ndarray
        Travel times (s), cone angles from the array's forward axis (rad), complex amplitudes (Pa) and Doppler
        shifts (Hz), each (E,), boundary population first; the scatterers are still.
    """
    rv = scene.reverberation
    travel, cone, amps, dops = [], [], [], []
    for pop in (rv.boundary, rv.volume):
        xy, sigma = draw_scatterers(pop, plat.rx_xy[k], rv.min_range_m, max_path_range_m(scene), rng)
        g = echo_geometry(xy, np.zeros_like(xy), plat.tx_xy[k], plat.tx_velocity[k], plat.rx_xy[k],
                          plat.rx_velocity[k], plat.array_heading_rad[k], scene.waveform.carrier_hz,
                          scene.sound_speed_mps)
        level = scene.sonar.source_level_db - tl.tx(g.tx_range_m, pop.depth_m) - tl.rx(g.rx_range_m, pop.depth_m)
        phase = np.exp(2j * np.pi * rng.uniform(0.0, 1.0, sigma.size))
        amps.append(np.sqrt(UPA2_PA2 * 10.0 ** (level / 10.0) * sigma) * phase)
        travel.append(g.travel_time_s)
        cone.append(g.cone_rad)
        dops.append(g.doppler_hz)
    return np.concatenate(travel), np.concatenate(cone), np.concatenate(amps), np.concatenate(dops)


def target_amplitudes(scene: ActiveSceneSettings, echo_level_db: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Complex amplitudes (Pa) of the target echoes of a ping: Swerling 1 or steady (module doc).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene (``target_fluctuation``).
    echo_level_db : numpy.ndarray
        (n,) echo levels (dB re 1 uPa).
    rng : numpy.random.Generator
        Stream of the amplitudes.

    Returns
    -------
    numpy.ndarray
        (n,) complex amplitudes (Pa): circular complex Gaussian with mean-square the echo level (swerling1), or
        that rms with a uniform random phase.
    """
    n = len(echo_level_db)
    g = rng.standard_normal((n, 2))
    rms = np.sqrt(UPA2_PA2 * 10.0 ** (np.asarray(echo_level_db, dtype=float) / 10.0))
    if scene.target_fluctuation == "swerling1":
        return rms * (g[:, 0] + 1j * g[:, 1]) / np.sqrt(2.0)
    return rms * np.exp(1j * np.arctan2(g[:, 1], g[:, 0]))


def ping_samples(scene: ActiveSceneSettings, plat: Platforms, k: int, tl: TransmissionLoss,
                 rng: np.random.Generator) -> np.ndarray:
    """The samples of ping ``k`` (0-based) at every element: (N, T f_s) complex64 in Pa (module doc).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene.
    plat : Platforms
        Platforms at the ping times (sim/active_scene.py ``ping_geometry``).
    k : int
        The ping's index into ``plat``.
    tl : TransmissionLoss
        The scene's transmission loss (``transmission_loss_model``).
    rng : numpy.random.Generator
        The ping's own stream (scatterers, then target fluctuations, then noise, in that order).

    Returns
    -------
    ndarray (N, M), complex64
        Element 0 is the front; sample 0 is the transmit time.
    """
    w = scene.waveform.waveform()
    fs, m, n_el = scene.sample_rate_hz, scene.samples_per_ping, scene.sonar.elements
    n_fft = fft_length(m + w.n_samples(fs) + 1)
    spectrum = np.zeros((n_el, n_fft), dtype=np.complex64)
    add_scatterers(spectrum, scene, *reverberation_echoes(scene, plat, k, tl, rng), w)
    levels, geoms = [], []
    for tgt in scene.targets:
        xy, vel = target_motion(tgt, plat.time_s[k])
        g = echo_geometry(xy[0], vel[0], plat.tx_xy[k], plat.tx_velocity[k], plat.rx_xy[k], plat.rx_velocity[k],
                          plat.array_heading_rad[k], w.carrier_hz, scene.sound_speed_mps)
        levels.append(scene.sonar.source_level_db - tl.tx(g.tx_range_m, tgt.depth_m) - tl.rx(g.rx_range_m, tgt.depth_m)
                      + tgt.target_strength_db)
        geoms.append(g)
    amplitudes = target_amplitudes(scene, np.asarray(levels, dtype=float), rng)
    for a, g in zip(amplitudes, geoms, strict=True):
        t_n = _echo_delays(scene, np.atleast_1d(g.travel_time_s), np.atleast_1d(g.cone_rad))[0]
        add_target(spectrum, scene, t_n, complex(a), float(g.doppler_hz), w)
    x = np.fft.ifft(spectrum, axis=1)[:, :m]
    sigma = np.sqrt(UPA2_PA2 * 10.0 ** (scene.noise_level_db / 10.0) * fs / 2.0)
    noise = rng.standard_normal((n_el, m, 2)) * sigma
    return (x + noise[..., 0] + 1j * noise[..., 1]).astype(np.complex64)
