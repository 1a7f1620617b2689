"""Figures: every plot of the package lives here, one module per domain or study.

Studies are simulate -> estimate -> summarize -> claims; the pictures of a study's summary are drawn
by ``report/figures/<study module>.py`` (``figures(summary, config) -> {name: Figure}``, the key
``"scenario"`` first in the report). The command line's pictures (waterfalls, tracks, TL fields,
tactical pictures) sit in the domain modules beside them. matplotlib is imported inside the
functions, so importing this package is cheap.
"""

from __future__ import annotations

import importlib

#: study id -> module holding that study's ``figures(summary, config)``.
STUDY_FIGURES = {
    "jpda-amplitude": "sonartrack.report.figures.jpda_amplitude",
    "mftd": "sonartrack.report.figures.mftd",
    "mftd-sensitivity": "sonartrack.report.figures.mftd_sensitivity",
    "bftma-imm": "sonartrack.report.figures.bftma_imm",
    "bftma-sensitivity": "sonartrack.report.figures.bftma_sensitivity",
    "tma-propagation": "sonartrack.report.figures.tma_propagation",
    "tma-sensitivity": "sonartrack.report.figures.tma_sensitivity",
    "bistatic-imm-ipda": "sonartrack.report.figures.bistatic_imm_ipda",
    "passive-chain": "sonartrack.report.figures.passive_chain",
    "quiet-target": "sonartrack.report.figures.quiet_target",
    "active-chain": "sonartrack.report.figures.active",
    "manoeuvring-target": "sonartrack.report.figures.manoeuvring_target",
}


def study_figures(study_id: str, summary: dict, config) -> dict:
    """The figures of one study's summary, ``{name: matplotlib Figure}``."""
    import matplotlib

    matplotlib.use("Agg")
    name = STUDY_FIGURES.get(study_id)
    if name is None:  # a study without pictures (e.g. a user's own, run through the same pipeline)
        return {}
    return importlib.import_module(name).figures(summary, config)

