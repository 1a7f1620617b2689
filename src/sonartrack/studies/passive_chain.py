"""Study passive-chain: the whole passive system on a family of simulated towed-array scenes (our own study).

Each trial draws one scene from a family (:func:`draw_scene`, deterministic in its seed): a line array of
``family.elements`` hydrophones ``family.spacing_m`` apart recorded at ``family.sample_rate_hz``; an ownship on a
random course that either turns once (``family.turn_deg``, to port or starboard) or zig-zags (2-3 turns of 25-45
deg alternating in direction, sim/scene.py ``zigzag_turns``); and four ships placed relative to the array
(sim/passive_scene.py :func:`~sonartrack.sim.passive_scene.place_ship`): a *pair* placed at the same relative
bearing at the same time at two ranges (they cross in cone angle there, their cone-angle rates at least
``MIN_CROSSING_RATE_DEG_S`` apart), a *crosser* placed on the array's axis (endfire, ahead or astern) with a course
across it (it changes side), and a *loner*. Their broadband source levels give a per-element SNR drawn from
``family.snr_db`` at the placement; each has a tonal line. The chain of ``sonartrack passive``
(systems/passive/chain.py :func:`run_passive`) runs on the recording, and on a noise-only recording of the same
array and length.

Truth per ship and window (:func:`window_levels`, :func:`window_truth`): the true cone angle, side and the
front end's level at the ship's cone angle; a ship is *detectable* in a window when that level (running median)
reaches the detection threshold and no other ship lies within a beam (separation in direction cosine below the
broadside beamwidth: :func:`direction_separation`; the beam widens in cone angle as 1 / sin(theta) towards endfire).
Events: a *crossing* is a maximal run of windows in which two ships lie within one beam (:func:`crossing_events`);
an *axis crossing* a change of a ship's true side (:func:`axis_crossings`).

Checks (claims, each with its 95 % interval):

* ships held: per (run, ship), the share of its detectable windows in which a confirmed track lies within
  the match tolerance of its cone angle (``match_deg``, or one beamwidth if wider: :func:`match_tolerance`); the
  mean over (run, ship) pairs >= ``HOLD_REQUIRED``;
* identities through crossings: the targets following the two ships ``crossing_window_s`` before a crossing
  follow the same ships after it (:func:`identity_through`), in >= ``IDENTITY_REQUIRED`` of the crossings judged
  (both ships followed by two targets before it, both detectable after it);
* true bearing after an axis crossing: the median error of the true bearings (the batch ML's record) of the
  target following the ship after the crossing within 2 beamwidths, in >= ``AXIS_REQUIRED`` of the crossings;
* ML near the CRB: of the determined final ML solutions of targets following a ship, >= ``CRB_SHARE`` within
  ``CRB_FACTOR`` x the bearings-only CRB position sd (computed with the bearing noise of the target's own peaks,
  over the scans the ML was fitted to, at its last row's time: :func:`target_errors`), and none off by more than
  ``MAX_SDS`` of its own position sds (Mahalanobis distance);
* no printed solution diverged (ML and IMM-MGEKF final rows printed with a range: :func:`diverged`);
* false targets: at most ``FALSE_PER_HOUR`` confirmed targets following no ship per hour (noise-only recordings
  and the ship scenes' targets that follow no ship).

Reported beside the claims: NEES of the final ML (and IMM-MGEKF) solutions against the chi-square 95 % interval,
the ml-near-crb share again against the CRB of AR(1) errors with the peaks' own lag-1 correlation
(:func:`correlated_crb_sd_m`: the bound for the slow errors a second ship in the beam makes, which the white-noise
CRB of the same sd is not), OSPA and GOSPA (with the switching term) of the tracks' cone angles and of the targets'
positions against the truth (metrics/ospa.py), and the track segments (fragmentation) and identity switches per ship
(metrics/track_quality.py).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.core.units import KNOT_MPS
from sonartrack.experiment.claims import Claim
from sonartrack.sim.scene import PassiveSceneSettings, ShipSettings
from sonartrack.systems.passive.settings import PassiveSettings

STUDY_ID = "passive-chain"
TITLE = "The passive chain on a family of simulated towed-array scenes (our own study)"
PAPER = "sonartrack's own: papers P0 (JPDA_A), P2 (IMM-MGEKF) and P3 (batch ML) joined into one system"
TRIAL_VERSION = 14
#: Monte Carlo size of the full run (``Config.runs``) and of ``Config.quick()``: literals, so that
#: ``sonartrack studies`` reads them from this file's source without importing it
RUNS = 32
QUICK_RUNS = 2
#: one trial per stored chunk: a trial takes tens of seconds, so an interruption loses at most one
CHUNK_SIZE = 1
HOLD_REQUIRED = 0.9
IDENTITY_REQUIRED = 0.8
AXIS_REQUIRED = 0.9
AXIS_BEAMWIDTHS = 2.0
CRB_FACTOR = 2.0
CRB_SHARE = 0.9
MAX_SDS = 5.0
FALSE_PER_HOUR = 1.0
#: windows of the running median of a ship's level at its cone angle (its SNR in the detector, :func:`window_truth`)
SNR_MEDIAN_WINDOWS = 11
#: the family's ships, in scene order (per-ship outputs are in this order)
FAMILY_SHIPS = ("pair-near", "pair-far", "crosser", "loner")
#: padded sizes of the per-trial event and solution outputs (the store keeps one shape per output)
MAX_EVENTS = 8
MAX_SOLUTIONS = 12
#: the pair's cone-angle rates differ by at least this at their crossing (else they move together: no crossing)
MIN_CROSSING_RATE_DEG_S = 0.06
#: a target follows a ship over a span when at least this many of its peaks lie within match_deg of it
MIN_FOLLOW_SCANS = 5
#: a printed solution has diverged when its range is beyond this many times the true range, or its speed beyond
#: the fastest ship a scene may hold, or it is not finite
DIVERGED_RANGE_FACTOR = 5.0
DIVERGED_SPEED_MPS = 60.0 * KNOT_MPS
#: cut-offs of OSPA / GOSPA (p = 1; GOSPA's switching penalty half the cut-off)
OSPA_CONE_DEG = 5.0
OSPA_POSITION_M = 2000.0


class FamilySettings(Settings):
    """The family the trials' scenes are drawn from (:func:`draw_scene`)."""

    elements: list[int] = setting(default_factory=lambda: [16, 24, 32], doc="hydrophone counts drawn from",
                                  unit="1", min_length=1)
    spacing_m: list[float] = setting(default_factory=lambda: [1.0, 1.5, 2.5], doc="element spacings drawn from",
                                     unit="m", min_length=1)
    sample_rate_hz: list[float] = setting(default_factory=lambda: [4000.0, 6000.0, 8000.0],
                                          doc="sample rates drawn from", unit="Hz", min_length=1)
    duration_s: float = setting(600.0, "length of each recording", unit="s", ge=240.0, le=7200.0)
    zigzag_share: float = setting(0.5, "share of the scenes whose ownship zig-zags (2-3 turns of 25-45 deg at 1 "
                                       "deg/s); the others turn once", unit="1", ge=0, le=1)
    turn_deg: list[float] = setting(default_factory=lambda: [30.0, 90.0], doc="range of the size of the single "
                                    "turn (at 0.5 deg/s, to port or starboard)", unit="deg", min_length=2,
                                    max_length=2)
    snr_db: list[float] = setting(default_factory=lambda: [-12.0, -2.0], doc="range of each ship's broadband "
                                  "per-element SNR at its placement", unit="dB", min_length=2, max_length=2)


