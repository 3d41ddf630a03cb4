"""Shared fixtures of the Python binding tests (run by ctest -L python).

ctest sets PYTHONPATH to the folder holding the built module and WEFT_BINARY
to the built `weft` command line, which the parity tests run on the same
inputs. Run by hand from the repository root:

    PYTHONPATH=build/release/python WEFT_BINARY=build/release/weft \
        /usr/bin/python3 -m pytest -q python/tests
"""
import os
import pathlib
import subprocess

import numpy as np
import pytest

import weft

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def weft_bin():
    path = os.environ.get("WEFT_BINARY")
    if not path or not os.path.exists(path):
        pytest.skip("WEFT_BINARY does not name the built weft command")
    return path


@pytest.fixture(scope="session")
def cli(weft_bin):
    """Runs `weft ARGS...`; fails the test with its stderr when it fails."""

    def run(*args, cwd=None):
        r = subprocess.run([weft_bin, *map(str, args)], cwd=cwd, capture_output=True, text=True)
        assert r.returncode == 0, f"weft {' '.join(map(str, args))}: {r.stderr}"
        return r.stdout

    return run


def unit_vectors(n, rng):
    """n directions uniform on the sphere, (n, 3) float64."""
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.fixture
def rng():
    return np.random.default_rng(7)
