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

Beyond the default: the ownship can zig-zag (``ownship.zigzag_turns`` course changes ``ownship.leg_s`` apart,
alternating in direction), and a ship can be placed relative to the array instead of by its position at t = 0
(``at_time_s``, ``at_range_m``, ``at_relative_bearing_deg``; sim/passive_scene.py :func:`place_ship`): at range r
and bearing beta clockwise from the array's axis heading h at time t_c, so that its position at t = 0 is
p(t_c) - v t_c with p(t_c) = p_array(t_c) + r [sin(h + beta), cos(h + beta)]. A ship placed on the axis
(beta = 0 or 180 deg) with a course across it crosses endfire at t_c; two ships placed at the same t_c and beta at
different ranges cross there in bearing and cone angle.

Legs (issue 30): a ship may give ``legs = [{duration_s, course_deg, speed_kn}, ...]`` instead of ``course_deg`` and
``speed_kn``, and the ownship ``legs`` instead of its single turn; legs run from t = 0 one after another, every leg
but the last gives its duration (the last is open-ended), the position is continuous. A ship's velocity changes at
once between legs (the piecewise-constant-velocity model of tma/legs.py, exact for its bounds); the ownship turns
the shorter way at ``turn_rate_deg_s`` from the start of each leg (a towing ship cannot turn at once, and the array
follows its track through the turn), its speed changing at once. The shipped ``zigzag`` scene
(``sonartrack/data/scenes/zigzag.toml``) is an example.

Every field is bounded to what a sea and a recorder can be (positions within 1000 km, levels within -100..220 dB,
at most 1024 elements and 1 MHz); across fields, the scene must give a WAV header's whole sample rate, an array
whose delays stay within a tenth of the synthesis block (the circular delay of sim/array_signals.py), a RAM field
of at most 200 km, and working arrays within :data:`MEMORY_LIMIT_BYTES` (:meth:`PassiveSceneSettings.memory_needs`):
each refused in one line naming the figure and the setting.
"""

from __future__ import annotations

import math
import tomllib
from functools import cache
from pathlib import Path
from typing import Literal

from pydantic import model_validator

from sonartrack.acoustics.environment import list_environments
from sonartrack.core.memory import MEMORY_LIMIT_BYTES  # the limit the scene validators plan for
from sonartrack.core.settings import Settings, setting

#: bounds of the scene's declarations: a position beyond 1000 km, a level beyond these, more elements or a higher
#: sample rate is a unit slip or a typo, not a scene (and 1024 elements x 1 MHz x 4 bytes still fit the WAV header's
#: 32-bit byte rate)
MAX_POSITION_M = 1e6
MAX_DEPTH_M = 12_000.0
MAX_DURATION_S = 86_400.0
MAX_ELEMENTS = 1024
MAX_SAMPLE_RATE_HZ = 1e6
MAX_SHIPS = 64
#: legs of a ship or of the ownship: more is a typo (or a track from another tool, better given as its own table)
MAX_LEGS = 1000
#: levels in dB: -100 is a silent source (tests switch a source off with it); a ship's spectral source level above
#: 220 dB re 1 uPa^2/Hz, or an ambient spectral level above 140 dB, is no sea
MIN_LEVEL_DB = -100.0
MAX_SOURCE_LEVEL_DB = 220.0
MAX_NOISE_LEVEL_DB = 140.0
#: the synthesis delays each element by a circular phase ramp within its block (sim/array_signals.py): the wave's
#: first |tau| of a block comes from the block's end, so the largest |tau| must stay a small part of the block
MAX_WRAP_FRACTION = 0.1
#: the RAM field is computed out to the farthest ship: beyond this range it would take hours
MAX_RAM_RANGE_M = 200_000.0


def check_environment_and_names(environment: str, names: list[str], what: str) -> None:
    """A scene validator's checks of its environment (one shipped) and its ``what``s' names (unique).

    Parameters
    ----------
    environment : str
        The environment of the RAM transmission loss.
    names : list of str
        The names of the scene's ships or targets (``what``: "ship", "target").
    what : str
        What the names name, as the message says.

    Raises
    ------
    ValueError
        Naming the unknown environment and the shipped ones, or the names.
    """
    if environment not in list_environments():
        raise ValueError(f"unknown environment '{environment}': choose one of {list_environments()}")
    if len(set(names)) != len(names):
        raise ValueError(f"{what} names must be unique: {names}")


class LegSettings(Settings):
    """One leg of a ship: its course and speed, held for ``duration_s`` from the leg's start (the last leg: open)."""

    duration_s: float | None = setting(None, "length of the leg from its start (every leg but the last, which goes "
                                             "on to the end of the recording and is given without one)", unit="s",
                                       gt=0, le=MAX_DURATION_S)
    course_deg: float = setting(..., "course, clockwise from north", unit="deg", ge=0, lt=360)
    speed_kn: float = setting(..., "speed", unit="kn", ge=0, le=60)