class Config(Settings):
    """Monte Carlo of the passive chain on the scene family; the chain is that of ``sonartrack passive`` with its
    defaults (:func:`study_chain`), its element count and spacing taken from each scene."""

    runs: int = setting(RUNS, "Monte Carlo runs (each: a scene of the family and a noise-only scene)", unit="1",
                        ge=1)
    family: FamilySettings = setting(default_factory=FamilySettings, doc="the scene family")
    scene: PassiveSceneSettings = setting(default_factory=PassiveSceneSettings, doc="the base scene (noise, band, "
                                          "sound speed, tow; the family replaces its array, rate, length, ownship "
                                          "and ships)")
    chain: PassiveSettings = setting(default_factory=lambda: study_chain(), doc="the chain of sonartrack passive "
                                     "with its defaults (see study_chain)")
    match_deg: float = setting(3.0, "a track follows a ship at a time when within this (or one broadside beamwidth "
                                    "of the array, if wider) of its true cone angle", unit="deg", gt=0)
    min_detectable_s: float = setting(60.0, "a ship above the detection threshold for less than this in a run is "
                                      "not judged on holding in that run (a track needs time to start)", unit="s",
                                      ge=0)
    crossing_window_s: float = setting(90.0, "identity at a crossing and bearings after an axis crossing: the "
                                       "targets following each ship this long before and after it", unit="s", gt=0)

    @classmethod
    def quick(cls) -> Config:
        """Demo preset: two 5-minute scenes of the family on the smaller arrays at 4 kHz (and two noise-only
        scenes), ~25 s; every check is computed on them (few TMA solutions are determined in 5 minutes)."""
        family = FamilySettings(elements=[16, 24], spacing_m=[1.5, 2.5], sample_rate_hz=[4000.0], duration_s=300.0)
        return cls(runs=QUICK_RUNS, family=family)


def study_chain() -> PassiveSettings:
    """The chain of ``sonartrack passive`` with its defaults (the automatic band, acoustics/beamforming.py
    :class:`~sonartrack.acoustics.beamforming.BeamformerSettings`)."""
    return PassiveSettings()


def ship_names(config: Config) -> list[str]:
    return list(FAMILY_SHIPS)


def chain_settings(config: Config, scene: PassiveSceneSettings | None = None) -> PassiveSettings:
    """The chain's settings with the array (spacing and element count) of ``scene`` (default ``config.scene``)."""
    scene = config.scene if scene is None else scene
    return config.chain.model_copy(update={"spacing_m": scene.spacing_m, "elements": scene.array.elements})


def navigation(geometry):
    """The simulator's platforms as the chain's :class:`~sonartrack.io.navigation.Navigation`."""
    from sonartrack.io.navigation import Navigation

    g = geometry
    return Navigation(g.time_s, g.own_xy[:, 0], g.own_xy[:, 1], np.unwrap(g.own_heading_rad), g.array_xy[:, 0],
                      g.array_xy[:, 1], np.unwrap(g.array_heading_rad))


