"""Bad input raises the right Python exception with the engine's message, and never
aborts or hangs the interpreter."""

from __future__ import annotations

import numpy as np
import pytest

import strata_sampling as ss
from conftest import DATA, icosphere

V, F = icosphere(1)


@pytest.mark.parametrize(
    "vertices,faces,match",
    [
        (V[:, :2], F, r"vertices must have shape \(N, 3\)"),
        (V.ravel(), F, r"vertices must have shape"),
        (V, F[:, :2], r"faces must have shape \(N, 3\)"),
        (V, np.c_[F, F[:, :1]], r"faces must have shape"),
        (V, F.astype(np.float64), r"faces must hold integers"),
        (V.astype(str), F, r"vertices must hold numbers"),
        (np.where(np.arange(len(V))[:, None] == 5, np.nan, V), F, r"vertex 5 has a non-finite coordinate"),
        (np.where(np.arange(len(V))[:, None] == 2, np.inf, V), F, r"vertex 2 has a non-finite coordinate"),
        (V, np.where(F == 7, len(V) + 3, F), r"refers to vertex %d, but the mesh has %d vertices" % (len(V) + 3, len(V))),
        (V, np.where(F == 7, -1, F), r"index -1"),
        (V, np.where(F == 7, 2**40, F), r"index 1099511627776"),
        (V, np.zeros((0, 3), dtype=np.int64), r"mesh is empty"),
        (np.zeros((3, 3)), np.array([[0, 1, 2]]), r"mesh"),
    ],
)
def test_bad_meshes_raise_value_error(vertices, faces, match):
    with pytest.raises(ValueError, match=match):
        ss.Sampler(vertices, faces)
    with pytest.raises(ValueError, match=match):
        ss.sample(vertices, faces, 10)


@pytest.mark.parametrize(
    "field,match",
    [
        (lambda: ss.constant(anisotropy=0.5), "anisotropy"),
        (lambda: ss.constant(density=-1.0), "density"),
        (lambda: ss.constant(density=float("nan")), "finite"),
        (lambda: ss.constant(direction=(0, 0, 0)), "direction"),
        (lambda: ss.curvature(floor=-1.0), "floor"),
        (lambda: ss.curvature(no_such_option=1.0), "no_such_option"),
        (lambda: ss.designed(weight=-1.0), "weight"),
        (lambda: ss.designed(solver="Fastest"), "Fastest"),
        (lambda: ss.designed(constraints=[(10**6, (1, 0, 0))]), "1000000"),
        (lambda: ss.isotropic(np.ones(len(V) - 1)), "%d values but the mesh has %d vertices" % (len(V) - 1, len(V))),
        (lambda: ss.isotropic(np.where(np.arange(len(V)) == 3, 0.0, 1.0)), "vertex 3"),
        (lambda: ss.isotropic(np.where(np.arange(len(V)) == 4, np.nan, 1.0)), "vertex 4"),
        (lambda: ss.isotropic(np.ones((len(V), 2))), "densities must have shape"),
        (lambda: ss.tensors(np.tile(-np.eye(3), (len(V), 1, 1))), "positive definite"),
        (lambda: ss.tensors(np.ones((len(V), 3))), r"tensors must have shape \(N, 3, 3\)"),
        (lambda: ss.frames(np.ones((len(V), 3)), np.ones((len(V), 3))), "eigenvalues must have shape"),
        (lambda: "Curvature(floor: )", "field description"),
        (lambda: "NoSuchField()", "NoSuchField"),
        (lambda: {"Constant": {"direction": [1, 0]}}, "field description"),
        (lambda: 42, "field must be"),
    ],
)
def test_bad_fields_raise_value_error(field, match):
    with pytest.raises(ValueError, match=match):
        ss.Sampler(V, F, field())


def test_bad_arguments_raise_value_error():
    sampler = ss.Sampler(V, F)
    with pytest.raises(ValueError, match="order"):
        sampler.sample(10, order="random")
    with pytest.raises(ValueError, match="n must be >= 0"):
        sampler.sample(-1)
    with pytest.raises(OverflowError):
        sampler.sample(10, seed=-1)
    with pytest.raises(ValueError, match="progressive order draws at most"):
        sampler.sample(2**32 + 1, order="progressive")
    with pytest.raises(ValueError, match="options"):
        ss.Sampler(V, F, options={"no_such_option": 1})
    with pytest.raises(ValueError, match="min_segment_faces"):
        ss.Sampler(V, F, options={"min_segment_faces": 0})
    with pytest.raises(ValueError, match="options"):
        ss.Sampler(V, F, options="(curve: (nonsense: 1))")
    with pytest.raises(ValueError, match="options must be"):
        ss.Sampler(V, F, options=3)


def test_options_are_applied():
    # The options of a scene file's sections, as a dict and as RON, reach the engine.
    a = ss.Sampler(V, F, ss.constant((0, 0, 1), anisotropy=3.0), options={"merge_pieces": False})
    b = ss.Sampler(V, F, ss.constant((0, 0, 1), anisotropy=3.0), options="(merge_pieces: false)")
    assert a.segments == b.segments and a.merges == 0
    coarse = ss.Sampler(V, F, options={"curve": {"max_cell_share": 0.01}})
    fine = ss.Sampler(V, F, options={"curve": {"max_cell_share": 0.0001}})
    assert coarse.cells < fine.cells
    with pytest.raises(ValueError, match="max_cell_share"):
        ss.Sampler(V, F, options={"curve": {"max_cell_share": 2.0}})


def test_files():
    with pytest.raises(OSError, match="no-such-file.obj"):
        ss.load_mesh("no-such-file.obj")
    with pytest.raises(FileNotFoundError):
        ss.load_mesh("no-such-file.ply")
    for name, match in [
        ("nan.obj", "non-finite"),
        ("out-of-range.obj", "refers to vertex"),
        ("bad-magic.ply", "ply"),
        ("truncated.ply", "file ends early"),
        ("no-faces.ply", "no `face` element"),
    ]:
        with pytest.raises(ValueError, match=match):
            ss.load_mesh(DATA / name)
    v, f = ss.load_mesh(DATA / "tetrahedron.obj")
    assert v.shape == (4, 3) and v.dtype == np.float64
    assert f.shape == (4, 3) and f.dtype == np.uint32
    assert len(ss.sample(v, f, 7)) == 7
