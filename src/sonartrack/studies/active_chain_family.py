"""The family of scenes of study active-chain: each trial's scene drawn from axes of pulse, array, band, tow, sea.

A trial's scene is the study's base scene (``Config.scene``) with these settings replaced (issue 34 item 6):

* pulse and reverberation model, cycled over the trial index (the trial's ``SeedSequence`` spawn key, core/random.py
  ``trial_rng``): trial i runs pulse ``pulses[i % P]`` and model ``reverb_models[(i // P) % R]``, so every (pulse,
  model) pair gets the same share of any run of P R consecutive trials, whatever the workers (a generator without a
  spawn key, e.g. a test's ``default_rng``, counts as trial 0);
* drawn from the trial's generator, uniformly among the listed values: elements, carrier, LFM bandwidth, tow pair
  (source, array), reverberation level (dB added to both populations' scattering strength), number of persistent
  clutter points; the element spacing among the listed spacings the chain accepts for that band
  (systems/active/checks.py: d < c / (f_c + B / 2) and N d >= c / (f_c - B / 2) / 2; a band no spacing fits is
  redrawn); the sample rate: the base's doubled until it holds 1.25 x the occupied band;
* the maneuvering target's turn (when the base has one, named ``MANEUVERING``): rate uniform in
  ``turn_rate_deg_s`` and course change uniform in ``turn_deg`` (sign drawn), starting at the base's time.

Persistent clutter points (the issue's "clutter density"): our simulator's scatterers are fresh each ping, so a
point stationary in the world frame is a still target (speed 0) named ``clutter-<k>``, target strength uniform in
``clutter_ts_db``, placed uniformly in the box ``clutter_box_m`` (x0, x1, y0, y1) around the ownship's track. The
study scores them as clutter: never a target, a confirmed track on one is a false track, and they stay in the
reverberation-only scene. The direct blast is not an axis: our simulator does not synthesise it (sim/active_signals.py;
the independent generator in tests/worlds does, and the chain gates it from the navigation there).
"""

from __future__ import annotations

import numpy as np

from sonartrack.core.settings import Settings, setting
from sonartrack.sim.active_scene import ActiveSceneSettings, TargetSettings

#: name prefix of the persistent clutter points (still "targets" of the simulator, clutter to the study)
CLUTTER_PREFIX = "clutter-"
#: K-distribution shapes (seabed, volume) of each reverberation model: Rayleigh-like (nu large), the simulator's
#: default K, and a spikier K (the issue's "spiky scatterer population")
REVERB_SHAPES = {"rayleigh": (50.0, 50.0), "k": (1.5, 0.2), "k-spiky": (0.5, 0.1)}


class FamilySettings(Settings):
    """The axes of the family (module doc)."""

    pulses: list[str] = setting(default_factory=lambda: ["lfm", "cw"], doc="pulse types, cycled over trials",
                                unit="")
    reverb_models: list[str] = setting(default_factory=lambda: list(REVERB_SHAPES), doc="reverberation models "
                                       "(rayleigh, k, k-spiky), cycled over trials", unit="")
    elements: list[int] = setting(default_factory=lambda: [8, 16, 32, 48], doc="array sizes", unit="1")
    spacings_m: list[float] = setting(default_factory=lambda: [0.25, 0.5, 0.75, 1.0], doc="element spacings "
                                      "(those the band allows)", unit="m")
    carriers_hz: list[float] = setting(default_factory=lambda: [1000.0, 1500.0, 2400.0], doc="carriers", unit="Hz")
    bandwidths_hz: list[float] = setting(default_factory=lambda: [50.0, 100.0, 200.0], doc="LFM swept bands",
                                         unit="Hz")
    tows_m: list[list[float]] = setting(default_factory=lambda: [[300.0, 450.0], [150.0, 900.0], [500.0, 550.0]],
                                        doc="(source, array) distances behind the ship", unit="m")
    reverb_levels_db: list[float] = setting(default_factory=lambda: [0.0, 5.0, 10.0], doc="added to both "
                                            "scatterer populations' scattering strength", unit="dB")
    clutter_points: list[int] = setting(default_factory=lambda: [0, 6, 14], doc="persistent clutter points",
                                        unit="1")
    clutter_ts_db: list[float] = setting(default_factory=lambda: [15.0, 30.0], doc="their target strength range",
                                         unit="dB re 1 m^2")
    clutter_box_m: list[float] = setting(default_factory=lambda: [-15000.0, 15000.0, -5000.0, 20000.0],
                                         doc="x0, x1, y0, y1 of the box they are placed in", unit="m")
    turn_rate_deg_s: list[float] = setting(default_factory=lambda: [0.3, 1.0], doc="the maneuvering target's turn "
                                           "rate range", unit="deg/s")
    turn_deg: list[float] = setting(default_factory=lambda: [60.0, 180.0], doc="its course change range (sign "
                                    "drawn)", unit="deg")


def trial_index(rng: np.random.Generator) -> int:
    """The trial's index from its generator's spawn key (core/random.py ``trial_rng``); 0 without one."""
    key = getattr(getattr(rng.bit_generator, "seed_seq", None), "spawn_key", ())
    return int(key[-1]) if key else 0