def run_chain(config: Config, scene: PassiveSceneSettings, *, plain_jpda: bool = False):
    """The chain on ``scene``'s recording (synthesised block by block, once per stage that reads it), with the
    scene's array; ``plain_jpda``: also track the peaks with plain JPDA
    (:func:`~sonartrack.systems.passive.chain.run_passive`). Returns (the chain's result, the navigation)."""
    from sonartrack.sim.array_signals import array_blocks, plan_blocks
    from sonartrack.sim.passive_scene import scene_geometry
    from sonartrack.systems.passive.chain import run_passive

    settings = chain_settings(config, scene)
    stages = settings.stages(scene.sample_rate_hz)
    plan = plan_blocks(scene)
    n_windows = int(scene.duration_s // settings.window_s)
    nav = navigation(scene_geometry(scene, np.arange(0.0, np.floor(scene.duration_s) + 1.0)))
    blocks = lambda: array_blocks(scene, np.random.default_rng(scene.seed), plan=plan)  # noqa: E731
    return run_passive(blocks, n_windows, nav, stages, plain_jpda=plain_jpda), nav


# ---------------------------------------------------------------------------------------------------------------
# the family


def _source_level_db(scene: PassiveSceneSettings, range_m: float, snr_db: float) -> float:
    """The broadband source level giving a per-element SNR ``snr_db`` at ``range_m`` (sonar equation SL = NL + TL +
    SNR, sim/passive_scene.py)."""
    from sonartrack.sim.passive_scene import broadband_tl_frequency_hz, transmission_loss_db

    tl = float(transmission_loss_db(scene, np.array([range_m]), broadband_tl_frequency_hz(scene), 5.0)[0])
    return float(scene.noise_level_db + tl + snr_db)


def _draw_ownship(rng: np.random.Generator, family: FamilySettings) -> dict:
    """A random course and speed, and either one turn (size from ``family.turn_deg`` at 0.5 deg/s) or a zig-zag
    of 2-3 turns of 25-45 deg at 1 deg/s; the manoeuvre starts at 15-40 % of the recording and ends by 90 %."""
    d = family.duration_s
    own = {"course_deg": float(rng.uniform(0.0, 360.0)), "speed_kn": float(rng.choice([5.0, 6.0, 8.0]))}
    sign = float(rng.choice([-1.0, 1.0]))
    if rng.random() < family.zigzag_share:
        n, size = int(rng.integers(2, 4)), float(rng.uniform(25.0, 45.0))
        turn_s = size / 1.0
        leg = min(float(rng.uniform(turn_s + 40.0, turn_s + 120.0)), (0.75 * d - turn_s) / (n - 1))
        own |= {"turn_deg": sign * size, "turn_rate_deg_s": 1.0, "zigzag_turns": n, "leg_s": max(leg, turn_s + 1.0)}
        span = (n - 1) * own["leg_s"] + turn_s
    else:
        size = float(rng.uniform(*family.turn_deg))
        own |= {"turn_deg": sign * size, "turn_rate_deg_s": 0.5}
        span = size / 0.5
    own["turn_start_s"] = float(np.clip(rng.uniform(0.15 * d, 0.4 * d), 0.0, max(0.9 * d - span, 0.0)))
    return own


def _ship(rng, scene, name: str, t_s: float, range_m: float, rel_deg: float, course_deg: float, speed_kn: float,
          snr_db: float) -> ShipSettings:
    sl = _source_level_db(scene, range_m, snr_db)
    return ShipSettings(name=name, at_time_s=float(t_s), at_range_m=float(range_m),
                        at_relative_bearing_deg=float(rel_deg), course_deg=float(course_deg % 360.0),
                        speed_kn=float(speed_kn), source_level_db=sl, tonal_hz=float(rng.uniform(80.0, 320.0)),
                        tonal_level_db=sl + float(rng.uniform(10.0, 16.0)))


def _pair(rng, scene: PassiveSceneSettings, family: FamilySettings) -> list[ShipSettings]:
    """Two ships at one relative bearing at one time, at two ranges, whose cone-angle rates differ there by at least
    ``MIN_CROSSING_RATE_DEG_S`` (redrawn until they do)."""
    from sonartrack.sim.passive_scene import scene_geometry

    d = family.duration_s
    ships = []
    for _ in range(50):
        t_c = rng.uniform(0.3 * d, 0.65 * d)
        rel = float(rng.choice([-1.0, 1.0]) * rng.uniform(35.0, 145.0))
        near = rng.uniform(2500.0, 5000.0)
        ranges = (near, near * rng.uniform(1.8, 3.0))
        ships = [_ship(rng, scene, n, t_c, r, rel, rng.uniform(0.0, 360.0), rng.uniform(6.0, 14.0),
                       rng.uniform(*family.snr_db)) for n, r in zip(FAMILY_SHIPS[:2], ranges, strict=True)]
        g = scene_geometry(scene.model_copy(update={"ships": ships}), np.array([t_c - 5.0, t_c + 5.0]))
        rates = np.rad2deg(np.diff(g.cone_rad, axis=1)[:, 0]) / 10.0
        if abs(rates[0] - rates[1]) >= MIN_CROSSING_RATE_DEG_S:
            break
    return ships


def _crosser(rng, scene: PassiveSceneSettings, family: FamilySettings) -> ShipSettings:
    """A ship on the array's axis (ahead or astern) at 35-70 % of the recording, on a course within 30 deg of
    square across the axis."""
    from sonartrack.sim.passive_scene import ownship_track

    d = family.duration_s
    t_a = rng.uniform(0.35 * d, 0.7 * d)
    rel = float(rng.choice([0.0, 180.0]))
    track = ownship_track(scene)
    _, _, h = track.state(np.array([t_a - scene.array.tow_length_m / track.speed_mps]))
    course = np.rad2deg(h[0]) + rel + float(rng.choice([-90.0, 90.0])) + rng.uniform(-30.0, 30.0)
    return _ship(rng, scene, FAMILY_SHIPS[2], t_a, rng.uniform(3500.0, 7000.0), rel, course, rng.uniform(8.0, 14.0),
                 rng.uniform(*family.snr_db))


def draw_scene(config: Config, seed: int) -> PassiveSceneSettings:
    """One scene of the family (module doc), a pure function of ``seed`` (the recording's seed too).

    Parameters
    ----------
    config : Config
        The family (``config.family``) and the base scene (noise, band, sound speed, tow).
    seed : int
        Seed of the draw and of the recording.

    Returns
    -------
    PassiveSceneSettings
        The scene, its ships named as ``FAMILY_SHIPS``.
    """
    f = config.family
    rng = np.random.default_rng(seed)
    array = config.scene.array.model_copy(update={"elements": int(rng.choice(f.elements)),
                                                  "spacing_m": float(rng.choice(f.spacing_m))})
    scene = config.scene.model_copy(update={
        "seed": int(seed), "duration_s": f.duration_s, "sample_rate_hz": float(rng.choice(f.sample_rate_hz)),
        "array": array, "ownship": config.scene.ownship.model_copy(update=_draw_ownship(rng, f)), "ships": []})
    ships = _pair(rng, scene, f) + [_crosser(rng, scene, f)]
    loner = _ship(rng, scene, FAMILY_SHIPS[3], 0.5 * f.duration_s, rng.uniform(4000.0, 12000.0),
                  rng.uniform(-180.0, 180.0), rng.uniform(0.0, 360.0), rng.uniform(4.0, 12.0), rng.uniform(*f.snr_db))
    # validated as a whole (the array's delays against the block, the tonals against the sample rate)
    ships = [s.model_dump() for s in ships + [loner]]
    return PassiveSceneSettings.model_validate(scene.model_dump() | {"ships": ships})


def example_scene(config: Config) -> PassiveSceneSettings:
    """The family's scene of seed 0 (drawn on the report's scenario figure)."""
    return draw_scene(config, 0)


# ---------------------------------------------------------------------------------------------------------------
# truth


def running_median(x, width: int) -> np.ndarray:
    """Centred running median along the last axis (edges: the nearest full window)."""
    from numpy.lib.stride_tricks import sliding_window_view

    x = np.asarray(x, float)
    if x.shape[-1] < width:
        return np.median(x, axis=-1, keepdims=True) * np.ones_like(x)
    med = np.median(sliding_window_view(x, width, axis=-1), axis=-1)
    pad = (width // 2, width - 1 - width // 2)
    return np.pad(med, [(0, 0)] * (x.ndim - 1) + [pad], mode="edge")


def window_levels(scene: PassiveSceneSettings, result):
    """Per ship and window: the geometry, the true cone angle (deg) and the front end's normalised level at it
    (linear between beams, running median over ``SNR_MEDIAN_WINDOWS`` windows: the ship's level, not a noise peak
    that happens to fall on its cone angle)."""
    from sonartrack.sim.passive_scene import scene_geometry

    rec = result.record
    tw = np.asarray(rec.time_s, float)
    g = scene_geometry(scene, tw)
    cone = np.rad2deg(g.cone_rad)
    level = np.asarray(rec.level, float)
    at_ship = np.array([[np.interp(cone[s, k], rec.cone_deg, level[k]) for k in range(len(tw))]
                        for s in range(cone.shape[0])]).reshape(cone.shape)
    return g, cone, running_median(at_ship, SNR_MEDIAN_WINDOWS)


def window_truth(scene: PassiveSceneSettings, result):
    """Per ship and window: the true cone angle (deg), and whether the ship is above the detection threshold.

    Its SNR as the detector sees it is the front end's level at its true cone angle (:func:`window_levels`); it
    counts when that level reaches the threshold and no other ship lies within one beam (direction-cosine separation
    below the broadside beamwidth ``PassiveStages.min_separation_deg`` in rad, :func:`direction_separation`), where
    the level would be the other ship's. A noise-limited formula (z = N SNR sqrt(bins)) would overrate a weak ship
    next to loud ones: their sidelobes, not the noise, set the background spread of the normaliser. Returns
    (geometry, cone (S, T), detectable (S, T))."""
    g, cone, at_ship = window_levels(scene, result)
    sep = direction_separation(cone[:, None, :], cone[None, :, :])
    sep[np.arange(len(cone)), np.arange(len(cone))] = np.inf
    alone = sep.min(axis=1) >= np.deg2rad(result.stages.min_separation_deg) if len(cone) > 1 \
        else np.ones_like(at_ship, bool)
    return g, cone, (at_ship >= result.settings.threshold) & alone


def direction_separation(cone_a_deg, cone_b_deg) -> np.ndarray:
    """|cos(a) - cos(b)|: two cone angles' separation in the direction cosine u = cos(theta), in which a line array's
    beam has one width everywhere (about lambda / L; Van Trees 2002, sec. 2.4): two ships are resolved when this
    reaches the broadside beamwidth in radians. In cone angle the beam widens as 1 / sin(theta) towards endfire,
    so two ships 3 deg apart at 175 deg lie in one beam of an array that resolves 3 deg at broadside.

    Parameters
    ----------
    cone_a_deg, cone_b_deg : array_like
        Cone angles (deg), broadcast together.

    Returns
    -------
    ndarray
        The separation in u (dimensionless; compare with a beamwidth in rad).
    """
    return np.abs(np.cos(np.deg2rad(cone_a_deg)) - np.cos(np.deg2rad(cone_b_deg)))


def crossing_events(cone_deg: np.ndarray, beamwidth_deg: float) -> list[tuple[int, int, int, int]]:
    """Crossings: each maximal run of windows in which two ships lie within one beam of the array: their
    direction-cosine separation (:func:`direction_separation`) below the broadside beamwidth, so that the run lasts
    as long as the array cannot tell the two apart (longer near endfire, where the beam is wider in cone angle).

    Parameters
    ----------
    cone_deg : ndarray (S, T)
        True cone angles (deg).
    beamwidth_deg : float
        One beamwidth at broadside (deg).

    Returns
    -------
    list of (a, b, k0, k1)
        The two ships (a < b) and the first and last window of the run (inclusive).
    """
    out = []
    for a in range(cone_deg.shape[0]):
        for b in range(a + 1, cone_deg.shape[0]):
            close = direction_separation(cone_deg[a], cone_deg[b]) < np.deg2rad(beamwidth_deg)
            edges = np.diff(np.concatenate([[0], close.astype(int), [0]]))
            out += [(a, b, int(k0), int(k1) - 1) for k0, k1 in zip(np.nonzero(edges == 1)[0],
                                                                  np.nonzero(edges == -1)[0], strict=True)]
    return out


def axis_crossings(bearing_rad: np.ndarray, array_heading_rad: np.ndarray) -> list[tuple[int, int]]:
    """Axis crossings: wherever a ship's true side (the sign of sin(bearing - array heading)) changes between
    consecutive windows.

    Parameters
    ----------
    bearing_rad : ndarray (S, T)
        True bearings (rad, clockwise from north).
    array_heading_rad : ndarray (T,)
        The array's axis heading (rad).

    Returns
    -------
    list of (int, int)
        (ship, first window on the new side).
    """
    side = np.sin(np.asarray(bearing_rad) - np.asarray(array_heading_rad)[None]) >= 0.0
    return [(int(s), int(k) + 1) for s, k in zip(*np.nonzero(side[:, 1:] != side[:, :-1]), strict=True)]


# ---------------------------------------------------------------------------------------------------------------
# judging


def held_by_track(tracks, tw, cone_true_deg, match_deg: float) -> np.ndarray:
    """(S, T) True where a confirmed track (of ``tracks``, a :class:`~sonartrack.tracking.run.BearingTracks`) lies
    within ``match_deg`` of the ship's cone angle at window t."""
    conf = np.asarray(tracks.confirmed).astype(bool)
    k = np.searchsorted(tw, np.asarray(tracks.time_s, float)[conf])
    cone = np.asarray(tracks.bearing_deg, float)[conf]
    held = np.zeros(cone_true_deg.shape, bool)
    for s in range(cone_true_deg.shape[0]):
        near = np.abs(cone - cone_true_deg[s, np.clip(k, 0, len(tw) - 1)]) < match_deg
        held[s, k[near & (k < len(tw))]] = True
    return held


def follower(measurements, tw, cone_true_deg, t_lo: float, t_hi: float, match_deg: float) -> int | None:
    """The target following a ship over [t_lo, t_hi]: the one with the most peaks within ``match_deg`` of the
    ship's true cone angle there, if at least ``MIN_FOLLOW_SCANS``.

    Parameters
    ----------
    measurements : list of (time_s, cone_deg) arrays
        Each target's peaks.
    tw, cone_true_deg : ndarray (T,)
        The windows' times (s) and the ship's true cone angle (deg) there.
    t_lo, t_hi : float
        The span (s).
    match_deg : float
        The match distance (deg).

    Returns
    -------
    int or None
        Index into ``measurements``.
    """
    best, hits_best = None, MIN_FOLLOW_SCANS - 1
    for i, (t, cone) in enumerate(measurements):
        t, cone = np.asarray(t, float), np.asarray(cone, float)
        inside = (t >= t_lo) & (t <= t_hi)
        hits = int(np.sum(np.abs(cone[inside] - np.interp(t[inside], tw, cone_true_deg)) < match_deg))
        if hits > hits_best:
            best, hits_best = i, hits
    return best


#: what became of two ships' targets through a crossing (:func:`crossing_outcome`)
OUTCOMES = {1: "kept", 2: "swapped", 3: "jumped", 4: "lost", 5: "new target"}


def crossing_outcome(measurements, tw, cone_a, cone_b, t0: float, t1: float, window_s: float,
                     match_deg: float) -> float:
    """What became of the two targets following ships a and b over ``window_s`` before a crossing [t0, t1], seen
    over ``window_s`` after it (codes of ``OUTCOMES``): 1 kept (each ship followed by its own target), 2 swapped
    (each followed by the other's), 3 jumped (one target follows the other ship, the rest not swapped: one record
    joining two ships), 4 lost (a ship followed by no target), 5 a new target on a ship; NaN if the two ships are
    not followed by two targets before it."""
    before = [follower(measurements, tw, c, t0 - window_s, t0, match_deg) for c in (cone_a, cone_b)]
    if None in before or before[0] == before[1]:
        return float("nan")
    after = [follower(measurements, tw, c, t1, t1 + window_s, match_deg) for c in (cone_a, cone_b)]
    if after == before:
        return 1.0
    if after == before[::-1]:
        return 2.0
    if after[0] == before[1] or after[1] == before[0]:
        return 3.0
    return 4.0 if None in after else 5.0


def identity_through(measurements, tw, cone_a, cone_b, t0: float, t1: float, window_s: float,
                     match_deg: float) -> float:
    """1 if the two targets following ships a and b over ``window_s`` before a crossing [t0, t1] follow the same
    ships over ``window_s`` after it, 0 if not (swapped, merged, lost or a new target), NaN if the two ships are
    not followed by two targets before it (:func:`crossing_outcome`)."""
    code = crossing_outcome(measurements, tw, cone_a, cone_b, t0, t1, window_s, match_deg)
    return code if np.isnan(code) else float(code == 1.0)


def bearing_error_after(record_t, record_bearing_rad, truth_t, truth_bearing_rad, t_lo: float, t_hi: float) -> float:
    """Median |true bearing - truth| of a record's bearings over [t_lo, t_hi].

    Parameters
    ----------
    record_t, record_bearing_rad : ndarray (n,)
        The record's times (s) and true bearings (rad).
    truth_t, truth_bearing_rad : ndarray (T,)
        The truth's times (s) and bearings (rad), interpolated (unwrapped) to the record's times.
    t_lo, t_hi : float
        The span (s).

    Returns
    -------
    float
        The median error (deg); NaN without a bearing in the span.
    """
    from sonartrack.core.angles import wrap_angle

    t = np.asarray(record_t, float)
    inside = (t >= t_lo) & (t <= t_hi)
    if not inside.any():
        return float("nan")
    truth = np.interp(t[inside], truth_t, np.unwrap(truth_bearing_rad))
    return float(np.rad2deg(np.median(np.abs(wrap_angle(np.asarray(record_bearing_rad)[inside] - truth)))))


def diverged(state, covariance, array_xy, true_range_m: float) -> bool:
    """Whether a solution's final row has gone away: not finite, a range beyond ``DIVERGED_RANGE_FACTOR`` x the
    true range, or a speed beyond ``DIVERGED_SPEED_MPS``.

    Parameters
    ----------
    state : array (4,)
        [x, y, vx, vy] (m, m/s).
    covariance : array (4, 4)
        Its covariance.
    array_xy : array (2,)
        The array centre at the same time (m).
    true_range_m : float
        The true range (m).

    Returns
    -------
    bool
        True when diverged.
    """
    x, P = np.asarray(state, float), np.asarray(covariance, float)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(P))):
        return True
    r = float(np.hypot(*(x[:2] - np.asarray(array_xy, float))))
    return bool(r > DIVERGED_RANGE_FACTOR * true_range_m or np.hypot(x[2], x[3]) > DIVERGED_SPEED_MPS)


