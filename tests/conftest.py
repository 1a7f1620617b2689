"""Shared test fixtures."""

import os

import matplotlib

matplotlib.use("Agg")
# numba-compiled kernels cache into the package; keep test runs from fighting over it
os.environ.setdefault("NUMBA_CACHE_DIR", os.path.join(os.path.dirname(__file__), "..", ".numba-cache"))


def _cpu_s() -> float:
    """CPU time of this process and its waited-for children (a test's subprocesses count), in s."""
    import resource

    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


if os.environ.get("SONARTRACK_TEST_CPU_LOG"):
    # Opt-in: each test's CPU time (setup + call + teardown), one line a test, appended to the file named by the
    # variable (one file a worker with -n). On a shared machine CPU time, not wall time, says what a test costs.
    import pytest

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(item, nextitem):
        start = _cpu_s()
        yield
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
        with open(f"{os.environ['SONARTRACK_TEST_CPU_LOG']}.{worker}", "a") as log:
            log.write(f"{_cpu_s() - start:.3f}\t{item.nodeid}\n")
