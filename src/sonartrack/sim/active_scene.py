"""An active towed-array scene: settings, platforms, each target's bistatic truth per ping, levels.

Geometry (paper P4, Fig. 1; DIGEST P4). The ownship (a straight leg, one turn, a straight leg) tows the
source Tx ``source_tow_m`` and the receiving line array Rx ``array_tow_m`` behind it along its own track:
each towed body sits where the ship was L / v seconds earlier, with the ship's heading then (the array's
axis heading phi lags the ship's through the turn). A ping is transmitted every ``ping_interval_s`` from
t = 0; the geometry of a ping is frozen at its transmit time (the stop-and-hop approximation of P4's
measurement model: the target and the platforms move < 100 m during the listening window). For a target
at p with velocity v, Tx at p_T (velocity v_T), Rx at p_R (velocity v_R), u_T and u_R the unit vectors from
Tx and Rx towards the target:

    bistatic range (total path)   r_B = |p - p_T| + |p - p_R|,     travel time t = r_B / c
    bistatic range rate           rdot_B = u_T . (v - v_T) + u_R . (v - v_R)
    Doppler                       f_d = -f_c rdot_B / c            (first order in v / c)
    bearing at Rx                 b = atan2(u_R,x, u_R,y);  cone angle theta = arccos(u_R . a), a = [sin phi,
                                  cos phi] the array's axis (0 = ahead); side = port or starboard of the axis

Levels (active sonar equation, Urick, Principles of Underwater Sound, ch. 2; dB re 1 uPa and 1 m):

    echo level      RL = SL - TL(r_T) - TL(r_R) + TS
    echo SNR        snr = RL - NL + 10 log10(tau) + 10 log10(N)   (matched-filter output on the beam's axis,
                                                                   against the ambient noise alone: the input
                                                                   SNR rho of paper P1's detector)

TL (sim/active_tl.py) is ``spherical`` (20 log10 r + Thorp absorption at the carrier) or ``ram`` (RAM in the shipped
environment, acoustics/transmission_loss.py, Tx leg from the source depth, Rx leg from the array depth by
reciprocity, both to the target's depth, averaged over ``tl_average_m``). Measured: one RAM field at 1.5 kHz
out to 25 km in the 193 m deep south-summer sea takes 6.6 s (then cached by the caller's store), so both
are offered; the default is spherical, whose levels the default targets were chosen with.

The default scene (one hour, 120 pings): the ownship steams north at 5 kn (P4's 2.5 m/s) and turns 60 deg
to port at P4's 0.08 deg/s from t = 1500 s; the source is 300 m and the array (16 elements, half a
wavelength apart at the carrier) 450 m astern (P4); an LFM of 1 s sweeping 100 Hz around 1.5 kHz at
215 dB; ambient noise 60 dB re 1 uPa^2/Hz; reverberation from random seabed and volume scatterers
(sim/active_signals.py); the targets of the shipped table ``data/scenes/active.toml``.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from functools import cache
from typing import Literal

import numpy as np
from pydantic import model_validator

from sonartrack.acoustics.matched_filter import Waveform, range_rate_to_doppler
from sonartrack.core.angles import wrap_angle
from sonartrack.core.memory import MEMORY_LIMIT_BYTES, over_limit
from sonartrack.core.settings import Settings, setting
from sonartrack.core.units import KNOT_MPS
from sonartrack.sim.active_tl import (  # noqa: F401  (re-exported: the scene's public names stay here)
    RAM_RANGE_STEP_M,
    TL_GRID_STEP_M,
    TransmissionLoss,
    max_path_range_m,
    transmission_loss_model,
)
from sonartrack.sim.platforms import ManeuveringTrack
from sonartrack.sim.scene import (
    MAX_DEPTH_M,
    MAX_DURATION_S,
    MAX_NOISE_LEVEL_DB,
    MAX_POSITION_M,
    MIN_LEVEL_DB,
    OwnshipSettings,
    check_environment_and_names,
    scenes_dir,
)

#: plausible bounds of an active scene's values (beyond them a unit slip or a typo, not a scene; 1e300 dB of target
#: strength overflows the echo's amplitude into NaN samples): a target strength in dB re 1 m^2 (a large ship or an
#: iceberg is +40 or so, -100 is a silent target), a tow behind the ship, a scattering strength in dB re 1 m^2/m^2
MIN_TARGET_STRENGTH_DB, MAX_TARGET_STRENGTH_DB = MIN_LEVEL_DB, 60.0
MAX_TOW_M = 10_000.0
MIN_SCATTERING_STRENGTH_DB = -150.0
#: bytes of working memory per reverberation scatterer of a ping beyond 17 per element (sim/active_signals.py: its
#: position, geometry, level and weights; measured with tracemalloc: 340 B at 16 elements, 1123 B at 64)
SCATTERER_BYTES, SCATTERER_BYTES_PER_ELEMENT = 100.0, 17.0


class ActiveOwnshipSettings(OwnshipSettings):
    """The ownship of an active scene: P4's slow ship and slow turn (sim/platforms.py ManeuveringTrack)."""

    speed_kn: float = setting(5.0, "speed through the water (5 kn = P4's 2.5 m/s)", unit="kn", gt=0, le=40)
    turn_deg: float = setting(-60.0, "course change (negative: to port); 0 for none; it makes the left/right side "
                                     "of the line array observable", unit="deg", ge=-180, le=180)
    turn_rate_deg_s: float = setting(0.08, "rate of turn (P4's 0.08 deg/s)", unit="deg/s", gt=0, le=10)
    turn_start_s: float | None = setting(1500.0, "time the turn starts (P4: 1500 s; 'off': centred on the "
                                                 "middle of the scene)", unit="s", ge=0, le=MAX_DURATION_S)