def normalised_errors(state, covariance, truth_state) -> tuple[float, float]:
    """NEES e^T P^-1 e of the 4-state (e = estimate - truth) and the Mahalanobis distance of the position error in
    its own 2 x 2 covariance.

    Parameters
    ----------
    state, truth_state : array (4,)
        Estimate and truth [x, y, vx, vy] (m, m/s).
    covariance : array (4, 4)
        The estimate's covariance.

    Returns
    -------
    (float, float)
        NEES (chi-square(4) for a consistent estimator) and the position error in sds; NaN for a singular P.
    """
    e = np.asarray(state, float) - np.asarray(truth_state, float)
    P = np.asarray(covariance, float)
    try:
        nees = float(e @ np.linalg.solve(P, e))
        pos = float(np.sqrt(max(e[:2] @ np.linalg.solve(P[:2, :2], e[:2]), 0.0)))
    except np.linalg.LinAlgError:
        return float("nan"), float("nan")
    return nees, pos


def match_targets(result, scene, match_deg: float) -> dict[int, int]:
    """target index -> ship index (the ship whose cone angle the target's peaks follow, median offset below
    ``match_deg``); targets following no ship are absent (false targets)."""
    from sonartrack.sim.passive_scene import scene_geometry

    out = {}
    for i, tg in enumerate(result.targets):
        cone = np.rad2deg(scene_geometry(scene, tg.track.time_s).cone_rad)  # (S, n)
        if cone.shape[0] == 0:
            continue
        off = np.median(np.abs(cone - np.asarray(tg.track.cone_deg)[None]), axis=1)
        if off.min() < match_deg:
            out[i] = int(np.argmin(off))
    return out


