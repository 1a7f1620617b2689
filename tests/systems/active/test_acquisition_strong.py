"""Strong single-ping detections joining the MFTD's (systems/active/run.py with_strong): kept when no MFTD
detection holds them, dropped when one does, weak ones never."""

import numpy as np

from sonartrack.detection.cells import Detections
from sonartrack.systems.active.run import with_strong


def detections(beam, travel_s, statistic) -> Detections:
    n = len(beam)
    z = np.zeros(n)
    return Detections(np.zeros(n, np.int64), z, np.asarray(beam, float) * 3.0, np.asarray(travel_s, float),
                      z + np.nan, z + np.nan, np.asarray(statistic, float), np.asarray(beam, np.int64),
                      np.zeros(n, np.int64), np.zeros(n, np.int64))


def test_strong_single_ping_detections_join_where_the_mftd_has_none():
    mftd = detections([5], [3.0], [40.0])
    single = detections([5, 6, 20, 30, 40], [3.01, 2.98, 5.0, 7.0, 3.0], [30.0, 30.0, 25.0, 12.0, 21.0])
    out = with_strong(mftd, single, threshold=20.0, delay_step_s=0.01)
    # beam 5 / 6 at 3 s: the MFTD's target (within a beam and 3 cells); beam 30 too weak; beams 20 and 40 join
    assert sorted(out.beam.tolist()) == [5, 20, 40]
    assert out.statistic[out.beam == 5].tolist() == [40.0]
    assert len(with_strong(detections([], [], []), single, 100.0, 0.01)) == 0
