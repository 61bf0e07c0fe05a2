"""Shapes, dtypes, exact counts, determinism, progressive prefixes, no copy on return,
inputs in every dtype and order, and interpolation."""

from __future__ import annotations

import numpy as np
import pytest

import strata_sampling as ss

COLUMNS = {
    "positions": ((3,), np.float32),
    "normals": ((3,), np.float32),
    "face_ids": ((), np.uint32),
    "barycentrics": ((3,), np.float32),
    "major_axes": ((3,), np.float32),
    "spacings": ((2,), np.float32),
    "segments": ((), np.uint32),
    "ranks": ((), np.uint32),
}


def arrays(s):
    return {name: getattr(s, name) for name in COLUMNS}


def assert_same(a, b):
    for name in COLUMNS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), name


def test_shapes_and_dtypes(sphere):
    v, f = sphere
    s = ss.sample(v, f, 500, seed=3)
    assert len(s) == 500
    for name, (tail, dtype) in COLUMNS.items():
        a = getattr(s, name)
        assert a.shape == (500, *tail), name
        assert a.dtype == dtype, name
        assert a.flags.c_contiguous, name


@pytest.mark.parametrize("n", [0, 1, 2, 3, 1000, 12345])
def test_exact_count(sphere, n):
    v, f = sphere
    sampler = ss.Sampler(v, f)
    for order in ("stratified", "progressive"):
        s = sampler.sample(n, seed=7, order=order)
        assert len(s) == n
        assert all(a.shape[0] == n for a in arrays(s).values())


def test_samples_lie_on_their_faces(sphere):
    v, f = sphere
    s = ss.sample(v, f, 3000, field=ss.constant((1, 2, 0), anisotropy=2.0), seed=1)
    b = s.barycentrics.astype(np.float64)
    assert np.all(b >= -1e-6) and np.all(b <= 1 + 1e-6)
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-6)
    corners = v[f[s.face_ids]]
    expected = np.einsum("nj,njk->nk", b, corners)
    np.testing.assert_allclose(s.positions, expected, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(s.major_axes, axis=1), 1.0, atol=1e-5)
    # The major axis is tangent: orthogonal to the face's normal (the sample normal is
    # the interpolated vertex normal, a little off the face's on this coarse sphere).
    c = v[f[s.face_ids]]
    fn = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    fn /= np.linalg.norm(fn, axis=1)[:, None]
    assert np.abs(np.einsum("ij,ij->i", s.major_axes, fn)).max() < 1e-4
    # Anisotropy 2: spacing along the major axis is half that along the minor one
    # (less near the poles of the direction, where the per-vertex frames turn).
    ratio = s.spacings[:, 1] / s.spacings[:, 0]
    assert abs(np.median(ratio) - 2.0) < 0.02 and ratio.max() < 2.01 and ratio.min() >= 0.999
    assert np.all(s.face_ids < len(f))
    assert np.all(s.segments < ss.Sampler(v, f, ss.constant((1, 2, 0), 2.0)).segments)


def test_same_seed_same_samples_other_seed_others(sphere):
    v, f = sphere
    a = ss.sample(v, f, 2000, seed=5)
    b = ss.sample(v, f, 2000, seed=5)
    c = ss.sample(v, f, 2000, seed=6)
    assert_same(a, b)
    assert a.positions.tobytes() != c.positions.tobytes()
    sampler = ss.Sampler(v, f)
    assert_same(sampler.sample(2000, seed=5), a)
    assert_same(sampler.sample(2000, seed=5), sampler.sample(2000, seed=5))


def test_sample_into_refills_in_place(sphere):
    v, f = sphere
    sampler = ss.Sampler(v, f, ss.constant((1, 0, 0), anisotropy=2.0))
    out = sampler.sample(3000, seed=1)
    before = {name: getattr(out, name) for name in COLUMNS}
    pointers = {name: a.__array_interface__["data"][0] for name, a in before.items()}
    for seed, order in [(2, "stratified"), (3, "progressive")]:
        sampler.sample_into(out, seed=seed, order=order)
        assert_same(out, sampler.sample(3000, seed=seed, order=order))
        for name, a in before.items():
            assert getattr(out, name) is a
            assert a.__array_interface__["data"][0] == pointers[name]
    with pytest.raises(ValueError, match="order"):
        sampler.sample_into(out, order="random")