def longest_per_ship(result, matches: dict[int, int], n_ships: int) -> list[int | None]:
    """For each ship, the index of its longest target (None if none follows it)."""
    best: list[int | None] = [None] * n_ships
    for i, s in matches.items():
        if best[s] is None or result.targets[i].track.duration_s > result.targets[best[s]].track.duration_s:
            best[s] = i
    return best


def ml_scans(tg) -> np.ndarray:
    """Which of the target's scans (``tg.track``) its ML solution was fitted to: those its record holds (the
    bearings + frequency ML's record keeps only the scans with a tonal frequency; bool (n,))."""
    return np.isin(np.asarray(tg.track.time_s, float), np.asarray(tg.ml.record.time_s, float))


def _crb_inputs(tg, scene, ship: int, nav):
    """(times s, array positions m, the peaks' offsets from the true cone angle rad, true X0 at the first time, the
    last row's time s) over the scans the target's ML was fitted to (:func:`ml_scans`)."""
    from sonartrack.core.angles import wrap_angle
    from sonartrack.sim.passive_scene import scene_geometry

    on = ml_scans(tg)
    t = np.asarray(tg.track.time_s, float)[on]
    g = scene_geometry(scene, t)
    offsets = wrap_angle(np.deg2rad(np.asarray(tg.track.cone_deg, float)[on]) - g.cone_rad[ship])
    x0 = np.concatenate([g.ship_xy[ship, 0], g.ship_velocity[ship, 0]])
    xy, _ = nav.array_at(t)
    return t, xy, offsets, x0, float(tg.ml.solution.time_s[-1])


