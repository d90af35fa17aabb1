import os
import subprocess

import pytest


@pytest.fixture(scope="module")
def cli():
    """Runs the command-line program (MICROSIM_BINARY, set by CTest); returns the completed process."""
    binary = os.environ.get("MICROSIM_BINARY")
    if not binary:
        pytest.skip("MICROSIM_BINARY is not set (run through ctest)")

    def run(*args, check=True):
        p = subprocess.run([binary, "--quiet", *map(str, args)], capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"microsim {' '.join(map(str, args))}: {p.stderr}")
        return p

    return run
