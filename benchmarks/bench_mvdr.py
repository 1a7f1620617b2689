"""Benchmark: MVDR (Capon) beams against the conventional beamformer, ms per 1 s window at 4 kHz; and the two
quiet-target stages of the passive chain beside them (narrowband pass, bearing-time MFTD).

16 and 32 elements (d = 2.5 m, the octave below aliasing 150-300 Hz), 181 beams, windows in batches of 32 as
the front end runs them (acoustics/beamforming.py ``cbf_powers``, acoustics/mvdr.py ``mvdr_powers``: Welch
CSM of 0.25 s segments, 50 % overlap, one Cholesky solve per bin); best of 3 repetitions. Narrowband: 16
elements, 61 beams, 75-300 Hz, 16 windows per integration (acoustics/lofar.py ``lofar_gram``). MFTD: the
passive chain's ``[btr_mftd]`` defaults on a 181-beam noise record of 120 windows, threshold calibration
excluded (it is done once per process).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from _timing import best_of  # noqa: E402

FS_HZ = 4000.0
BATCH = 32


def main() -> None:
    from sonartrack.acoustics.beamforming import BeamformerSettings, cbf_powers
    from sonartrack.acoustics.line_array import LineArray
    from sonartrack.acoustics.mvdr import mvdr_powers

    settings = BeamformerSettings()
    rng = np.random.default_rng(0)
    for n in (16, 32):
        array = LineArray(n, 2.5, 1500.0)
        band = array.band(FS_HZ)
        blocks = rng.standard_normal((BATCH, n, int(FS_HZ)))
        t_cbf = best_of(lambda: cbf_powers(blocks, FS_HZ, array, settings, band), 1, repeat=3) / BATCH  # noqa: B023
        t_mvdr = best_of(lambda: mvdr_powers(blocks, FS_HZ, array, settings, band), 1, repeat=3) / BATCH  # noqa: B023
        print(f"mvdr front end, {n} elements, band {band.low_hz:.0f}-{band.high_hz:.0f} Hz: "
              f"cbf {1e3 * t_cbf:.2f} ms/window, mvdr {1e3 * t_mvdr:.2f} ms/window ({t_mvdr / t_cbf:.1f}x), "
              f"{1.0 / t_mvdr:.0f}x real time")

    _quiet_target_stages(rng)


def _quiet_target_stages(rng) -> None:
    from sonartrack.acoustics.line_array import LineArray
    from sonartrack.acoustics.lofar import LofarSettings, lofar_gram
    from sonartrack.detection.btr_mftd import btr_mftd
    from sonartrack.systems.passive.settings import PassiveBtrMftdSettings

    array = LineArray(16, 2.5, 1500.0)
    blocks = rng.standard_normal((32, 16, int(FS_HZ)))
    t_nb = best_of(lambda: lofar_gram(iter(blocks), FS_HZ, array, LofarSettings(), 1.0), 1, repeat=3) / len(blocks)
    level = rng.standard_normal((120, 181))
    cfg = PassiveBtrMftdSettings()
    btr_mftd(level[:20], np.linspace(0, 180, 181), 1.0, cfg.pfa, cfg)  # calibrate and compile once
    t_mftd = best_of(lambda: btr_mftd(level, np.linspace(0, 180, 181), 1.0, cfg.pfa, cfg), 1, repeat=3) / 120
    print(f"quiet-target stages, 16 elements: narrowband {1e3 * t_nb:.2f} ms/window, bearing-time MFTD "
          f"{1e3 * t_mftd:.2f} ms/window")


if __name__ == "__main__":
    main()
