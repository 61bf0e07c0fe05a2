"""Shared fixtures of the strata_sampling tests: meshes made in code, the repository's
small test meshes, the shared real meshes (skipped when absent) and the `strata` CLI."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import strata_sampling as ss

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "meshes"


def icosphere(subdivisions: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere: an icosahedron subdivided `subdivisions` times."""
    t = (1.0 + 5.0**0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, dtype=np.float64) / np.linalg.norm(p) for p in v]
    faces = [tuple(x) for x in f]
    for _ in range(subdivisions):
        cache: dict[tuple[int, int], int] = {}

        def mid(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return np.array(verts), np.array(faces, dtype=np.int64)


def grid(k: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """A flat unit square in the xy plane, k x k quads split in two."""
    xs = np.linspace(0.0, 1.0, k + 1)
    x, y = np.meshgrid(xs, xs, indexing="xy")
    v = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    f = []
    for j in range(k):
        for i in range(k):
            a = j * (k + 1) + i
            f += [(a, a + 1, a + k + 2), (a, a + k + 2, a + k + 1)]
    return v, np.array(f, dtype=np.int64)


@pytest.fixture(scope="session")
def sphere():
    return icosphere(3)


@pytest.fixture(scope="session")
def plane():
    return grid(8)


def shared_mesh(name: str) -> Path:
    base = Path(os.environ.get("STRATA_MESH_DIR") or ROOT.parent / "shared" / "meshes")
    path = base / name
    if not path.exists():
        pytest.skip(f"{path} not found (set STRATA_MESH_DIR)")
    return path


@pytest.fixture(scope="session")
def bunny_path() -> Path:
    return shared_mesh("stanford-bunny.obj")


@pytest.fixture(scope="session")
def bunny(bunny_path):
    return ss.load_mesh(bunny_path)


@pytest.fixture(scope="session")
def cli() -> Path:
    path = Path(os.environ.get("STRATA_CLI") or ROOT / "target" / "release" / "strata")
    if not path.exists():
        pytest.skip(f"{path} not found: build it with `cargo build --release` (or set STRATA_CLI)")
    return path


def read_sample_ply(path: Path) -> np.ndarray:
    """A binary little-endian PLY of samples as a numpy record array."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    types = {"float": "<f4", "uint": "<u4", "double": "<f8", "int": "<i4"}
    fields = []
    for line in data[:end].decode().splitlines():
        parts = line.split()
        if parts[:1] == ["property"]:
            fields.append((parts[2], types[parts[1]]))
    return np.frombuffer(data[end:], dtype=np.dtype(fields))
