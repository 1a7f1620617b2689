"""sonartrack: underwater target detection, tracking and target motion analysis.

Layers (each imports only from layers below it)::

    cli/, report/, stonesoup/     faces: command line, HTML report and figures, Stone Soup components
    studies/                      one module per source paper
    experiment/                   Monte Carlo runner, result store, resume
    passive/                      the passive chain: array recording + navigation -> target tracks and solutions
    io/                           user data in and out
    tracking/ tma/ detection/     trackers, TMA estimators, MFTD
    association/                  gating, PDA, JPDA, IPDA, IMM-IPDA
    filters/                      KF, EKF, MGEKF, IMM on arrays
    sim/                          platforms, trajectories, sensor simulators (not used by estimators)
    acoustics/                    sound speed, propagation, sonar equation, bearings
    models/                       motion and measurement models, clutter
    core/                         angles, Gaussians, linear algebra, random streams, settings, units
    metrics/                      RMSE, CTT, ROC, CRLB (imports core/ and models/ only)

The order is enforced by tests/architecture/test_layers.py. ``import sonartrack`` is kept light: heavy
dependencies are imported lazily by the modules that need them.
"""

__version__ = "0.1.0"

from sonartrack.core.errors import InputError  # noqa: E402  (cheap, and the one public exception)

__all__ = ["InputError", "__version__"]
