"""sonartrack: underwater target detection, tracking and target motion analysis.

Layers, top to bottom (each imports only from layers below it; layers on one line do not import each
other)::

    cli/   stonesoup/             the faces: command line (may use report/); Stone Soup components
    report/                       HTML report and figures
    studies/                      one module per source paper: config, one trial, summary, claims
    experiment/                   Monte Carlo runner (seeds, processes), result store, resume, claims
    systems/                      end-to-end pipelines, one run function and one settings tree each:
                                  passive, track, tma, detect, simulate
    io/                           user data in and out: contacts, bearings, navigation, WAV, TOML (atomic)
    tracking/   tma/   detection/ trackers and track management; batch and sequential TMA; MFTD
    association/                  gating, PDA, JPDA (+ amplitude), IPDA, IMM-IPDA weights
    filters/                      KF, EKF, MGEKF, IMM: predict/update on arrays
    sim/                          platforms, trajectories, sensor simulators (never imported by estimators)
    acoustics/                    sound speed, propagation and TL, sonar equation, signals, beamforming, bearings
    metrics/                      beside the algorithms (imports core/, models/ only): RMSE, CTT, ROC, CRLB
    models/                       motion and measurement models, clutter, Swerling statistics
    core/                         angles, Gaussians, linear algebra, random streams, settings, units, errors

The order is enforced by tests/architecture/test_layers.py. ``import sonartrack`` is kept light: heavy
dependencies are imported lazily by the modules that need them.
"""

__version__ = "0.1.0"

from sonartrack.core.errors import InputError  # noqa: E402  (cheap, and the one public exception)

__all__ = ["InputError", "__version__"]
