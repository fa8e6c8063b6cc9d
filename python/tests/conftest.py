"""Shared set-up of the layerlab Python tests.

- Without LAYERLAB_LIBRARY, use the checkout's own build (build/lib), so a
  plain `pytest` in python/ tests the library built next to it.
- matplotlib draws headless (Agg).
- Pictures go to $LAYERLAB_PY_OUT, else <checkout>/out/python/.
- Measured times (seconds, or (value, unit) pairs) print at the end of the run.
"""

import atexit
import os
import pathlib
import shutil
import tempfile

CHECKOUT = pathlib.Path(__file__).resolve().parents[2]
TESTDATA = CHECKOUT / "tests" / "data"

if not os.environ.get("LAYERLAB_LIBRARY"):
    _built = CHECKOUT / "build" / "lib" / "liblayerlab.so"
    if _built.exists():
        os.environ["LAYERLAB_LIBRARY"] = str(_built)

# Hermetic: the searches' choices go to a scratch directory, never the
# user's cache (layerlab.user_cache_dir reads LAYERLAB_CACHE_DIR first).
_cache = tempfile.mkdtemp(prefix="layerlab-cache-")
os.environ["LAYERLAB_CACHE_DIR"] = _cache
atexit.register(shutil.rmtree, _cache, True)

import matplotlib  # noqa: E402

matplotlib.use("Agg")

import pytest  # noqa: E402

TIMINGS = {}


@pytest.fixture(scope="session")
def out_dir():
    path = pathlib.Path(os.environ.get("LAYERLAB_PY_OUT") or CHECKOUT / "out" / "python")
    path.mkdir(parents=True, exist_ok=True)
    return path


@pytest.fixture(scope="session")
def timings():
    return TIMINGS


@pytest.fixture(scope="session")
def testdata_dir():
    """The project's test files (tests/data/README.md)."""
    return TESTDATA


def pytest_terminal_summary(terminalreporter):
    if TIMINGS:
        terminalreporter.write_sep("-", "layerlab measured times")
        for name, value in TIMINGS.items():
            value, unit = value if isinstance(value, tuple) else (value, "s")
            terminalreporter.write_line("%-55s %8.3f %s" % (name, value, unit))