def target_errors(tg, scene, ship: int, nav) -> tuple[float, float, float, float]:
    """(final ML position error m, CRB position sd m at the same time, measured bearing sd deg, range determined)
    of one target, judged on the data the ML was given: the scans of its record (:func:`ml_scans`) and the time of
    its last row. The CRB (tma/batch_ml.py :func:`~sonartrack.tma.batch_ml.crb_position_sd_m`) is that of the
    true constant-velocity track over those scans, with the bearing noise of the target's own peaks there (the sd
    of their offsets from the true cone angle: the sensor's noise, whichever side the chain took), carried to the
    last row's time; the error is the last row's position against the ship's at that time."""
    from sonartrack.sim.passive_scene import scene_geometry
    from sonartrack.tma.batch_ml import crb_position_sd_m

    t, xy, offsets, x0, t_end = _crb_inputs(tg, scene, ship, nav)
    sigma = float(np.std(offsets))
    crb_sd = crb_position_sd_m(x0, t - t[0], xy, max(sigma, 1e-6), t_end - t[0])
    truth_end = scene_geometry(scene, np.array([t_end])).ship_xy[ship, 0]
    err = float(np.hypot(*(np.asarray(tg.ml.solution.state[-1, :2], float) - truth_end)))
    return err, crb_sd, float(np.rad2deg(sigma)), float(tg.ml.solution.range_flags()[-1])


