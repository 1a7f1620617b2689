"""The passive scene's settings: ownship, towed line array, ships, noise, propagation, sample inputs.

Declared once (core/settings.py); the same declarations serve the Python API, the scene TOML file of
``sonartrack simulate --scene my.toml`` (ships as a ``[[ships]]`` array of tables) and
``--print-config``. Units at this edge: positions in m, speeds in knots, courses and headings in degrees
clockwise from north, levels in dB (source levels at 1 m; spectral levels per Hz).

The default scene (20 minutes, four ships; the ship list is the shipped table
``sonartrack/data/scenes/passive.toml``): the ownship steams north at 6 kn towing a 16-element line
array 200 m astern (half-wavelength spacing at 300 Hz: 2.5 m), and turns 45 deg to port at 0.5 deg/s
half-way through. A merchant and a trawler on the starboard side cross in bearing (and in cone angle)
at t = 360 s (the P0 situation); a quiet submarine to port is the weak target; a tanker far to port
is a loud distant contact. Ambient noise 73 dB re 1 uPa^2/Hz (heavy shipping), band 50-1000 Hz.
"""

from __future__ import annotations

import tomllib
from functools import cache
from pathlib import Path
from typing import Literal

from pydantic import model_validator

from sonartrack.acoustics.environment import list_environments
from sonartrack.core.settings import Settings, setting


class OwnshipSettings(Settings):
    """The ownship: a straight leg, one course change, a straight leg (sim/platforms.py ManeuveringTrack)."""

    x_m: float = setting(0.0, "start position east", unit="m")
    y_m: float = setting(0.0, "start position north", unit="m")
    speed_kn: float = setting(6.0, "speed through the water", unit="kn", gt=0, le=40)
    course_deg: float = setting(0.0, "initial course, clockwise from north", unit="deg")
    turn_deg: float = setting(-45.0, "course change (negative: to port); 0 for none; it makes range and the "
                                     "left/right side observable", unit="deg", ge=-180, le=180)
    turn_rate_deg_s: float = setting(0.5, "rate of turn", unit="deg/s", gt=0)
    turn_start_s: float | None = setting(None, "time the turn starts (not set: the turn is centred on the middle "
                                               "of the recording)", unit="s", ge=0)


class ArraySettings(Settings):
    """The towed uniform line array; element 1 is the front (nearest the ship), element N the tail."""

    elements: int = setting(16, "number of hydrophones N", unit="1", ge=2)
    design_hz: float = setting(300.0, "design frequency: the spacing is half a wavelength there", unit="Hz", gt=0)
    spacing_m: float | None = setting(None, "element spacing d (not set: c / (2 design_hz))", unit="m", gt=0)
    tow_length_m: float = setting(200.0, "distance of the array centre behind the ship along its track (the "
                                         "array heading lags the ship's by tow_length / speed)", unit="m", ge=0)
    depth_m: float = setting(50.0, "array depth (receiver depth of the transmission loss)", unit="m", gt=0)


class ShipSettings(Settings):
    """A ship at constant velocity radiating broadband noise (flat over the scene's band) and one tonal line."""

    name: str = setting(..., "name (the ship column of truth.csv)", unit="")
    x_m: float = setting(..., "position east at t = 0", unit="m")
    y_m: float = setting(..., "position north at t = 0", unit="m")
    course_deg: float = setting(..., "course, clockwise from north", unit="deg")
    speed_kn: float = setting(..., "speed", unit="kn", ge=0, le=60)
    depth_m: float = setting(5.0, "source depth (of the transmission loss)", unit="m", gt=0)
    source_level_db: float = setting(..., "broadband spectral source level at 1 m, flat over the band",
                                     unit="dB re 1 uPa^2/Hz")
    tonal_hz: float | None = setting(None, "emitted frequency of the tonal line (not set: no tonal)", unit="Hz", gt=0)
    tonal_level_db: float = setting(0.0, "source level of the tonal line at 1 m", unit="dB re 1 uPa^2")


class SampleSettings(Settings):
    """The sample inputs of the other commands, made from the same scene (sim/sample_inputs.py)."""

    pair_elements: list[int] = setting(default_factory=lambda: [1, 9], doc="the two elements written to pair.wav "
                                       "for `sonartrack bearings` (1 = front)", unit="1", min_length=2, max_length=2)
    ping_interval_s: float = setting(20.0, "active sonar: time between pings (contacts.csv, raw.csv)", unit="s", gt=0)
    tx_tow_length_m: float = setting(100.0, "active sonar: transmitter towed this far behind the ship; the "
                                            "receiver is the array", unit="m", ge=0)
    pd: float = setting(0.8, "active sonar: probability of detecting each ship per ping", unit="1", ge=0, le=1)
    clutter_per_scan: float = setting(40.0, "active sonar: mean number of false contacts per ping (over the "
                                            "square that holds every ship)", unit="1", ge=0)
    tma_ship: str | None = setting(None, "the ship of brg.csv for `sonartrack tma` (not set: the weakest by "
                                         "broadband source level)", unit="")
    tma_interval_s: float = setting(10.0, "time between bearings in brg.csv", unit="s", gt=0)
    sigma_bearing_deg: float = setting(1.0, "bearing noise of brg.csv", unit="deg", ge=0)
    sigma_freq_hz: float = setting(0.1, "frequency noise of brg.csv", unit="Hz", ge=0)
    sigma_snr_db: float = setting(1.0, "SNR noise of brg.csv", unit="dB", ge=0)
    frames: int = setting(6, "range-Doppler frames K in frames.npy (`sonartrack detect`)", unit="1", ge=1)
    frame_range_cells: int = setting(16, "range cells of frames.npy", unit="1", ge=1)
    frame_doppler_cells: int = setting(64, "Doppler cells of frames.npy", unit="1", ge=1)
    frame_snr_db: float = setting(12.0, "SNR of the Swerling-1 target in frames.npy", unit="dB")