def is_clutter(name: str) -> bool:
    return str(name).startswith(CLUTTER_PREFIX)


def target_names(scene: ActiveSceneSettings) -> list[str]:
    """The scene's real targets (its clutter points left out)."""
    return [t.name for t in scene.targets if not is_clutter(t.name)]


def _pick(rng: np.random.Generator, values: list) -> tuple[int, object]:
    k = int(rng.integers(len(values)))
    return k, values[k]


def _array_and_band(fam: FamilySettings, pulse: str, c: float, rng: np.random.Generator) -> dict:
    """Elements, carrier, bandwidth and a spacing the chain accepts (module doc), with their axis indices."""
    for _ in range(100):
        (ie, n), (ic, fc), (ib, bw) = (_pick(rng, v) for v in (fam.elements, fam.carriers_hz, fam.bandwidths_hz))
        half = 0.5 * bw if pulse == "lfm" else 0.0
        ok = [k for k, d in enumerate(fam.spacings_m) if d < c / (fc + half) and n * d >= 0.5 * c / (fc - half)]
        if ok:
            k = ok[int(rng.integers(len(ok)))]
            return {"elements": (ie, n), "carrier": (ic, fc), "bandwidth": (ib, bw), "spacing": (k, fam.spacings_m[k])}
    raise ValueError("family: no listed spacing fits any drawn band and array (list a smaller spacing)")


def _clutter(fam: FamilySettings, n: int, rng: np.random.Generator) -> list[TargetSettings]:
    x0, x1, y0, y1 = fam.clutter_box_m
    lo, hi = fam.clutter_ts_db
    return [TargetSettings(name=f"{CLUTTER_PREFIX}{k}", x_m=float(rng.uniform(x0, x1)), y_m=float(rng.uniform(y0, y1)),
                           course_deg=0.0, speed_kn=0.0, target_strength_db=float(rng.uniform(lo, hi)))
            for k in range(n)]


def _turned(t: TargetSettings, fam: FamilySettings, rng: np.random.Generator) -> TargetSettings:
    rate = float(rng.uniform(*fam.turn_rate_deg_s))
    turn = float(rng.uniform(*fam.turn_deg)) * (1.0 if rng.random() < 0.5 else -1.0)
    return t.model_copy(update={"turn_rate_deg_s": rate, "turn_deg": turn})


#: the axes recorded per trial (their index in the family's list; the pulse and model as cycled)
AXES = ("pulse", "reverb_model", "elements", "spacing", "carrier", "bandwidth", "tow", "reverb_level", "clutter")


def draw_scene(base: ActiveSceneSettings, fam: FamilySettings, rng: np.random.Generator,
               maneuvering: str) -> tuple[ActiveSceneSettings, np.ndarray]:
    """The trial's scene (module doc) and its axes' indices (:data:`AXES` order, int array)."""
    i = trial_index(rng)
    ip, pulse = i % len(fam.pulses), fam.pulses[i % len(fam.pulses)]
    im = (i // len(fam.pulses)) % len(fam.reverb_models)
    model = fam.reverb_models[im]
    ab = _array_and_band(fam, pulse, base.sound_speed_mps, rng)
    (it, tow), (il, level), (iq, n_clutter) = (_pick(rng, v) for v in (fam.tows_m, fam.reverb_levels_db,
                                                                       fam.clutter_points))
    shape_b, shape_v = REVERB_SHAPES[model]
    rv = base.reverberation
    reverb = rv.model_copy(update={
        "boundary": rv.boundary.model_copy(update={"shape": shape_b, "strength_db": min(rv.boundary.strength_db +
                                                                                        level, 0.0)}),
        "volume": rv.volume.model_copy(update={"shape": shape_v, "strength_db": min(rv.volume.strength_db + level,
                                                                                    0.0)})})
    targets = [_turned(t, fam, rng) if t.name == maneuvering and t.turn_start_s is not None else t
               for t in base.targets] + _clutter(fam, int(n_clutter), rng)
    waveform = base.waveform.model_copy(update={"kind": pulse, "carrier_hz": ab["carrier"][1],
                                                "bandwidth_hz": ab["bandwidth"][1]})
    sonar = base.sonar.model_copy(update={"elements": ab["elements"][1], "spacing_m": ab["spacing"][1],
                                          "source_tow_m": tow[0], "array_tow_m": tow[1]})
    probe = base.model_copy(update={"waveform": waveform, "targets": []})
    fs = base.sample_rate_hz
    while fs < 1.25 * probe.occupied_band_hz:
        fs *= 2.0
    scene = ActiveSceneSettings.model_validate({**base.model_dump(), "waveform": waveform.model_dump(),
                                                "sonar": sonar.model_dump(), "reverberation": reverb.model_dump(),
                                                "targets": [t.model_dump() for t in targets], "sample_rate_hz": fs})
    axes = np.array([ip, im, ab["elements"][0], ab["spacing"][0], ab["carrier"][0], ab["bandwidth"][0], it, il, iq])
    return scene, axes