def correlated_crb_sd_m(tg, scene, ship: int, nav) -> float:
    """The CRB position sd of :func:`target_errors` for errors that are AR(1) in scan order with the lag-1
    correlation of the peaks' own offsets from the truth (tma/solve.py
    :func:`~sonartrack.tma.solve.lag1_correlation`; tma/batch_ml.py
    :func:`~sonartrack.tma.batch_ml.fisher_information` with ``rho``). A reading of the ml-near-crb yardstick,
    reported beside it: a second ship in the beam makes the errors slow (lag-1 correlation 0.5-0.95 on the study's
    failures), and the white-noise CRB of the same sd then bounds an error no estimator can reach."""
    from sonartrack.tma.batch_ml import crb_position_sd_m
    from sonartrack.tma.solve import lag1_correlation

    t, xy, offsets, x0, t_end = _crb_inputs(tg, scene, ship, nav)
    return crb_position_sd_m(x0, t - t[0], xy, max(float(np.std(offsets)), 1e-6), t_end - t[0],
                             rho=lag1_correlation(offsets))


# ---------------------------------------------------------------------------------------------------------------
# one trial


def match_tolerance(config: Config, result) -> float:
    """How near a ship's cone angle a track or target must lie to follow it: ``match_deg``, or one broadside
    beamwidth of the array if wider (a small array's peaks on a ship scatter over its beam, more so towards
    endfire, where the beam widens as 1 / sin(theta))."""
    return max(config.match_deg, float(result.stages.min_separation_deg))


def _padded(values, size: int) -> np.ndarray:
    out = np.full(size, np.nan)
    v = np.asarray(values, float)[:size]
    out[: len(v)] = v
    return out


def _measurements(result) -> list[tuple[np.ndarray, np.ndarray]]:
    return [(np.asarray(tg.track.time_s, float), np.asarray(tg.track.cone_deg, float)) for tg in result.targets]


def _crossing_outputs(config: Config, result, tw, cone, detect) -> dict[str, np.ndarray]:
    """What became of the targets through each crossing (:func:`crossing_outcome`; not judged: a crossing within
    ``crossing_window_s`` of the recording's start or end, a ship not followed before it, or not detectable in half
    the windows after it) and whether the two cone angles changed order through it."""
    meas, w = _measurements(result), config.crossing_window_s
    kept, crossed = [], []
    for a, b, k0, k1 in crossing_events(cone, result.stages.min_separation_deg):
        after = (tw > tw[k1]) & (tw <= tw[k1] + w)
        # both spans inside the recording: a target cut short by the recording's end has not lost its ship
        edge = tw[k0] - w < tw[0] or tw[k1] + w > tw[-1]
        if edge or min(detect[a, after].mean(), detect[b, after].mean()) < 0.5:
            continue
        kept.append(crossing_outcome(meas, tw, cone[a], cone[b], tw[k0], tw[k1], w, match_tolerance(config, result)))
        crossed.append(float(np.sign(cone[a, k0 - 1] - cone[b, k0 - 1]) != np.sign(cone[a, k1 + 1] - cone[b, k1 + 1])))
    return {"crossing_outcome": _padded(kept, MAX_EVENTS), "crossing_crossed": _padded(crossed, MAX_EVENTS)}


def _axis_outputs(config: Config, result, g, tw, cone) -> dict[str, np.ndarray]:
    """Per axis crossing: the median error (deg) of the true bearings of the target following the ship after it,
    from 20 s to ``crossing_window_s`` + 20 s after, and whether that target also followed it before."""
    meas, w, tol = _measurements(result), config.crossing_window_s, match_tolerance(config, result)
    err, spans = [], []
    for s, k in axis_crossings(g.bearing_rad, g.array_heading_rad):
        tc = float(tw[k])
        if tc + 20.0 + w > tw[-1]:  # the span after it must lie inside the recording
            continue
        i = follower(meas, tw, cone[s], tc + 20.0, tc + 20.0 + w, tol)
        if i is None:
            continue
        rec = result.targets[i].ml.record
        err.append(bearing_error_after(rec.time_s, rec.bearing_rad, tw, g.bearing_rad[s], tc + 20.0, tc + 20.0 + w))
        spans.append(float(follower(meas, tw, cone[s], tc - 20.0 - w, tc - 20.0, tol) == i))
    return {"axis_error_deg": _padded(err, MAX_EVENTS), "axis_one_target": _padded(spans, MAX_EVENTS),
            "beamwidth_deg": np.array([result.stages.min_separation_deg])}


def side_correct(side, time_s, truth_side) -> float:
    """1 if a target's side decision (per segment between its axis crossings: ``side.side_at``) matches the true side
    in at least 90 % of its scans, 0 if not, NaN if its side is unresolved."""
    if side.side == "unresolved":
        return float("nan")
    return float(np.mean(side.side_at(time_s) == np.asarray(truth_side, object)) >= 0.9)


def _solution_row(tg, scene, ship: int, nav) -> list[float]:
    """[side right, determined, error m, CRB m, CRB of correlated errors m, position sds, ML NEES, ML diverged, IMM
    printed, IMM diverged, IMM NEES] of one target's side decision and final solutions against its ship."""
    from sonartrack.sim.passive_scene import scene_geometry

    t = np.asarray(tg.track.time_s, float)
    g = scene_geometry(scene, t)
    truth_side = np.where(np.sin(g.bearing_rad[ship] - g.array_heading_rad) >= 0.0, "starboard", "port")
    err, crb_m, _, det = target_errors(tg, scene, ship, nav)
    row = [side_correct(tg.side, t, truth_side), det, err, crb_m, correlated_crb_sd_m(tg, scene, ship, nav)]
    for sol in (tg.ml.solution, tg.sequential.solution):
        t_end = float(sol.time_s[-1])
        g = scene_geometry(scene, np.array([t_end]))
        truth = np.concatenate([g.ship_xy[ship, 0], g.ship_velocity[ship, 0]])
        nees, sds = normalised_errors(sol.state[-1], sol.covariance[-1], truth)
        gone = float(diverged(sol.state[-1], sol.covariance[-1], g.array_xy[0], float(g.range_m[ship, 0])))
        printed = float(sol.range_flags()[-1])
        row += [sds, nees, gone * printed] if sol is tg.ml.solution else [printed, gone * printed, nees]
    return row