class SonarSettings(Settings):
    """The towed source and the towed receiving line array (P4's Fig. 1)."""

    source_level_db: float = setting(215.0, "source level SL at 1 m", unit="dB re 1 uPa", gt=100, le=260)
    source_tow_m: float = setting(300.0, "distance of the source behind the ship along its track (P4)", unit="m",
                                  ge=0, le=MAX_TOW_M)
    array_tow_m: float = setting(450.0, "distance of the array centre behind the ship along its track (P4)",
                                 unit="m", ge=0, le=MAX_TOW_M)
    source_depth_m: float = setting(50.0, "source depth (transmission loss)", unit="m", gt=0, le=MAX_DEPTH_M)
    array_depth_m: float = setting(50.0, "array depth (transmission loss)", unit="m", gt=0, le=MAX_DEPTH_M)
    elements: int = setting(16, "hydrophones N of the line array", unit="1", ge=2, le=256)
    spacing_m: float | None = setting(None, "element spacing d (not set: half a wavelength at the carrier, "
                                            "c / (2 f_c))", unit="m", gt=0)


class WaveformSettings(Settings):
    """The transmitted pulse (acoustics/matched_filter.py)."""

    kind: Literal["lfm", "cw"] = setting("lfm", "lfm = linear FM sweep (pulse compression), cw = a tone "
                                                "(Doppler filter bank, paper P1)", unit="")
    duration_s: float = setting(1.0, "pulse length tau", unit="s", gt=0)
    carrier_hz: float = setting(1500.0, "carrier f_c (the LFM's centre frequency)", unit="Hz", gt=0)
    bandwidth_hz: float = setting(100.0, "LFM swept band B, centred on the carrier (ignored for a CW)", unit="Hz",
                                  ge=0)

    def waveform(self) -> Waveform:
        """The library's :class:`~sonartrack.acoustics.matched_filter.Waveform` (its checks run here).

        Returns
        -------
        Waveform
            Kind, pulse length (s), carrier (Hz) and bandwidth (Hz; 0 for a CW).
        """
        return Waveform(self.kind, self.duration_s, self.carrier_hz, self.bandwidth_hz if self.kind == "lfm" else 0.0)


