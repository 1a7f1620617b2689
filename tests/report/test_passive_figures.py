"""The passive pictures' PNG writer (report/figures/passive.py ``_save_png``): one drawing, cropped to the ink plus
the stated white margin -- the picture a tight bounding box gives -- and written atomically, without pyplot."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
from matplotlib.patches import Rectangle
from PIL import Image

from sonartrack.report.figures import passive


def test_the_picture_is_the_drawing_cropped_to_its_ink_plus_the_margin(tmp_path):
    fig = passive._figure((4.0, 3.0))
    # a black block of known pixels: 1.0-2.0 in across, 1.0-1.5 in up, in figure inches
    fig.patches.append(Rectangle((1.0, 1.0), 1.0, 0.5, transform=fig.dpi_scale_trans, facecolor="black",
                                 edgecolor="none", antialiased=False))
    path = passive._save_png(fig, tmp_path / "p.png")
    img = np.asarray(Image.open(path).convert("RGB"))
    pad = round(passive.PAD_IN * passive.DPI)
    assert img.shape[:2] == (round(0.5 * passive.DPI) + 2 * pad, round(1.0 * passive.DPI) + 2 * pad)
    ink = np.any(img != 255, axis=2)
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    assert (rows[0], cols[0]) == (pad, pad) and (img.shape[0] - 1 - rows[-1], img.shape[1] - 1 - cols[-1]) == (pad, pad)
    assert [p.name for p in tmp_path.iterdir()] == ["p.png"]


def test_an_empty_picture_is_written_whole(tmp_path):
    img = Image.open(passive._save_png(passive._figure((2.0, 1.0)), tmp_path / "e.png"))
    assert img.size == (2 * passive.DPI, passive.DPI)


def test_drawn_without_pyplot(tmp_path):
    code = ("import sys; from sonartrack.report.figures import passive; "
            f"passive._save_png(passive._figure((1.0, 1.0)), {str(tmp_path / 'x.png')!r}); "
            "print('matplotlib.pyplot' in sys.modules, 'matplotlib.figure' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True"] and (tmp_path / "x.png").is_file()
