"""Test-suite settings.

Hypothesis runs derandomized by default, so that ``pytest`` (and CI) tries the same examples
on every run and a red build always means a change, never the luck of the draw. To hunt for new
counterexamples, run ``pytest --hypothesis-profile=explore`` (random, 10× the examples) and keep
what it finds as ``@example``.

Under pytest-xdist each worker runs Numba's parallel kernels on one thread.
"""

import os
import sys
from pathlib import Path

from hypothesis import settings

if os.environ.get("PYTEST_XDIST_WORKER"):
    # the xdist workers already use every core: a parallel Numba kernel in each would only
    # oversubscribe them (the kernels draw their noise by counters: the same results)
    import numba

    numba.set_num_threads(1)

# The benchmark harness (reference paths, the pose benchmark) is not the library; tests use it.
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

settings.register_profile("default", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False, max_examples=1000)
settings.load_profile("default")