class ScattererSettings(Settings):
    """One population of random point scatterers (sim/active_signals.py)."""

    density_per_km2: float = setting(..., "mean number of scatterers per square km at 10 km from the array, "
                                          "falling as 1 / range (Poisson, fresh each ping)", unit="1/km^2", ge=0)
    strength_db: float = setting(..., "scattering strength: total mean cross-section per square metre of sea",
                                 unit="dB re 1 m^2/m^2", ge=MIN_SCATTERING_STRENGTH_DB, le=0)
    shape: float = setting(..., "K-distribution shape nu of a scatterer's cross-section (small: spiky, heavy "
                                "tail; large: Rayleigh)", unit="1", gt=0)
    depth_m: float = setting(..., "depth of the scatterers (transmission loss with propagation = ram)", unit="m",
                             gt=0, le=MAX_DEPTH_M)


def _boundary() -> ScattererSettings:
    return ScattererSettings(density_per_km2=100.0, strength_db=-50.0, shape=1.5, depth_m=150.0)


def _volume() -> ScattererSettings:
    return ScattererSettings(density_per_km2=0.5, strength_db=-65.0, shape=0.2, depth_m=80.0)


class ReverberationSettings(Settings):
    """Reverberation: seabed and volume point scatterers whose echoes give the heavy-tailed background."""

    boundary: ScattererSettings = setting(default_factory=_boundary, doc="seabed scatterers: dense, moderately "
                                          "heavy-tailed (nu = 1)")
    volume: ScattererSettings = setting(default_factory=_volume, doc="volume scatterers (fish schools, debris): "
                                        "sparse and spiky (nu = 0.3), the discrete clutter")
    min_range_m: float = setting(200.0, "no scatterers nearer than this to the array (inside the blanked near zone)",
                                 unit="m", ge=0, le=MAX_POSITION_M)
    doppler_step_hz: float = setting(0.25, "synthesis: scatterer Dopplers are split between nodes this far apart",
                                     unit="Hz", gt=0, le=2)


class TargetSettings(Settings):
    """A point target at constant velocity."""

    name: str = setting(..., "name (the target column of truth.csv)", unit="")
    x_m: float = setting(..., "position east at t = 0", unit="m", ge=-MAX_POSITION_M, le=MAX_POSITION_M)
    y_m: float = setting(..., "position north at t = 0", unit="m", ge=-MAX_POSITION_M, le=MAX_POSITION_M)
    course_deg: float = setting(..., "course, clockwise from north", unit="deg", ge=-360, le=360)
    speed_kn: float = setting(..., "speed", unit="kn", ge=0, le=60)
    depth_m: float = setting(100.0, "depth (transmission loss with propagation = ram)", unit="m", gt=0,
                             le=MAX_DEPTH_M)
    target_strength_db: float = setting(..., "target strength TS", unit="dB re 1 m^2", ge=MIN_TARGET_STRENGTH_DB,
                                        le=MAX_TARGET_STRENGTH_DB)
    turn_start_s: float | None = setting(None, "time a course change starts (not set: constant velocity)", unit="s",
                                         ge=0, le=MAX_DURATION_S)
    turn_deg: float = setting(0.0, "course change from turn_start_s (negative: to port)", unit="deg", ge=-360,
                              le=360)
    turn_rate_deg_s: float = setting(1.0, "rate of that turn", unit="deg/s", gt=0, le=10)


@cache
def _shipped_targets() -> tuple[dict, ...]:
    return tuple(tomllib.loads((scenes_dir() / "active.toml").read_text()).get("targets", []))


def _default_targets() -> list[TargetSettings]:
    return [TargetSettings(**t) for t in _shipped_targets()]