class OwnshipLegSettings(LegSettings):
    """One leg of the ownship: as a ship's, at a speed a towing ship keeps (way on, at most 40 kn)."""

    speed_kn: float = setting(..., "speed through the water", unit="kn", gt=0, le=40)


def check_legs(legs: list[LegSettings], who: str) -> None:
    """Every leg but the last gives its duration; the last is open-ended.

    Parameters
    ----------
    legs : list of LegSettings
        The legs, in order.
    who : str
        The owner's name in the message (``ownship``, ``ship merchant``).

    Raises
    ------
    ValueError
        Naming the leg and the fix.
    """
    for k, leg in enumerate(legs[:-1]):
        if leg.duration_s is None:
            raise ValueError(f"{who} legs[{k}] has no duration_s (s): every leg but the last gives its length")
    if legs[-1].duration_s is not None:
        raise ValueError(f"{who} legs[{len(legs) - 1}].duration_s {legs[-1].duration_s:g} s: the last leg is "
                         "open-ended (it lasts to the end of the recording): leave out its duration_s")


def leg_starts_s(legs: list[LegSettings]) -> list[float]:
    """Start time (s, from t = 0) of every leg: the running sum of the durations before it."""
    return list(math.fsum([0.0, *(leg.duration_s for leg in legs[:k])]) for k in range(len(legs)))


#: the ownship's single-turn (and zig-zag) fields: with ``ownship.legs`` they are left out
SINGLE_TURN_FIELDS = ("speed_kn", "course_deg", "turn_deg", "turn_start_s", "zigzag_turns", "leg_s")


