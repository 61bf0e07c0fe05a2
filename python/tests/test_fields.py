"""Every kind of field: constant, curvature, designed (each guidance, constraints,
density and anisotropy sources), per-vertex densities, frames and tensors, scene
descriptions as RON and as dicts. Each changes the samples the way it says."""

from __future__ import annotations

import numpy as np
import pytest

import strata_sampling as ss
from conftest import icosphere


def check(s, v, f, n):
    assert len(s) == n
    b = s.barycentrics.astype(np.float64)
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-6)
    expected = np.einsum("nj,njk->nk", b, v[f[s.face_ids]])
    np.testing.assert_allclose(s.positions, expected, atol=1e-5)


def spacing_ratio(s):
    return float(np.median(s.spacings[:, 1] / s.spacings[:, 0]))


FIELDS = {
    "default": lambda v: None,
    "constant": lambda v: ss.constant((0, 0, 1), anisotropy=3.0, density=2.0),
    "curvature": lambda v: ss.curvature(measure="Mean", floor=0.5, max_anisotropy=2.0),
    "designed curvature": lambda v: ss.designed("curvature", weight=2.0, smoothing_iterations=1),
    "designed smoothest": lambda v: ss.designed("smoothest", anisotropy=2.0),
    "designed direction": lambda v: ss.designed((0, 0, 1), solver="Direct"),
    "designed constraints": lambda v: ss.designed(
        "smoothest", constraints=[(0, (1, 0, 0)), ((0.0, 0.0, 1.0), (0, 1, 0))], cancel_distance=0.0
    ),
    "designed sources": lambda v: ss.designed(
        "curvature",
        anisotropy={"Curvature": {"min": 1.0, "max": 4.0}},
        density={"Shading": {"light": [0.0, 0.0, 1.0], "lit": 0.5, "shadow": 2.0}},
    ),
    "designed curvature density": lambda v: ss.designed(
        "smoothest", density={"Curvature": {"floor": 0.5}}, smoothness=0.2, smoothing=0.0
    ),
    "isotropic densities": lambda v: ss.isotropic(1.0 + v[:, 0] ** 2),
    "frames": lambda v: ss.frames(np.tile([0.0, 0.0, 1.0], (len(v), 1)), np.tile([4.0, 1.0], (len(v), 1))),
    "tensors": lambda v: ss.tensors(np.tile(np.diag([1.0, 2.0, 3.0]), (len(v), 1, 1))),
    "ron": lambda v: "Curvature(floor: 0.1, scale: 2.0, smoothing_iterations: 0)",
    "ron designed": lambda v: "Designed(guidance: Direction(1.0, 0.0, 0.0), weight: 0.5)",
    "from_scene": lambda v: ss.from_scene("Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0)"),
    "dict": lambda v: {"Constant": {"direction": [0, 1, 0], "anisotropy": 1.5}},
    "planar warp": lambda v: "Warp(warp: Shear(shear: 0.5), density: 1.0)",
}


@pytest.mark.parametrize("name", list(FIELDS))
def test_every_field_kind_samples(sphere, name):
    v, f = sphere
    if name == "planar warp":
        from conftest import grid

        v, f = grid(8)
    field = FIELDS[name](v)
    sampler = ss.Sampler(v, f, field)
    s = sampler.sample(3000, seed=1)
    check(s, v, f, 3000)
    # Deterministic for every field.
    assert s.positions.tobytes() == ss.Sampler(v, f, field).sample(3000, seed=1).positions.tobytes()


def test_constant_anisotropy_shows_in_the_spacings(sphere):
    v, f = sphere
    iso = ss.sample(v, f, 2000, field=ss.constant(anisotropy=1.0))
    aniso = ss.sample(v, f, 2000, field=ss.constant((0, 0, 1), anisotropy=3.0))
    assert spacing_ratio(iso) == pytest.approx(1.0, abs=5e-3)
    assert spacing_ratio(aniso) == pytest.approx(3.0, rel=0.02)


def test_density_array_moves_samples(sphere):
    v, f = sphere
    # Density 9 on the upper half, 1 on the lower: about 9x the samples per area above.
    dens = np.where(v[:, 2] > 0, 9.0, 1.0)
    s = ss.sample(v, f, 20000, field=ss.isotropic(dens), seed=2)
    up = np.count_nonzero(s.positions[:, 2] > 0.1)
    down = np.count_nonzero(s.positions[:, 2] < -0.1)
    assert 6.0 < up / down < 12.0
    uniform = ss.sample(v, f, 20000, seed=2)
    up_u = np.count_nonzero(uniform.positions[:, 2] > 0.1)
    down_u = np.count_nonzero(uniform.positions[:, 2] < -0.1)
    assert 0.9 < up_u / down_u < 1.1


def test_frames_and_tensors_agree(plane):
    v, f = plane
    # On the xy plane the tensor 4 m m^T + (I - m m^T) with a tangent m is the frame
    # (m, 4, 1): spacing ratio sqrt(4 / 1) = 2 both ways.
    m = np.tile([1.0, 0.0, 0.0], (len(v), 1))
    eig = np.tile([4.0, 1.0], (len(v), 1))
    t = 3.0 * np.einsum("ni,nj->nij", m, m) + np.eye(3)[None]
    a = ss.sample(v, f, 2000, field=ss.frames(m, eig), seed=3)
    b = ss.sample(v, f, 2000, field=ss.tensors(t), seed=3)
    assert a.positions.tobytes() == b.positions.tobytes()
    assert spacing_ratio(a) == pytest.approx(2.0, rel=1e-3)
    # The same tensor on a sphere, restricted to each tangent plane, is less
    # anisotropic where m leaves the plane: never more than 2.
    sv, sf = icosphere(2)
    c = ss.sample(sv, sf, 2000, field=ss.tensors(np.tile(t[0], (len(sv), 1, 1))), seed=3)
    assert 1.0 <= spacing_ratio(c) <= 2.0 + 1e-3


def test_designed_guidance_aligns_the_major_axis(sphere):
    v, f = sphere
    s = ss.sample(v, f, 4000, field=ss.designed((0, 0, 1), weight=10.0, smoothness=0.0), seed=1)
    # Away from the poles the major axis follows the meridians (the z direction
    # projected into the tangent plane).
    band = np.abs(s.positions[:, 2]) < 0.5
    n = s.normals[band].astype(np.float64)
    z = np.array([0.0, 0.0, 1.0]) - n[:, 2:3] * n
    z /= np.linalg.norm(z, axis=1)[:, None]
    cos = np.abs(np.einsum("ij,ij->i", s.major_axes[band], z))
    assert np.median(cos) > 0.95