class ActiveSceneSettings(Settings):
    """An active towed-array scene and its pings (module doc for the default)."""

    duration_s: float = setting(3600.0, "length of the scene: pings at 0, T, 2T, ... before it ends", unit="s",
                                gt=0, le=86_400)
    ping_interval_s: float = setting(30.0, "time T between pings (P4: 30 s); each ping listens for T", unit="s",
                                     gt=0, le=600)
    sample_rate_hz: float = setting(200.0, "complex-baseband sample rate f_s (must hold the band and the Dopplers)",
                                    unit="Hz", gt=0, le=100_000)
    sound_speed_mps: float = setting(1500.0, "sound speed c (travel times, Doppler, plane-wave delays)", unit="m/s",
                                     gt=1300, lt=1700)
    noise_level_db: float = setting(60.0, "ambient noise spectral level NL, independent between elements",
                                    unit="dB re 1 uPa^2/Hz", ge=MIN_LEVEL_DB, le=MAX_NOISE_LEVEL_DB)
    propagation: Literal["spherical", "ram"] = setting(
        "spherical", "transmission loss: spherical = 20 log10 r + Thorp absorption; ram = RAM in the environment, "
                     "averaged over tl_average_m", unit="")
    environment: str = setting("south-summer", "shipped environment of the RAM transmission loss (sonartrack tl "
                                               "--list)", unit="")
    tl_average_m: float = setting(1000.0, "range average of the RAM transmission loss", unit="m", ge=0, le=100_000)
    target_fluctuation: Literal["swerling1", "steady"] = setting(
        "swerling1", "echo amplitude per ping: swerling1 = complex Gaussian (exponential power, paper P1's "
                     "model), steady = fixed level with a random phase", unit="")
    seed: int = setting(1, "master seed: ping k draws from child k", unit="1", ge=0)
    ownship: ActiveOwnshipSettings = setting(default_factory=ActiveOwnshipSettings, doc="the ownship")
    sonar: SonarSettings = setting(default_factory=SonarSettings, doc="the towed source and line array")
    waveform: WaveformSettings = setting(default_factory=WaveformSettings, doc="the transmitted pulse")
    reverberation: ReverberationSettings = setting(default_factory=ReverberationSettings, doc="the scatterers")
    targets: list[TargetSettings] = setting(default_factory=_default_targets, doc="the targets ([[targets]] tables; "
                                            "empty for a reverberation-only scene)", unit="")

    @model_validator(mode="after")
    def _consistent(self):
        w = self.waveform
        if w.kind == "lfm" and w.bandwidth_hz <= 0:
            raise ValueError("waveform: an LFM needs bandwidth_hz > 0 (a zero-bandwidth LFM is a CW: kind = 'cw')")
        if w.duration_s >= self.ping_interval_s:
            raise ValueError(f"waveform: the pulse ({w.duration_s:g} s) must be shorter than the ping interval "
                             f"({self.ping_interval_s:g} s)")
        if self.occupied_band_hz > self.sample_rate_hz:
            raise ValueError(f"sample_rate_hz {self.sample_rate_hz:g} does not hold the pulse's band with its "
                             f"Dopplers ({self.occupied_band_hz:.0f} Hz): raise it")
        if w.duration_s * self.sample_rate_hz < 4:
            raise ValueError("the pulse holds fewer than 4 samples: raise sample_rate_hz or duration_s")
        check_environment_and_names(self.environment, [t.name for t in self.targets], "target")
        over = over_limit(self.memory_needs())  # refused before anything is allocated, the largest named
        if over is not None:
            need, what, fix = over[1]
            raise ValueError(f"{what} would take {need / 1e9:.3g} GB of memory, more than the "
                             f"{MEMORY_LIMIT_BYTES / 1e9:.3g} GB the simulator plans for: {fix}")
        return self

    def memory_needs(self) -> list[tuple[float, str, str]]:
        """A ping's largest working arrays (sim/active_signals.py): bytes, what they hold and sizes them, the fix.

        The reverberation's scatterers of one ping, E = sum of density x 10 km x 2 pi x (r_max - min_range_m) (the
        Poisson mean of :func:`~sonartrack.sim.active_signals.draw_scatterers`), at ``SCATTERER_BYTES`` +
        ``SCATTERER_BYTES_PER_ELEMENT`` N each; the ping's element spectra, samples and noise, 64 N F bytes
        (F >= the FFT length of a listening window and a pulse: the next power of two).

        Returns
        -------
        list of (float, str, str)
            Bytes (estimate), what needs them (with the settings that size it), and how to make it smaller.
        """
        rv, n, m = self.reverberation, self.sonar.elements, self.samples_per_ping
        width_m = max(max_path_range_m(self) - rv.min_range_m, 0.0)
        per_ping = sum(p.density_per_km2 / 1e6 * 1e4 * 2.0 * np.pi * width_m for p in (rv.boundary, rv.volume))
        n_fft = 2 ** int(np.ceil(np.log2(m + self.waveform.duration_s * self.sample_rate_hz + 2)))  # >= fft_length
        return [(per_ping * (SCATTERER_BYTES + SCATTERER_BYTES_PER_ELEMENT * n), f"one ping's reverberation "
                 f"({per_ping:.3g} scatterers of reverberation.boundary and .volume density_per_km2 out to "
                 f"{max_path_range_m(self) / 1e3:.3g} km)",
                 "lower the density_per_km2 (per square km, stated at 10 km)"),
                (64.0 * n * n_fft, f"one ping's samples ({n} elements x {m} samples of ping_interval_s x "
                 f"sample_rate_hz)", "lower sample_rate_hz or ping_interval_s, or use fewer sonar.elements")]

    @property
    def occupied_band_hz(self) -> float:
        """The baseband width the pulse and the Dopplers of 30 m/s of bistatic range rate need (Hz)."""
        w = self.waveform
        band = w.bandwidth_hz if w.kind == "lfm" else 4.0 / w.duration_s
        return band + 2.0 * 30.0 * w.carrier_hz / self.sound_speed_mps

    @property
    def spacing_m(self) -> float:
        """Element spacing d: as given, else half a wavelength at the carrier."""
        s = self.sonar
        return s.spacing_m if s.spacing_m is not None else self.sound_speed_mps / (2.0 * self.waveform.carrier_hz)

    @property
    def ping_times_s(self) -> np.ndarray:
        """Transmit times 0, T, 2T, ... < duration (s)."""
        return np.arange(0.0, self.duration_s, self.ping_interval_s)

    @property
    def samples_per_ping(self) -> int:
        """Samples of one ping's listening window (T f_s)."""
        return int(round(self.ping_interval_s * self.sample_rate_hz))