class OwnshipSettings(Settings):
    """The ownship: a straight leg, one course change, a straight leg (sim/platforms.py ManeuveringTrack); or, with
    ``zigzag_turns`` > 1, a zig-zag of legs ``leg_s`` apart alternating between two courses; or, with ``legs``, legs
    of their own course and speed joined by turns at ``turn_rate_deg_s`` (sim/platforms.py LegTrack)."""

    x_m: float = setting(0.0, "start position east", unit="m", ge=-MAX_POSITION_M, le=MAX_POSITION_M)
    y_m: float = setting(0.0, "start position north", unit="m", ge=-MAX_POSITION_M, le=MAX_POSITION_M)
    speed_kn: float = setting(6.0, "speed through the water", unit="kn", gt=0, le=40)
    course_deg: float = setting(0.0, "initial course, clockwise from north", unit="deg", ge=-360, le=360)
    turn_deg: float = setting(-45.0, "course change (negative: to port); 0 for none; it makes range and the "
                                     "left/right side observable", unit="deg", ge=-180, le=180)
    turn_rate_deg_s: float = setting(0.5, "rate of turn", unit="deg/s", gt=0, le=10)
    turn_start_s: float | None = setting(None, "time the (first) turn starts (not set: the turns are centred on the "
                                               "middle of the recording)", unit="s", ge=0, le=MAX_DURATION_S)
    zigzag_turns: int = setting(1, "number of course changes: 1 is the one turn; more make a zig-zag, the turns "
                                   "alternating in direction (turn_deg, -turn_deg, turn_deg, ...) so that the legs "
                                   "alternate between course_deg and course_deg + turn_deg", unit="1", ge=1, le=100)
    leg_s: float = setting(300.0, "zig-zag: time from the start of one turn to the start of the next (longer than "
                                  "a turn, |turn_deg| / turn_rate_deg_s)", unit="s", gt=0, le=MAX_DURATION_S)
    legs: list[OwnshipLegSettings] | None = setting(
        None, "legs instead of the single turn (then speed_kn, course_deg, turn_deg, turn_start_s, zigzag_turns and "
              "leg_s are left out): [{duration_s, course_deg, speed_kn}, ...] from t = 0, the last without "
              "duration_s; each course change is a turn the shorter way (180 deg: to starboard) at turn_rate_deg_s "
              "starting at its leg's start, each speed change instantaneous", unit="", min_length=1,
        max_length=MAX_LEGS)

    @model_validator(mode="after")
    def _legs_longer_than_turns(self):
        if self.legs is not None:
            self._check_own_legs()
            return self
        turn_s = abs(self.turn_deg) / self.turn_rate_deg_s
        if self.zigzag_turns > 1 and self.leg_s <= turn_s:
            raise ValueError(f"ownship.leg_s {self.leg_s:g} s is not longer than a turn ({turn_s:g} s = |turn_deg| / "
                             "turn_rate_deg_s): lengthen leg_s or turn less or faster")
        return self

    def _check_own_legs(self) -> None:
        """Legs replace the single turn, and each leg lasts longer than the turn into it."""
        for name in SINGLE_TURN_FIELDS:
            if getattr(self, name) != type(self).model_fields[name].default:
                raise ValueError(f"ownship.{name} belongs to the single turn: with ownship.legs leave it out (the "
                                 "legs give the courses, speeds and times)")
        check_legs(self.legs, "ownship")
        for k in range(1, len(self.legs)):
            turn_s = abs(course_change_deg(self.legs[k - 1].course_deg, self.legs[k].course_deg)) / self.turn_rate_deg_s
            if self.legs[k].duration_s is not None and self.legs[k].duration_s <= turn_s:
                raise ValueError(f"ownship legs[{k}].duration_s {self.legs[k].duration_s:g} s is not longer than the "
                                 f"turn into it ({turn_s:g} s at turn_rate_deg_s {self.turn_rate_deg_s:g} deg/s): "
                                 "lengthen the leg or turn faster")

    @property
    def max_speed_kn(self) -> float:
        """The fastest speed of the ownship (kn)."""
        return max(leg.speed_kn for leg in self.legs) if self.legs is not None else self.speed_kn

    @property
    def maneuver_s(self) -> float:
        """Time from the first turn's start to the last turn's end (s; 0 without a turn)."""
        if self.turn_deg == 0:
            return 0.0
        return (self.zigzag_turns - 1) * self.leg_s + abs(self.turn_deg) / self.turn_rate_deg_s


def course_change_deg(from_deg: float, to_deg: float) -> float:
    """The turn from one course to another the shorter way (deg, in (-180, 180]; positive to starboard, and a
    reversal of course to starboard)."""
    d = (to_deg - from_deg) % 360.0
    return d - 360.0 if d > 180.0 else d


class ArraySettings(Settings):
    """The towed uniform line array; element 1 is the front (nearest the ship), element N the tail."""

    elements: int = setting(16, "number of hydrophones N", unit="1", ge=2, le=MAX_ELEMENTS)
    design_hz: float = setting(300.0, "design frequency: the spacing is half a wavelength there", unit="Hz", gt=0,
                             le=MAX_SAMPLE_RATE_HZ / 2)
    spacing_m: float | None = setting(None, "element spacing d (not set: c / (2 design_hz))", unit="m", gt=0,
                                       le=1000)
    tow_length_m: float = setting(200.0, "distance of the array centre behind the ship along its track (the "
                                         "array heading lags the ship's by tow_length / speed)", unit="m", ge=0,
                                  le=10_000)
    depth_m: float = setting(50.0, "array depth (receiver depth of the transmission loss)", unit="m", gt=0,
                                 le=MAX_DEPTH_M)