def test_progressive_prefixes_are_nested(sphere):
    v, f = sphere
    sampler = ss.Sampler(v, f, ss.constant((0, 0, 1), anisotropy=1.5))
    big = sampler.sample(5000, seed=2, order="progressive")
    for n in (1, 17, 1000, 4999):
        small = sampler.sample(n, seed=2, order="progressive")
        for name in COLUMNS:
            if name == "spacings":
                continue  # spacing is for the count drawn, not the sequence
            assert getattr(small, name).tobytes() == getattr(big, name)[:n].tobytes(), name
    np.testing.assert_array_equal(big.ranks, np.arange(5000))
    # Stratified order is not a prefix sequence: it stratifies for the count asked.
    strat = sampler.sample(1000, seed=2)
    assert strat.positions.tobytes() != big.positions[:1000].tobytes()


def test_arrays_are_handed_over_without_copy(sphere):
    v, f = sphere
    s = ss.sample(v, f, 1000)
    for name in COLUMNS:
        a = getattr(s, name)
        # numpy does not own the buffer: it is the Rust vector the samples were
        # written into, kept alive by the array's base object (not another array).
        assert not a.flags.owndata, name
        assert a.base is not None and not isinstance(a.base, np.ndarray), name
        # The attribute is the same array each time (no copy per access).
        assert getattr(s, name) is a, name
        assert a.flags.writeable, name


def test_freed_arrays_are_reused_and_kept_views_are_not(sphere):
    v, f = sphere
    sampler = ss.Sampler(v, f)
    fresh = sampler.sample(2000, seed=5)
    want = {name: getattr(fresh, name).tobytes() for name in COLUMNS}
    def addresses(s):
        return {getattr(s, name).__array_interface__["data"][0] for name in COLUMNS}

    old = addresses(fresh)
    del fresh
    # The freed buffers are written again by the next draw, with the same samples.
    again = sampler.sample(2000, seed=5)
    assert addresses(again) == old
    for name in COLUMNS:
        assert getattr(again, name).tobytes() == want[name], name
    # A view kept alive keeps its buffer: a later draw neither reuses nor changes it.
    kept = again.positions[::2]
    kept_bytes = kept.tobytes()
    kept_address = again.positions.__array_interface__["data"][0]
    del again
    other = sampler.sample(2000, seed=6)
    assert kept_address not in addresses(other)
    assert len(addresses(other) & old) == len(COLUMNS) - 1
    assert kept.tobytes() == kept_bytes
    # Smaller and larger counts draw into fitting buffers or new ones, correctly.
    del other
    for n in (1500, 900, 2500):
        got = sampler.sample(n, seed=5)
        assert got.positions.shape == (n, 3) and got.face_ids.shape == (n,)
        ref = ss.Sampler(v, f).sample(n, seed=5)
        for name in COLUMNS:
            assert getattr(got, name).tobytes() == getattr(ref, name).tobytes(), (n, name)
        del got


@pytest.mark.parametrize("vdtype", [np.float32, np.float64, np.int64])
@pytest.mark.parametrize("fdtype", [np.int32, np.int64, np.uint32, np.uint64, np.uint16])
def test_input_dtypes_give_the_same_samples(vdtype, fdtype):
    # Integer-valued coordinates, so that every vertex dtype holds them exactly.
    from conftest import grid

    v, f = grid(4)
    v = v * 4.0
    ref = ss.sample(v, f, 300, seed=1)
    got = ss.sample(v.astype(vdtype), f.astype(fdtype), 300, seed=1)
    assert_same(ref, got)