@dataclass(frozen=True, slots=True)
class Platforms:
    """Ownship, source and array at times (T,): positions (T, 2), velocities (T, 2), headings (T,) in rad."""

    time_s: np.ndarray
    own_xy: np.ndarray
    own_heading_rad: np.ndarray
    tx_xy: np.ndarray
    tx_velocity: np.ndarray
    rx_xy: np.ndarray
    rx_velocity: np.ndarray
    array_heading_rad: np.ndarray


@dataclass(frozen=True, slots=True)
class EchoGeometry:
    """Bistatic quantities of points seen by one ping (arrays (...,)): path lengths r_T, r_R, r_B (m), travel
    time (s), range rate (m/s), Doppler (Hz), bearing at Rx (rad), cone angle (rad), unit vector from Rx (..., 2)."""

    tx_range_m: np.ndarray
    rx_range_m: np.ndarray
    bistatic_range_m: np.ndarray
    travel_time_s: np.ndarray
    range_rate_mps: np.ndarray
    doppler_hz: np.ndarray
    bearing_rad: np.ndarray
    cone_rad: np.ndarray


def ownship_track(scene: ActiveSceneSettings) -> ManeuveringTrack:
    """The ownship's track in ``scene``: constant speed (m/s) and start heading (rad, clockwise from north), with at
    most one turn, starting at ``ownship.turn_start_s`` or centred on the scene (``scene.ownship``: start x east /
    y north in m, speed in kn, course in deg clockwise from north, turn in deg, negative to port, at a rate in
    deg/s)."""
    o = scene.ownship
    turns = ()
    if o.turn_deg != 0:
        t0 = o.turn_start_s if o.turn_start_s is not None else \
            max(0.5 * scene.duration_s - 0.5 * abs(o.turn_deg) / o.turn_rate_deg_s, 0.0)
        rate = np.sign(o.turn_deg) * np.deg2rad(o.turn_rate_deg_s)
        turns = ((t0, t0 + abs(o.turn_deg) / o.turn_rate_deg_s, float(rate)),)
    return ManeuveringTrack(o.x_m, o.y_m, o.speed_kn * KNOT_MPS, float(np.deg2rad(o.course_deg)), turns)