class ShipSettings(Settings):
    """A ship radiating broadband noise (flat over the scene's band) and one tonal line, at constant velocity
    (``course_deg``, ``speed_kn``) or on ``legs`` of constant velocity joined by instantaneous changes."""

    name: str = setting(..., "name (the ship column of truth.csv)", unit="")
    x_m: float | None = setting(None, "position east at t = 0 (not set: placed by at_time_s, at_range_m and "
                                      "at_relative_bearing_deg)", unit="m", ge=-MAX_POSITION_M, le=MAX_POSITION_M)
    y_m: float | None = setting(None, "position north at t = 0 (with x_m)", unit="m", ge=-MAX_POSITION_M,
                                le=MAX_POSITION_M)
    at_time_s: float | None = setting(None, "placed relative to the array instead of x_m, y_m: the time at which the "
                                            "ship is at at_range_m and at_relative_bearing_deg from the array centre",
                                      unit="s", ge=-MAX_DURATION_S, le=MAX_DURATION_S)
    at_range_m: float | None = setting(None, "placed: range from the array centre at at_time_s", unit="m", gt=0,
                                       le=MAX_POSITION_M)
    at_relative_bearing_deg: float | None = setting(
        None, "placed: bearing from the array centre at at_time_s, clockwise from the array's axis heading (0 ahead "
              "and 180 astern are on the axis, endfire: a ship crossing it there changes side; 90 the starboard "
              "beam, -90 port); two ships placed at the same time and relative bearing at different ranges cross "
              "there in bearing and cone angle", unit="deg", ge=-360, le=360)
    course_deg: float | None = setting(None, "course, clockwise from north (not set: legs)", unit="deg", ge=-360,
                                       le=360)
    speed_kn: float | None = setting(None, "speed (not set: legs)", unit="kn", ge=0, le=60)
    legs: list[LegSettings] | None = setting(
        None, "legs instead of course_deg and speed_kn: [{duration_s, course_deg, speed_kn}, ...] from t = 0, the "
              "last without duration_s; the velocity changes at once between legs (a zig), the position is "
              "continuous", unit="", min_length=1, max_length=MAX_LEGS)
    depth_m: float = setting(5.0, "source depth (of the transmission loss)", unit="m", gt=0, le=MAX_DEPTH_M)
    source_level_db: float = setting(..., "broadband spectral source level at 1 m, flat over the band",
                                     unit="dB re 1 uPa^2/Hz", ge=MIN_LEVEL_DB, le=MAX_SOURCE_LEVEL_DB)
    tonal_hz: float | None = setting(None, "emitted frequency of the tonal line (not set: no tonal)", unit="Hz", gt=0,
                                     le=MAX_SAMPLE_RATE_HZ / 2)
    tonal_level_db: float = setting(0.0, "source level of the tonal line at 1 m", unit="dB re 1 uPa^2",
                                   ge=MIN_LEVEL_DB, le=MAX_SOURCE_LEVEL_DB)

    @model_validator(mode="after")
    def _placed_once(self):
        absolute = (self.x_m is not None, self.y_m is not None)
        placed = (self.at_time_s is not None, self.at_range_m is not None, self.at_relative_bearing_deg is not None)
        if not ((all(absolute) and not any(placed)) or (all(placed) and not any(absolute))):
            raise ValueError(f"ship {self.name}: give either x_m and y_m, or at_time_s, at_range_m and "
                             "at_relative_bearing_deg (placed relative to the array)")
        if self.legs is None and (self.course_deg is None or self.speed_kn is None):
            raise ValueError(f"ship {self.name}: give course_deg (deg) and speed_kn (kn), or legs")
        if self.legs is not None:
            if self.course_deg is not None or self.speed_kn is not None:
                raise ValueError(f"ship {self.name}: give legs, or course_deg and speed_kn, not both (the first leg "
                                 "gives the course and speed at t = 0)")
            check_legs(self.legs, f"ship {self.name}")
        return self

    @property
    def max_speed_kn(self) -> float:
        """The fastest speed of the ship (kn)."""
        return max(leg.speed_kn for leg in self.legs) if self.legs is not None else self.speed_kn

    @property
    def placed(self) -> bool:
        """Whether the ship is placed relative to the array (at_time_s, at_range_m, at_relative_bearing_deg)."""
        return self.x_m is None


