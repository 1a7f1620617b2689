"""One version string: the installed distribution's metadata is read from ``sonartrack.__version__``."""

from importlib.metadata import version

import sonartrack


def test_distribution_version_is_the_package_version():
    assert version("sonartrack") == sonartrack.__version__
