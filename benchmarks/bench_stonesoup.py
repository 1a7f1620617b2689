"""Benchmark: sonartrack's drop-in JPDA inside Stone Soup against Stone Soup's own JPDA and JPDAwithEHM2.

Same hypothesiser (Stone Soup's PDAHypothesiser), same tracks, same scan, same ``associate`` call: only the
associator class differs. Scans: the 8 converging targets of bench_jpda.py (one cluster of 8 tracks, where
Stone Soup's enumerating JPDA is out of reach), the same with 4 targets (where it is not), and a whole run of
Stone Soup's JPDA tutorial scene (tests/stonesoup/conftest.py). Every associate call includes Stone Soup's
hypothesis generation, which is the same work for all; its time is printed so the association step alone can
be compared too. Each line ends with the largest weight difference from Stone Soup's result. Last line: the
bearings-only initiator's cost per call against the workaround of Stone Soup's bearing-only example.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(1, str(HERE.parent / "tests" / "stonesoup"))
from _timing import best_of  # noqa: E402


def max_weight_difference(a, b) -> float:
    """Largest |beta_a - beta_b| over the tracks and hypotheses of two associate() results."""
    diff = 0.0
    for track, multi in a.items():
        wa = {id(h.measurement) if h else None: float(h.probability) for h in multi}
        wb = {id(h.measurement) if h else None: float(h.probability) for h in b[track]}
        assert wa.keys() == wb.keys()
        diff = max(diff, max(abs(wa[k] - wb[k]) for k in wa))
    return diff


def with_hypotheses(cls, hypotheses):
    """``cls`` with its hypothesis generation replaced by ``hypotheses``: times the association step alone."""
    return type(cls.__name__, (cls,), {"generate_hypotheses": lambda self, *args, **kwargs: hypotheses})


def compare_scan(label, tracks, detections, timestamp, hypothesiser, theirs) -> None:
    """One line: associate() of ours and of each of ``theirs`` (and their association step alone), the ratios."""
    from sonartrack.stonesoup import JPDA

    hypotheses = JPDA(hypothesiser).generate_hypotheses(tracks, detections, timestamp)
    t_hyp = best_of(lambda: JPDA(hypothesiser).generate_hypotheses(tracks, detections, timestamp), 5, repeat=5)
    reference = JPDA(hypothesiser).associate(tracks, detections, timestamp)  # also loads the compiled kernel
    t_ours = best_of(lambda: JPDA(hypothesiser).associate(tracks, detections, timestamp), 5, repeat=5)
    ours_alone = with_hypotheses(JPDA, hypotheses)(hypothesiser)
    a_ours = best_of(lambda: ours_alone.associate(tracks, detections, timestamp), 20, repeat=5)
    parts = []
    for cls, n in theirs:
        diff = max_weight_difference(reference, cls(hypothesiser).associate(tracks, detections, timestamp))
        t = best_of(lambda cls=cls: cls(hypothesiser).associate(tracks, detections, timestamp), n, repeat=3)
        alone = with_hypotheses(cls, hypotheses)(hypothesiser)
        a = best_of(lambda alone=alone: alone.associate(tracks, detections, timestamp), n, repeat=3)
        parts.append(f"Stone Soup {cls.__name__} {a * 1e3:.2f} ms = {a / a_ours:.0f} x ours "
                     f"(with hypothesis generation {t * 1e3:.1f} ms = {t / t_ours:.1f} x), max |beta diff| {diff:.0e}")
    print(f"{label}: association step ours {a_ours * 1e3:.3f} ms (with Stone Soup's hypothesis generation, "
          f"{t_hyp * 1e3:.1f} ms for all: {t_ours * 1e3:.1f} ms); " + "; ".join(parts), flush=True)


def tutorial_run(theirs) -> None:
    """Stone Soup's JPDA tutorial scene, all 20 scans with the tutorial's tracker loop, ours vs ``theirs``."""
    import time

    from test_tutorial_scene import max_state_difference, run_tutorial_tracker

    from conftest import build_scene, pda_hypothesiser
    from sonartrack.stonesoup import JPDA

    scene = build_scene()
    classes = (JPDA, *theirs)
    times, results = dict.fromkeys(classes, np.inf), {}
    run_tutorial_tracker(scene, JPDA, pda_hypothesiser)  # loads the compiled kernel
    for _ in range(5):  # interleaved, best of 5: the least disturbed run of each
        for cls in classes:
            t0 = time.perf_counter()
            results[cls], _ = run_tutorial_tracker(scene, cls, pda_hypothesiser)
            times[cls] = min(times[cls], time.perf_counter() - t0)
    line = ", ".join(f"{cls.__name__} {times[cls]:.2f} s = {times[cls] / times[JPDA]:.2f} x ours, max |state diff| "
                     f"{max_state_difference(results[JPDA], results[cls]):.0e}" for cls in theirs)
    print(f"JPDA tutorial scene, 20 scans end to end (Kalman updates included): ours {times[JPDA]:.2f} s; {line}")


def bearings_initiator_run() -> None:
    """Stone Soup's bearing-only example scene (tests/stonesoup/test_bearings_initiator.py): the cost of one
    initiate() call of our held range-parameterised bank (16 EKFs, one detection a scan until release) against
    Stone Soup's SinglePointInitiator, the example's workaround (one EKF update of a given prior)."""
    from stonesoup.initiator.simple import SinglePointInitiator
    from stonesoup.types.state import GaussianState
    from test_bearings_initiator import START, example_scene, ours

    _, scans = example_scene(0, n_steps=30)

    def run_ours():
        initiator, calls = ours(), 0
        for when, detections in scans:
            calls += 1
            if initiator.initiate(detections, when):
                return calls
        return calls

    calls = run_ours()
    t_ours = best_of(run_ours, 5, repeat=5) / calls
    workaround = SinglePointInitiator(GaussianState([50.0, 0.0, 50.0, 0.0], np.eye(4), timestamp=START))
    when, detections = scans[0]
    t_theirs = best_of(lambda: workaround.initiate(detections, when), 50, repeat=5)
    print(f"bearings-only initiator, Stone Soup's bearing-only example: ours {t_ours * 1e3:.2f} ms a call "
          f"({calls} calls to release, {calls * t_ours * 1e3:.1f} ms in all) = {t_ours / t_theirs:.1f} x Stone Soup's "
          f"SinglePointInitiator from the truth ({t_theirs * 1e3:.2f} ms a call)", flush=True)


def main() -> None:
    from stonesoup.dataassociator.probability import JPDA as StoneSoupJPDA
    from stonesoup.dataassociator.probability import JPDAwithEHM2

    from bench_jpda import build

    tracks, dets, t1, hyp = build()
    compare_scan(f"8 converging targets, {len(dets)} detections", set(tracks), dets, t1, hyp, [(JPDAwithEHM2, 3)])
    tracks, dets, t1, hyp = build(n=4, radius_now=15.0)
    compare_scan(f"4 converging targets, {len(dets)} detections", set(tracks), dets, t1, hyp,
                 [(StoneSoupJPDA, 2), (JPDAwithEHM2, 5)])
    tutorial_run([StoneSoupJPDA, JPDAwithEHM2])
    bearings_initiator_run()


if __name__ == "__main__":
    main()