class SampleSettings(Settings):
    """The sample inputs of the other commands, made from the same scene (sim/sample_inputs.py)."""

    pair_elements: list[int] = setting(default_factory=lambda: [1, 9], doc="the two elements written to pair.wav "
                                       "for `sonartrack bearings` (1 = front)", unit="1", min_length=2, max_length=2)
    ping_interval_s: float = setting(20.0, "active sonar: time between pings (contacts.csv, raw.csv)", unit="s", gt=0,
                                     le=3600)
    tx_tow_length_m: float = setting(100.0, "active sonar: transmitter towed this far behind the ship; the "
                                            "receiver is the array", unit="m", ge=0, le=10_000)
    pd: float = setting(0.8, "active sonar: probability of detecting each ship per ping", unit="1", ge=0, le=1)
    clutter_per_scan: float = setting(40.0, "active sonar: mean number of false contacts per ping (over the "
                                            "square that holds every ship)", unit="1", ge=0, le=10_000)
    tma_ship: str | None = setting(None, "the ship of brg.csv for `sonartrack tma` (not set: the weakest by "
                                         "broadband source level)", unit="")
    tma_interval_s: float = setting(10.0, "time between bearings in brg.csv", unit="s", gt=0, le=3600)
    sigma_bearing_deg: float = setting(1.0, "bearing noise of brg.csv", unit="deg", ge=0, le=30)
    sigma_freq_hz: float = setting(0.1, "frequency noise of brg.csv", unit="Hz", ge=0, le=10)
    sigma_snr_db: float = setting(1.0, "SNR noise of brg.csv", unit="dB", ge=0, le=20)
    frames: int = setting(6, "range-Doppler frames K in frames.npy (`sonartrack detect`)", unit="1", ge=1,
                         le=1000)
    frame_range_cells: int = setting(16, "range cells of frames.npy", unit="1", ge=1, le=4096)
    frame_doppler_cells: int = setting(64, "Doppler cells of frames.npy", unit="1", ge=1, le=4096)
    frame_snr_db: float = setting(12.0, "SNR of the Swerling-1 target in frames.npy", unit="dB", ge=-30,
                                 le=60)


def _default_ships() -> list[ShipSettings]:
    return [ShipSettings(**s) for s in _shipped_scene("passive").get("ships", [])]


@cache
def _shipped_scene(name: str) -> dict:
    """A scene table shipped with the package (``sonartrack/data/scenes/<name>.toml``), read once."""
    return tomllib.loads((scenes_dir() / f"{name}.toml").read_text())


def scenes_dir() -> Path:
    """Folder of the scene tables shipped with the package.

    Returns
    -------
    pathlib.Path
        ``sonartrack/data/scenes``.
    """
    from importlib.resources import files

    return Path(str(files("sonartrack") / "data" / "scenes"))