def platforms(scene: ActiveSceneSettings, t_s) -> Platforms:
    """Ownship, source and array centre at times ``t_s`` (module doc: towed along the ship's own track).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene.
    t_s : float or array_like (T,)
        Times (s).

    Returns
    -------
    Platforms
        Positions (m), velocities (m/s) and headings (rad, clockwise from north).
    """
    t = np.atleast_1d(np.asarray(t_s, dtype=float))
    track = ownship_track(scene)
    own_xy, _, own_h = track.state(t)
    v = track.speed_mps
    tx_xy, tx_v, _ = track.state(t - scene.sonar.source_tow_m / v)
    rx_xy, rx_v, rx_h = track.state(t - scene.sonar.array_tow_m / v)
    return Platforms(t, own_xy, wrap_angle(own_h), tx_xy, tx_v, rx_xy, rx_v, wrap_angle(rx_h))


def echo_geometry(points_xy, points_velocity, tx_xy, tx_velocity, rx_xy, rx_velocity, array_heading_rad,
                  carrier_hz: float, sound_speed_mps: float) -> EchoGeometry:
    """Bistatic range, rate, Doppler, bearing and cone angle of points (module doc).

    Parameters
    ----------
    points_xy, points_velocity : array_like (..., 2)
        Positions (m) and velocities (m/s) of the echoing points.
    tx_xy, tx_velocity, rx_xy, rx_velocity : array_like (..., 2)
        Source and array centre positions (m) and velocities (m/s), broadcast against the points.
    array_heading_rad : float or array_like (...,)
        Heading of the array's axis (rad, clockwise from north).
    carrier_hz, sound_speed_mps : float
        Carrier (Hz) and sound speed (m/s).

    Returns
    -------
    EchoGeometry
        Path lengths (m), travel time (s), range rate (m/s), Doppler (Hz), bearing and cone angle (rad).
    """
    p = np.asarray(points_xy, dtype=float)
    v = np.asarray(points_velocity, dtype=float)
    d_t = p - tx_xy
    d_r = p - rx_xy
    r_t = np.maximum(np.hypot(d_t[..., 0], d_t[..., 1]), 1e-9)
    r_r = np.maximum(np.hypot(d_r[..., 0], d_r[..., 1]), 1e-9)
    u_t = d_t / r_t[..., None]
    u_r = d_r / r_r[..., None]
    rate = np.sum(u_t * (v - tx_velocity), axis=-1) + np.sum(u_r * (v - rx_velocity), axis=-1)
    axis = np.stack([np.sin(array_heading_rad), np.cos(array_heading_rad)], axis=-1)
    cos_cone = np.clip(np.sum(u_r * axis, axis=-1), -1.0, 1.0)
    r_b = r_t + r_r
    return EchoGeometry(r_t, r_r, r_b, r_b / sound_speed_mps, rate,
                        range_rate_to_doppler(rate, carrier_hz, sound_speed_mps),
                        np.arctan2(u_r[..., 0], u_r[..., 1]), np.arccos(cos_cone))