def _solution_outputs(result, scene, nav, matches: dict[int, int]) -> dict[str, np.ndarray]:
    keys = ("side_correct", "determined", "pos_err_m", "crb_sd_m", "crb_corr_sd_m", "pos_sds", "ml_nees",
            "ml_diverged", "imm_printed", "imm_diverged", "imm_nees")
    rows = [_solution_row(result.targets[i], scene, s, nav) for i, s in sorted(matches.items())]
    cols = np.array(rows, float).reshape(-1, len(keys)).T
    return {k: _padded(c, MAX_SOLUTIONS) for k, c in zip(keys, cols, strict=True)}


def _ospa_outputs(result, g, tw, cone, above, matches) -> dict[str, np.ndarray]:
    """Mean OSPA and GOSPA (with switching) of the confirmed tracks' cone angles against the ships above the
    threshold, their switch count, and mean OSPA of the determined targets' positions (metrics/ospa.py)."""
    from sonartrack.metrics.ospa import gospa_over_time, ospa_over_time

    s_idx, k_idx = np.nonzero(above)
    tr = result.tracks
    c = np.asarray(tr.confirmed, bool)
    est = (np.asarray(tr.time_s, float)[c], np.asarray(tr.track_id)[c], np.asarray(tr.bearing_deg, float)[c, None])
    gs = gospa_over_time(tw[k_idx], s_idx, cone[s_idx, k_idx, None], *est, OSPA_CONE_DEG, 1.0, OSPA_CONE_DEG / 2)
    o_cone = ospa_over_time(tw[k_idx], cone[s_idx, k_idx, None], est[0], est[2], OSPA_CONE_DEG, 1.0)[1]
    pt, pxy = [], []
    for tg in result.targets:
        sol = tg.ml.solution
        if sol.range_flags()[-1]:
            k = (tw >= sol.time_s[0]) & (tw <= sol.time_s[-1])
            pt.append(tw[k])
            pxy.append(np.stack([np.interp(tw[k], sol.time_s, sol.state[:, j]) for j in (0, 1)], axis=1))
    pt = np.concatenate(pt) if pt else np.zeros(0)
    pxy = np.concatenate(pxy) if pxy else np.zeros((0, 2))
    o_pos = ospa_over_time(tw[k_idx], g.ship_xy[s_idx, k_idx], pt, pxy, OSPA_POSITION_M, 1.0)[1]
    mean = lambda x: float(np.mean(x)) if len(x) else float("nan")  # noqa: E731
    return {"ospa_cone_deg": np.array([mean(o_cone)]), "gospa_cone_deg": np.array([mean(gs.distance)]),
            "gospa_switches": np.array([float(np.sum(gs.switches))]), "ospa_position_m": np.array([mean(o_pos)])}


def _quality_outputs(result, tw, cone, above, match_deg: float) -> dict[str, np.ndarray]:
    """Track segments (fragmentation) and identity switches per ship, of the confirmed tracks on cone angle
    (metrics/track_quality.py, gate ``match_deg``); NaN for a ship never above the threshold."""
    from sonartrack.metrics.track_quality import associate_tracks, identity_switches, track_segments

    s_idx, k_idx = np.nonzero(above)
    tr = result.tracks
    seg, sw = np.full(cone.shape[0], np.nan), np.full(cone.shape[0], np.nan)
    if len(s_idx):
        assoc = associate_tracks(tw[k_idx], s_idx, cone[s_idx, k_idx, None], np.asarray(tr.time_s, float),
                                 np.asarray(tr.track_id, np.int64), np.asarray(tr.bearing_deg, float)[:, None],
                                 match_deg, confirmed=np.asarray(tr.confirmed, bool))
        seg[assoc.truth_ids] = track_segments(assoc)
        sw[assoc.truth_ids] = identity_switches(assoc)
    return {"segments": seg, "switches": sw}


def _ship_scene_trial(config: Config, scene: PassiveSceneSettings) -> dict[str, np.ndarray]:
    result, nav = run_chain(config, scene)
    g, cone, levels = window_levels(scene, result)
    _, _, detect = window_truth(scene, result)
    above = levels >= result.settings.threshold
    tw = np.asarray(result.record.time_s, float)
    tol = match_tolerance(config, result)
    held = held_by_track(result.tracks, tw, cone, tol)
    enough = detect.sum(axis=1) * result.settings.window_s >= config.min_detectable_s
    hold = np.array([held[s, detect[s]].mean() if enough[s] else np.nan for s in range(len(scene.ships))])
    matches = match_targets(result, scene, tol)
    o = scene.ownship
    out = {"hold": hold, "scene": np.array([scene.array.elements, scene.spacing_m, scene.sample_rate_hz,
                                            o.zigzag_turns * np.sign(o.turn_deg)], float),
           "false_targets_ships": np.array([len(result.targets) - len(matches)], float),
           "narrowband_targets": np.array([len(getattr(result, "narrowband_target_ids", ()) or ())], float)}
    out |= _crossing_outputs(config, result, tw, cone, detect) | _axis_outputs(config, result, g, tw, cone)
    out |= _solution_outputs(result, scene, nav, matches) | _ospa_outputs(result, g, tw, cone, above, matches)
    return out | _quality_outputs(result, tw, cone, above, tol)


def run_trial(config: Config, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One scene of the family and one noise-only scene of the same array and length, each with its own seed."""
    seeds = rng.integers(0, 2**31 - 1, size=2)
    scene = draw_scene(config, int(seeds[0]))
    out = _ship_scene_trial(config, scene)
    result, _ = run_chain(config, scene.model_copy(update={"seed": int(seeds[1]), "ships": []}))
    out["false_targets_noise"] = np.array([len(result.targets)], float)
    out["hours"] = np.array([scene.duration_s / 3600.0])
    return out


# ---------------------------------------------------------------------------------------------------------------
# summary and claims


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
