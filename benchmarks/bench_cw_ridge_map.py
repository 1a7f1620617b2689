"""The CW clutter map fed the echoes the ridge notch hides: the default scene's rows and held % with and without it.

The chain (``sonartrack active``) is run once per scene (the default active scene simulated with a 1 s CW, seeds as
given; bench_active_rows.py ``run_scene``, cached under ``--cache``) with the echoes under each beam's ridge notch
recorded per ping (detection/cw_cells.py ``ridge_echoes``, their contacts; systems/active/run.py
``_Chain._ridge_contacts``); then the tracker stage is run twice on the SAME stored contacts: without those echoes
(the chain as on main: the map sees the tracker's contacts only) and with them (the map fed them too, and the contacts
within ``cw_ridge_window`` of one it shows still withheld from unconfirmed tracks: clutter_map.py ``echo_images``).
Printed per seed: bench_active_rows.py's report of each (rows, false, extra, held % per target) and how many contacts
the ridge echoes withheld.

Usage: ``PYTHONPATH=src python benchmarks/bench_cw_ridge_map.py [--cache /tmp/cw_ridge_map] [--seeds 1 2]``.
Measures, not tests: nothing is asserted.
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def run_scene(kind: str, seed: int, cache: Path) -> dict:
    """bench_active_rows.py's cached chain run, with each ping's ridge-echo contacts (``ridge``: time -> Contacts)."""
    import bench_active_rows as rows
    import sonartrack.systems.active.run as run_mod

    path = cache / f"ridge_{kind}_{seed}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    inner, seen = run_mod._Chain._ridge_contacts, {}

    def recording(self, cells, number, time_s):
        out = inner(self, cells, number, time_s)
        seen[round(float(time_s), 3)] = out
        return out

    run_mod._Chain._ridge_contacts = recording
    try:
        c = rows.run_scene(kind, seed, cache / "chain")
    finally:
        run_mod._Chain._ridge_contacts = inner
    c = {**c, "ridge": seen, "kind": kind, "seed": seed}
    cache.mkdir(parents=True, exist_ok=True)
    path.write_bytes(pickle.dumps(c))
    return c


def track(c: dict, with_ridge: bool):
    """bench_active_rows.py ``track`` on the stored contacts, the ridge echoes given to each step or not; returns
    (tracks, end reasons, contacts withheld by the ridge echoes)."""
    import bench_active_rows as rows
    from sonartrack.systems.active.contact_tracker import ContactTracker, ridge_map_of
    from sonartrack.systems.active.cw_tracking import cw_ridge_window

    real, count = ContactTracker.step, {}
    window = cw_ridge_window(rows.scene(c["kind"], c["seed"]).waveform.waveform(), c["settings"].sound_speed_mps)

    def step(self, t_s, contacts, ridge=None):
        self.ridge_window = window
        if with_ridge and getattr(self, "ridge_map", None) is None:
            self.ridge_map = ridge_map_of(c["settings"])
        ridge = c["ridge"].get(round(float(t_s), 3)) if with_ridge else None
        keep = real(self, t_s, contacts, ridge)
        count["n"] = list(self.ridge_counts)
        return keep

    ContactTracker.step = step
    try:
        res, reasons = rows.track(c)
    finally:
        ContactTracker.step = real
    return res, reasons, count.get("n", [0, 0])


def main() -> None:
    import bench_active_rows as rows

    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cache", default="/tmp/cw_ridge_map")
    p.add_argument("--seeds", nargs="+", type=int, default=[1, 2])
    p.add_argument("--kinds", nargs="+", default=["cw"], help="cw, cwb (bench_cw_held.py's scene b)")
    a = p.parse_args()
    for kind in a.kinds:
        for seed in a.seeds:
            c = run_scene(kind, seed, Path(a.cache))
            n_ridge = sum(len(v) for v in c["ridge"].values() if v is not None)
            print(f"{kind} seed {seed}: {n_ridge} ridge-echo contacts in {len(c['time_s'])} pings")
            for flag in (False, True):
                t0 = time.process_time()
                res, reasons, n = track(c, flag)
                print(f"    tracker stage {time.process_time() - t0:.1f} s CPU")
                rows.report(c, res, reasons, 1000.0, f"{kind.upper()} seed {seed} ridge echoes "
                            f"{'on' if flag else 'off'}")
                if flag:
                    print(f"    ridge-echo contacts shown still (summed over pings) {n[0]}, contacts the ridge map "
                          f"marked (in a known point's gate or an echo's window) {n[1]}")


if __name__ == "__main__":
    main()