def target_motion(target: TargetSettings, t_s) -> tuple[np.ndarray, np.ndarray]:
    """Positions (T, 2) and velocities (T, 2) of a target at times ``t_s``: constant velocity, or with one
    constant-rate course change (sim/platforms.py :class:`ManeuveringTrack`, in closed form).

    Parameters
    ----------
    target : TargetSettings
        The target (start x east / y north in m, speed in kn, course in deg clockwise from north, optional turn).
    t_s : float or array (T,)
        Times (s).

    Returns
    -------
    positions : numpy.ndarray
        (T, 2) [x east, y north] (m).
    velocities : numpy.ndarray
        (T, 2) [east, north] (m/s).
    """
    course = np.deg2rad(target.course_deg)
    v = target.speed_kn * KNOT_MPS * np.array([np.sin(course), np.cos(course)])
    t = np.atleast_1d(np.asarray(t_s, dtype=float))
    if target.turn_start_s is None or target.turn_deg == 0:
        return np.array([target.x_m, target.y_m]) + t[:, None] * v, np.broadcast_to(v, (t.size, 2)).copy()
    a = float(target.turn_start_s)
    turn = ((a, a + abs(target.turn_deg) / target.turn_rate_deg_s,
             float(np.sign(target.turn_deg) * np.deg2rad(target.turn_rate_deg_s))),)
    st = ManeuveringTrack(target.x_m, target.y_m, target.speed_kn * KNOT_MPS, float(course), turn).state(t)
    return np.asarray(st[0], float).reshape(-1, 2), np.asarray(st[1], float).reshape(-1, 2)


def ping_geometry(scene: ActiveSceneSettings) -> Platforms:
    """The platforms at every ping's transmit time of the ``scene``.

    Returns
    -------
    Platforms
        :func:`platforms` at ``scene.ping_times_s``.
    """
    return platforms(scene, scene.ping_times_s)


def target_truth(scene: ActiveSceneSettings, tl: TransmissionLoss, plat: Platforms | None = None) -> dict:
    """The truth table: a row per ping and target (ping-major) with every bistatic quantity (module doc).

    Columns: ping (1-based), time_s, target, x_m, y_m, vx_mps, vy_mps, bistatic_range_m (r_B), tx_range_m,
    rx_range_m, travel_time_s, lfm_delay_s (where an LFM compresses: travel time - f_d tau / B), range_rate_mps
    (rdot_B), doppler_hz, bearing_deg (at the array centre, clockwise from north, 0..360), cone_deg, side,
    echo_level_db (RL), snr_db, in_window (the echo starts inside the listening window), in_blast (it arrives
    within a pulse length of the direct blast, baseline / c).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene.
    tl : TransmissionLoss
        Its transmission loss (:func:`transmission_loss_model`).
    plat : Platforms, optional
        The platforms at the ping times (computed if not given).

    Returns
    -------
    dict of ndarray
        The columns above, each (pings x targets,), SI units except the degrees named so.
    """
    plat = ping_geometry(scene) if plat is None else plat
    w = scene.waveform
    n_t, n_p = len(scene.targets), plat.time_s.size
    cols: dict[str, list] = {}
    for tgt in scene.targets:
        xy, vel = target_motion(tgt, plat.time_s)
        g = echo_geometry(xy, vel, plat.tx_xy, plat.tx_velocity, plat.rx_xy, plat.rx_velocity,
                          plat.array_heading_rad, w.carrier_hz, scene.sound_speed_mps)
        rl = scene.sonar.source_level_db - tl.tx(g.tx_range_m, tgt.depth_m) - tl.rx(g.rx_range_m, tgt.depth_m) \
            + tgt.target_strength_db
        side = np.where(np.sin(g.bearing_rad - plat.array_heading_rad) >= 0.0, "starboard", "port")
        baseline_s = np.hypot(*(plat.tx_xy - plat.rx_xy).T) / scene.sound_speed_mps
        shift = -g.doppler_hz * w.duration_s / w.bandwidth_hz if w.kind == "lfm" else 0.0
        row = {"ping": np.arange(1, n_p + 1), "time_s": plat.time_s, "target": np.full(n_p, tgt.name, dtype=object),
               "x_m": xy[:, 0], "y_m": xy[:, 1], "vx_mps": vel[:, 0], "vy_mps": vel[:, 1],
               "bistatic_range_m": g.bistatic_range_m, "tx_range_m": g.tx_range_m, "rx_range_m": g.rx_range_m,
               "travel_time_s": g.travel_time_s, "lfm_delay_s": g.travel_time_s + shift,
               "range_rate_mps": g.range_rate_mps, "doppler_hz": g.doppler_hz,
               "bearing_deg": np.rad2deg(g.bearing_rad) % 360.0, "cone_deg": np.rad2deg(g.cone_rad), "side": side,
               "echo_level_db": rl, "snr_db": echo_snr_db(scene, rl),
               "in_window": g.travel_time_s < scene.ping_interval_s,
               "in_blast": g.travel_time_s < baseline_s + w.duration_s}
        for k, v in row.items():
            cols.setdefault(k, []).append(np.asarray(v))
    if not n_t:
        return {k: np.zeros(0) for k in TRUTH_COLUMNS}
    # ping-major rows: (target, ping) -> (ping, target)
    return {k: np.stack(v, axis=1).reshape(-1) for k, v in cols.items()}


