"""The quiet-target study's held-against-level figure: one curve per front end, the narrowband detection level
moved from the tonal axis to the broadband one."""

import numpy as np
import pytest

pytest.importorskip("matplotlib")


def test_held_figure_curves_and_level_marks():
    import matplotlib.pyplot as plt

    from sonartrack.report.figures.quiet_target import held_figure

    scenes = {"levels_db": [-20.0, -10.0, 0.0], "tonal_db": [-7.0, 3.0, 13.0],
              "held_broadband": [0.0, 0.1, 0.9], "level80_broadband": [-1.0, -2.0, 0.0],
              "held_narrowband": [0.5, 1.0, 1.0], "level80_narrowband": [-5.0, -6.0, -4.0]}
    fig = held_figure(scenes)
    ax = fig.axes[0]
    curves = [ln for ln in ax.lines if len(ln.get_xdata()) == 3]
    assert len(curves) == 2
    marks = sorted(float(ln.get_xdata()[0]) for ln in ax.lines if ln.get_marker() == "D")
    np.testing.assert_allclose(marks, [-18.0, -1.0])  # -5 dB tonal = -18 dB broadband (tonal 13 dB above)
    plt.close(fig)