def _default_ships() -> list[ShipSettings]:
    return [ShipSettings(**s) for s in _shipped_scene("passive").get("ships", [])]


@cache
def _shipped_scene(name: str) -> dict:
    """A scene table shipped with the package (``sonartrack/data/scenes/<name>.toml``), read once."""
    return tomllib.loads((scenes_dir() / f"{name}.toml").read_text())


def scenes_dir() -> Path:
    """Folder of the shipped scene tables."""
    from importlib.resources import files

    return Path(str(files("sonartrack") / "data" / "scenes"))


class PassiveSceneSettings(Settings):
    """A passive towed-array scene and its recording (``sonartrack simulate``; module doc for the default)."""

    # at most a day: a day of 16 channels at 4 kHz is already 22 GB
    duration_s: float = setting(1200.0, "length of the recording", unit="s", gt=0, le=86_400)
    sample_rate_hz: float = setting(4000.0, "sample rate of the recording", unit="Hz", gt=0)
    block_s: float = setting(1.0, "synthesis block: geometry is held for a block, noise is drawn per block",
                             unit="s", gt=0)
    band_hz: list[float] = setting(default_factory=lambda: [50.0, 1000.0], doc="band of the broadband noise "
                                   "(ships and ambient); the recording holds nothing outside it", unit="Hz",
                                   min_length=2, max_length=2)
    noise_level_db: float = setting(73.0, "ambient noise spectral level NL, independent between elements",
                                    unit="dB re 1 uPa^2/Hz")
    sound_speed_mps: float = setting(1500.0, "sound speed at the array (plane-wave delays, Doppler)", unit="m/s",
                                     gt=1300, lt=1700)
    propagation: Literal["spherical", "ram"] = setting(
        "spherical", "transmission loss: spherical = 20 log10 r + Thorp absorption; ram = RAM parabolic equation "
                     "in the environment, averaged over tl_average_m (cached in .sonartrack-cache/tl)", unit="")
    environment: str = setting("south-summer", "shipped environment of the RAM transmission loss and of ctd.csv "
                                               "(see sonartrack tl --list)", unit="")
    tl_average_m: float = setting(1000.0, "range average of the RAM transmission loss (as em-map's)", unit="m",
                                  ge=0)
    seed: int = setting(1, "master seed: the recording and each sample input draw from its own child stream",
                        unit="1", ge=0)
    ownship: OwnshipSettings = setting(default_factory=OwnshipSettings, doc="the ownship")
    array: ArraySettings = setting(default_factory=ArraySettings, doc="the towed line array")
    ships: list[ShipSettings] = setting(default_factory=_default_ships, doc="the ships ([[ships]] tables; empty "
                                        "for a noise-only recording)", unit="")
    samples: SampleSettings = setting(default_factory=SampleSettings, doc="the sample inputs of the other commands")

    @model_validator(mode="after")
    def _consistent(self):
        lo, hi = self.band_hz
        nyquist = self.sample_rate_hz / 2
        if not 0 <= lo < hi <= nyquist:
            raise ValueError(f"band_hz {self.band_hz} must satisfy 0 <= low < high <= sample_rate_hz / 2 = {nyquist:g}")
        if self.block_s * self.sample_rate_hz < 16 or self.duration_s * self.sample_rate_hz < 16:
            raise ValueError("block_s and duration_s must hold 16 samples or more: lengthen them")
        if self.environment not in list_environments():
            raise ValueError(f"unknown environment '{self.environment}': choose one of {list_environments()}")
        names = [s.name for s in self.ships]
        if len(set(names)) != len(names):
            raise ValueError(f"ship names must be unique: {names}")
        for s in self.ships:
            if s.tonal_hz is not None and s.tonal_hz >= nyquist:
                raise ValueError(f"ship {s.name}: tonal_hz {s.tonal_hz:g} is at or above sample_rate_hz / 2")
        n = self.array.elements
        if not all(1 <= e <= n for e in self.samples.pair_elements) or len(set(self.samples.pair_elements)) != 2:
            raise ValueError(f"samples.pair_elements must be two different elements in 1..{n}")
        if self.samples.tma_ship is not None and self.samples.tma_ship not in names:
            raise ValueError(f"samples.tma_ship '{self.samples.tma_ship}' is not a ship of the scene ({names})")
        return self

    @property
    def spacing_m(self) -> float:
        """Element spacing d: as given, else half a wavelength at the design frequency."""
        a = self.array
        return a.spacing_m if a.spacing_m is not None else self.sound_speed_mps / (2.0 * a.design_hz)

    @property
    def turn_start_s(self) -> float:
        """When the ownship's turn starts (given, or centred on the middle of the recording)."""
        o = self.ownship
        if o.turn_start_s is not None:
            return o.turn_start_s
        return max(0.5 * self.duration_s - 0.5 * abs(o.turn_deg) / o.turn_rate_deg_s, 0.0)

    def tma_ship_name(self) -> str | None:
        """The ship of the TMA sample: the named one, else the quietest (None without ships)."""
        if self.samples.tma_ship is not None:
            return self.samples.tma_ship
        if not self.ships:
            return None
        return min(self.ships, key=lambda s: s.source_level_db).name