#: the truth table's columns, in order
TRUTH_COLUMNS = ("ping", "time_s", "target", "x_m", "y_m", "vx_mps", "vy_mps", "bistatic_range_m", "tx_range_m",
                 "rx_range_m", "travel_time_s", "lfm_delay_s", "range_rate_mps", "doppler_hz", "bearing_deg",
                 "cone_deg", "side", "echo_level_db", "snr_db", "in_window", "in_blast")


def echo_snr_db(scene: ActiveSceneSettings, echo_level_db):
    """snr = RL - NL + 10 log10(tau) + 10 log10(N): matched-filter output SNR on the beam's axis (module doc).

    Parameters
    ----------
    scene : ActiveSceneSettings
        The scene (noise spectral level NL, pulse length tau in s, N elements).
    echo_level_db : float or array
        Echo level RL at the array (dB re 1 uPa).

    Returns
    -------
    numpy.ndarray
        SNR (dB), shaped as ``echo_level_db``.
    """
    return (np.asarray(echo_level_db, dtype=float) - scene.noise_level_db
            + 10.0 * np.log10(scene.waveform.duration_s * scene.sonar.elements))


def nav_columns(plat: Platforms) -> dict[str, np.ndarray]:
    """The navigation table: ownship, source, array centre and array axis heading (headings in deg 0..360).

    Parameters
    ----------
    plat : Platforms
        The platforms at the navigation times (positions m, headings rad clockwise from north).

    Returns
    -------
    dict of numpy.ndarray
        The columns of nav.csv (systems/active/scene_files.py ``NAV_COLUMNS``): positions x east, y north (m),
        headings (deg clockwise from north, 0..360).
    """
    return {"time_s": plat.time_s, "x_m": plat.own_xy[:, 0], "y_m": plat.own_xy[:, 1],
            "heading_deg": np.rad2deg(plat.own_heading_rad) % 360.0,
            "source_x_m": plat.tx_xy[:, 0], "source_y_m": plat.tx_xy[:, 1],
            "array_x_m": plat.rx_xy[:, 0], "array_y_m": plat.rx_xy[:, 1],
            "array_heading_deg": np.rad2deg(plat.array_heading_rad) % 360.0}
