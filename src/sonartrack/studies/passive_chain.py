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
from sonartrack.sim.scene import PassiveSceneSettings, ShipSettings
from sonartrack.studies.passive_chain_claims import (
    AXIS_BEAMWIDTHS,
    AXIS_REQUIRED,
    CRB_FACTOR,
    CRB_SHARE,
    FALSE_PER_HOUR,
    HOLD_REQUIRED,
    IDENTITY_REQUIRED,
    MAX_SDS,
    claims,
    summarize,
)
from sonartrack.studies.passive_chain_measures import (
    DIVERGED_SPEED_MPS,
    FAMILY_SHIPS,
    OUTCOMES,
    axis_crossings,
    bearing_error_after,
    correlated_crb_sd_m,
    crossing_events,
    crossing_outcome,
    direction_separation,
    diverged,
    follower,
    held_by_track,
    identity_through,
    match_targets,
    normalised_errors,
    running_median,
    ship_names,
    side_correct,
    target_errors,
    window_levels,
    window_truth,
)
from sonartrack.systems.passive.settings import PassiveSettings

#: the study's surface (studies/__init__.py's contract) and the measures and requirements the report and tests read
#: here (defined in studies/passive_chain_measures.py and passive_chain_claims.py)
__all__ = [
    "CHUNK_SIZE", "PAPER", "QUICK_RUNS", "RUNS", "STUDY_ID", "TITLE", "TRIAL_VERSION", "Config", "claims",
    "run_trial", "summarize", "draw_scene", "example_scene", "run_chain", "chain_settings", "navigation",
    "AXIS_BEAMWIDTHS", "AXIS_REQUIRED", "CRB_FACTOR", "CRB_SHARE", "FALSE_PER_HOUR", "HOLD_REQUIRED",
    "IDENTITY_REQUIRED", "MAX_SDS", "DIVERGED_SPEED_MPS", "FAMILY_SHIPS", "OUTCOMES", "ship_names",
    "direction_separation", "identity_through", "running_median",
]

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
#: padded sizes of the per-trial event and solution outputs (the store keeps one shape per output)
MAX_EVENTS = 8
MAX_SOLUTIONS = 12
#: the pair's cone-angle rates differ by at least this at their crossing (else they move together: no crossing)
MIN_CROSSING_RATE_DEG_S = 0.06
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


# ---------------------------------------------------------------------------------------------------------------
# judging


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