class PassiveSceneSettings(Settings):
    """A passive towed-array scene and its recording (``sonartrack simulate``; module doc for the default)."""

    # at most a day: a day of 16 channels at 4 kHz is already 22 GB
    duration_s: float = setting(1200.0, "length of the recording", unit="s", gt=0, le=MAX_DURATION_S)
    sample_rate_hz: float = setting(4000.0, "sample rate of the recording", unit="Hz", ge=100,
                                   le=MAX_SAMPLE_RATE_HZ)
    block_s: float = setting(1.0, "synthesis block: geometry is held for a block, noise is drawn per block",
                             unit="s", gt=0, le=600)
    band_hz: list[float] = setting(default_factory=lambda: [50.0, 1000.0], doc="band of the broadband noise "
                                   "(ships and ambient); the recording holds nothing outside it", unit="Hz",
                                   min_length=2, max_length=2)
    noise_level_db: float = setting(73.0, "ambient noise spectral level NL, independent between elements",
                                    unit="dB re 1 uPa^2/Hz", ge=MIN_LEVEL_DB, le=MAX_NOISE_LEVEL_DB)
    sound_speed_mps: float = setting(1500.0, "sound speed at the array (plane-wave delays, Doppler)", unit="m/s",
                                     gt=1300, lt=1700)
    propagation: Literal["spherical", "ram"] = setting(
        "spherical", "transmission loss: spherical = 20 log10 r + Thorp absorption; ram = RAM parabolic equation "
                     "in the environment, averaged over tl_average_m (cached in .sonartrack-cache/tl)", unit="")
    environment: str = setting("south-summer", "shipped environment of the RAM transmission loss and of ctd.csv "
                                               "(see sonartrack tl --list)", unit="")
    tl_average_m: float = setting(1000.0, "range average of the RAM transmission loss (as em-map's)", unit="m",
                                  ge=0, le=100_000)
    seed: int = setting(1, "master seed: the recording and each sample input draw from its own child stream",
                        unit="1", ge=0, lt=2**63)
    ownship: OwnshipSettings = setting(default_factory=OwnshipSettings, doc="the ownship")
    array: ArraySettings = setting(default_factory=ArraySettings, doc="the towed line array")
    ships: list[ShipSettings] = setting(default_factory=_default_ships, doc="the ships ([[ships]] tables; empty "
                                        "for a noise-only recording)", unit="",
                                        max_length=MAX_SHIPS)
    samples: SampleSettings = setting(default_factory=SampleSettings, doc="the sample inputs of the other commands")

    @model_validator(mode="after")
    def _consistent(self):
        lo, hi = self.band_hz
        nyquist = self.sample_rate_hz / 2
        if not 0 <= lo < hi <= nyquist:
            raise ValueError(f"band_hz {self.band_hz} must satisfy 0 <= low < high <= sample_rate_hz / 2 = {nyquist:g}")
        if self.block_s * self.sample_rate_hz < 16 or self.duration_s * self.sample_rate_hz < 16:
            raise ValueError("block_s and duration_s must hold 16 samples or more: lengthen them")
        names = [s.name for s in self.ships]
        check_environment_and_names(self.environment, names, "ship")
        for s in self.ships:
            if s.tonal_hz is not None and s.tonal_hz >= nyquist:
                raise ValueError(f"ship {s.name}: tonal_hz {s.tonal_hz:g} is at or above sample_rate_hz / 2")
        n = self.array.elements
        if not all(1 <= e <= n for e in self.samples.pair_elements) or len(set(self.samples.pair_elements)) != 2:
            raise ValueError(f"samples.pair_elements must be two different elements in 1..{n}")
        if self.samples.tma_ship is not None and self.samples.tma_ship not in names:
            raise ValueError(f"samples.tma_ship '{self.samples.tma_ship}' is not a ship of the scene ({names})")
        self._check_recording()
        self._check_reach()
        for need, what, fix in self.memory_needs():
            if need > MEMORY_LIMIT_BYTES:
                raise ValueError(f"{what} would take {need / 1e9:.3g} GB of memory, more than the "
                                 f"{MEMORY_LIMIT_BYTES / 1e9:.3g} GB the simulator plans for: {fix}")
        return self

    def _check_recording(self) -> None:
        """What the WAV file and the block synthesis need of the sample rate and the array's length."""
        fs = self.sample_rate_hz
        if not float(fs).is_integer():
            raise ValueError(f"sample_rate_hz {fs:g} is not a whole number of samples per second, which is all a WAV "
                             f"header holds: give {round(fs)}")
        half_delay_s = 0.5 * (self.array.elements - 1) * self.spacing_m / self.sound_speed_mps
        if half_delay_s > MAX_WRAP_FRACTION * self.block_s:
            need_s = half_delay_s / MAX_WRAP_FRACTION
            raise ValueError(f"the array ({self.array.elements} elements {self.spacing_m:g} m apart) delays a wave by "
                             f"up to {half_delay_s:.3g} s from its centre, which wraps round "
                             f"{100 * min(half_delay_s / self.block_s, 1):.0f} % of each {self.block_s:g} s "
                             f"synthesis block (at most {100 * MAX_WRAP_FRACTION:.0f} %): set block_s >= "
                             f"{need_s:.3g} s, or check array.spacing_m (metres)")

    def _check_reach(self) -> None:
        """The RAM field is computed out to the farthest ship: refuse a scene that would need hours of it."""
        if self.propagation != "ram" or not self.ships:
            return
        from sonartrack.core.units import KNOT_MPS

        o = self.ownship
        def start_distance(s: ShipSettings) -> float:  # a placed ship: at most this far at t = 0
            if not s.placed:
                return math.hypot(s.x_m - o.x_m, s.y_m - o.y_m)
            return s.at_range_m + self.array.tow_length_m + (s.max_speed_kn + o.max_speed_kn) * KNOT_MPS * abs(
                s.at_time_s)

        reach = max(start_distance(s) + (s.max_speed_kn + o.max_speed_kn) * KNOT_MPS * self.duration_s
                    for s in self.ships) + self.array.tow_length_m
        if reach > MAX_RAM_RANGE_M:
            raise ValueError(f"propagation = ram would compute the field out to {reach / 1e3:.0f} km (the farthest "
                             f"ship), more than {MAX_RAM_RANGE_M / 1e3:.0f} km: use propagation = spherical, or bring "
                             "the ships nearer or shorten duration_s")

    def memory_needs(self) -> list[tuple[float, str, str]]:
        """The simulation's largest working arrays: bytes, what they hold and sizes them, and the fix.

        One synthesis block (sim/array_signals.py: the ships' phase ramps S x N x n_band and the element spectra,
        complex128), the block plan (delays B x S x N, float64), the truth table (a row per second and ship) and
        frames.npy (K x Nr x Nd); a few temporaries of each are counted.

        Returns
        -------
        list of (float, str, str)
            Bytes (estimate), what needs them (with the settings that size it), and how to make it smaller.
        """
        fs = self.sample_rate_hz
        nb = round(self.block_s * fs)
        n_band = max(int((self.band_hz[1] - self.band_hz[0]) * self.block_s) + 1, 1)
        n, s = self.array.elements, max(len(self.ships), 1)
        n_blocks = math.ceil(self.duration_s / self.block_s)
        sp = self.samples
        return [
            (16.0 * (2 * s * n * n_band + 3 * n * (nb // 2 + 1)) + 24.0 * n * nb,
             f"one synthesis block ({s} ship(s) x {n} elements x {n_band} bins of band_hz over block_s)",
             "shorten block_s, narrow band_hz or use fewer array.elements"),
            (24.0 * n_blocks * s * n, f"the block plan ({n_blocks} blocks x {s} ship(s) x {n} elements)",
             "lengthen block_s, shorten duration_s or use fewer array.elements"),
            (16.0 * 20 * (math.floor(self.duration_s) + 2) * s, f"truth.csv ({math.floor(self.duration_s) + 2} "
             f"seconds x {s} ship(s))", "shorten duration_s or give fewer ships"),
            (24.0 * sp.frames * sp.frame_range_cells * sp.frame_doppler_cells, f"frames.npy ({sp.frames} frames x "
             f"{sp.frame_range_cells} x {sp.frame_doppler_cells} cells)",
             "lower samples.frames, frame_range_cells or frame_doppler_cells"),
        ]

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
        return max(0.5 * self.duration_s - 0.5 * o.maneuver_s, 0.0)

    def tma_ship_name(self) -> str | None:
        """The ship of the TMA sample (brg.csv): the named one, else the quietest by broadband source level.

        Returns
        -------
        str or None
            Its name; None without ships.
        """
        if self.samples.tma_ship is not None:
            return self.samples.tma_ship
        if not self.ships:
            return None
        return min(self.ships, key=lambda s: s.source_level_db).name