def test_fortran_order_and_lists_give_the_same_samples(sphere):
    v, f = sphere
    ref = ss.sample(v, f, 300, seed=4)
    assert_same(ref, ss.sample(np.asfortranarray(v), np.asfortranarray(f), 300, seed=4))
    assert_same(ref, ss.sample(v.tolist(), f.tolist(), 300, seed=4))
    # float32 vertices: the same as float64 vertices rounded to float32.
    v32 = v.astype(np.float32)
    assert_same(ss.sample(v32, f, 300, seed=4), ss.sample(v32.astype(np.float64), f, 300, seed=4))


def test_sample_passes_options_on(sphere):
    v, f = sphere
    field = ss.constant((0, 0, 1), anisotropy=3.0)
    options = {"curve": {"max_cell_share": 0.001}, "merge_pieces": False}
    want = ss.Sampler(v, f, field, options=options).sample(999, seed=8)
    assert_same(ss.sample(v, f, 999, field=field, seed=8, options=options, progress=False), want)
    other = ss.sample(v, f, 999, field=field, seed=8)
    assert other.positions.tobytes() != want.positions.tobytes()


def test_sampler_reports_its_preprocessing(sphere, plane):
    v, f = sphere
    s = ss.Sampler(v, f, ss.curvature())
    assert s.path == "surface"
    assert s.segments >= 1 and s.cells >= s.segments
    assert s.vertex_count == len(v) and s.face_count == len(f)
    times = s.stage_times
    assert list(times)[:2] == ["mesh", "field"]
    assert "cells" in times and all(t >= 0.0 for t in times.values())
    p = ss.Sampler(*plane)
    assert p.path == "planar" and p.segments == 1 and p.singularities == 0
    assert "Sampler(" in repr(s)


def test_interpolate_known_answers(sphere):
    v, f = sphere
    s = ss.sample(v, f, 2000, seed=9)
    # The vertex positions interpolate to the sample positions.
    np.testing.assert_allclose(ss.interpolate(f, s.face_ids, s.barycentrics, v), s.positions, atol=1e-5)
    # A constant interpolates to itself; a linear function of position to itself.
    ones = np.ones(len(v))
    np.testing.assert_allclose(ss.interpolate(f, s.face_ids, s.barycentrics, ones), 1.0, atol=1e-6)
    lin = v @ np.array([1.0, -2.0, 0.5]) + 3.0
    want = s.positions.astype(np.float64) @ np.array([1.0, -2.0, 0.5]) + 3.0
    np.testing.assert_allclose(ss.interpolate(f, s.face_ids, s.barycentrics, lin), want, atol=1e-5)
    # Hand-made case: one triangle, corner weights picked out.
    tri = np.array([[0, 1, 2]])
    values = np.array([[1.0, 0.0], [0.0, 10.0], [4.0, 4.0]])
    out = ss.interpolate(tri, [0, 0], [[1, 0, 0], [0.25, 0.25, 0.5]], values)
    np.testing.assert_allclose(out, [[1.0, 0.0], [2.25, 4.5]])
    assert out.dtype == np.float64
    # uint8 colours come back as float64.
    colours = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255]], dtype=np.uint8)
    out = ss.interpolate(tri, [0], [[0.5, 0.5, 0.0]], colours)
    np.testing.assert_allclose(out, [[127.5, 127.5, 0.0]])


def test_interpolate_rejects_bad_input():
    tri = np.array([[0, 1, 2]])
    with pytest.raises(ValueError, match="face_ids"):
        ss.interpolate(tri, [1], [[1, 0, 0]], np.zeros(3))
    with pytest.raises(ValueError, match="face_ids"):
        ss.interpolate(tri, [-1], [[1, 0, 0]], np.zeros(3))
    with pytest.raises(ValueError, match="barycentrics"):
        ss.interpolate(tri, [0], [[1, 0]], np.zeros(3))
    with pytest.raises(ValueError, match="vertices outside"):
        ss.interpolate(tri, [0], [[1, 0, 0]], np.zeros(2))
    with pytest.raises(ValueError, match="faces"):
        ss.interpolate(np.array([[0.0, 1.0, 2.0]]), [0], [[1, 0, 0]], np.zeros(3))
