"""symsphere._threads: numba's threads wait passively; importing and sampling leave os.environ alone."""

import os
import subprocess
import sys

import numba
import pytest

PROBE = """
import os, json
before = dict(os.environ)
import symsphere
after_import = dict(os.environ)
symsphere.sample_sphere(48)
after_sampling = dict(os.environ)
print(json.dumps([after_import == before, after_sampling == before, os.environ.get("OMP_WAIT_POLICY")]))
"""


@pytest.mark.parametrize("preset", [None, "active"])
def test_threads_wait_passively_unless_the_user_says_otherwise_and_environ_is_untouched(preset):
    # Spinning OpenMP threads starve numpy's BLAS threads (docs/design.md, "Threads"): the kernels start
    # numba's threads with OMP_WAIT_POLICY=passive unless the user set it, and put os.environ back.
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    env["OMP_DISPLAY_ENV"] = "true"  # libgomp prints the settings it took, when it is loaded
    if preset:
        env["OMP_WAIT_POLICY"] = preset
    result = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    import json

    unchanged_by_import, unchanged_by_sampling, policy = json.loads(result.stdout.splitlines()[-1])
    assert unchanged_by_import and unchanged_by_sampling
    assert policy == preset
    if numba.config.THREADING_LAYER in ("default", "omp") and "OPENMP DISPLAY ENVIRONMENT" in result.stderr:
        assert f"OMP_WAIT_POLICY = '{(preset or 'passive').upper()}'" in result.stderr
