"""Shared fixtures of the Python tests: the repository root, the CLI binary, a cube mesh."""
import os
import pathlib

import numpy as np
import pytest

ROOT = pathlib.Path(os.environ.get("SDFT_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


@pytest.fixture
def root():
    return ROOT


@pytest.fixture
def cli():
    path = os.environ.get("SDFT_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("SDFT_CLI (the sdftrace binary) not set; run through ctest")
    return path


def cube_mesh(half=0.5):
    """An axis-aligned cube of half-size `half` centred at the origin, outward-facing triangles."""
    v = np.array([[x, y, z] for z in (-half, half) for y in (-half, half) for x in (-half, half)],
                 np.float32)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    f = []
    for a, b, c, d in quads:
        f += [(a, b, c), (a, c, d)]
    return v, np.array(f, np.int32)


def box_distance(p, half=0.5):
    """The exact signed distance of that cube."""
    q = np.abs(p) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(np.max(q, axis=1), 0.0)
    return outside + inside
