"""The engine's quality measures on point arrays: star discrepancy and the radially
averaged power spectrum, with known answers for white noise and regular grids."""

from __future__ import annotations

import numpy as np
import pytest

import strata_sampling as ss


def test_star_discrepancy_known_answers():
    # One point at (0.5, 0.5): the sup discrepancy by brute force over the boxes
    # anchored at the origin whose corners are the point's coordinates or 1, open and
    # closed.
    pts = np.array([[0.5, 0.5]])
    brute = 0.0
    for x in (0.5, 1.0):
        for y in (0.5, 1.0):
            open_count = np.sum((pts[:, 0] < x) & (pts[:, 1] < y))
            closed_count = np.sum((pts[:, 0] <= x) & (pts[:, 1] <= y))
            brute = max(brute, abs(x * y - open_count), abs(closed_count - x * y))
    assert ss.star_discrepancy(pts, kind="sup") == pytest.approx(brute)
    # A stratified set beats white noise.
    rng = np.random.default_rng(1)
    white = rng.random((1024, 2))
    i, j = np.meshgrid(np.arange(32), np.arange(32))
    jittered = (np.stack([i.ravel(), j.ravel()], axis=1) + rng.random((1024, 2))) / 32
    assert ss.star_discrepancy(jittered) < 0.5 * ss.star_discrepancy(white)
    assert ss.star_discrepancy(jittered.astype(np.float32), kind="l2") > 0.0


def test_radial_spectrum_of_white_noise_is_flat():
    rng = np.random.default_rng(2)
    sets = [rng.random((400, 2)) for _ in range(8)]
    freq, power, aniso = ss.radial_spectrum(sets, max_frequency=2.0)
    assert freq.shape == power.shape == aniso.shape and freq.dtype == np.float64
    assert np.all(np.diff(freq) > 0) and freq[-1] <= 2.0 + 1e-9
    assert abs(power.mean() - 1.0) < 0.1
    # Jittered grids: little low-frequency energy.
    i, j = np.meshgrid(np.arange(20), np.arange(20))
    grid = np.stack([i.ravel(), j.ravel()], axis=1)
    jit = [(grid + rng.random((400, 2))) / 20 for _ in range(8)]
    _, pj, _ = ss.radial_spectrum(jit, 2.0)
    low = freq < 0.5
    assert pj[low].mean() < 0.5 * power[low].mean()
    # One array works as one set.
    f1, p1, _ = ss.radial_spectrum(sets[0])
    assert len(f1) == len(p1) > 0


def test_bad_points_raise_value_error():
    with pytest.raises(ValueError, match="points must have shape"):
        ss.star_discrepancy(np.zeros((4, 3)))
    with pytest.raises(ValueError):
        ss.star_discrepancy(np.array([[0.5, 1.5]]))
    with pytest.raises(ValueError, match="kind"):
        ss.star_discrepancy(np.array([[0.5, 0.5]]), kind="linf")
    with pytest.raises(ValueError):
        ss.radial_spectrum(np.zeros((0, 2)))


def test_surface_spectrum_tells_blue_noise_from_white_on_a_sphere():
    from conftest import icosphere

    v, f = icosphere(3)
    n = 3000
    area = 4.0 * np.pi
    s = ss.sample(v, f, n, seed=3)
    rng = np.random.default_rng(4)
    white = rng.normal(size=(n, 3))
    white /= np.linalg.norm(white, axis=1)[:, None]

    def low(points, normals):
        freq, power, aniso = ss.surface_spectrum(points, normals, np.sqrt(area / n))
        assert freq.shape == power.shape == aniso.shape and freq.dtype == np.float64
        assert np.all(np.diff(freq) > 0) and freq[-1] <= 2.5 + 1e-9
        band = (freq >= 0.2) & (freq < 0.5)
        return power[band].mean(), power[freq > 1.5].mean()

    ours_low, ours_high = low(s.positions, s.normals)
    white_low, white_high = low(white, white)
    # White noise: about 1 at every frequency past the kernel's bump.
    assert 0.7 < white_low < 1.3 and 0.8 < white_high < 1.2
    # strata's samples: far less power at low frequencies, the same far out.
    assert ours_low < 0.5 * white_low
    assert 0.7 < ours_high < 1.3


def test_surface_spectrum_refuses_bad_input():
    p = np.zeros((4, 3))
    with pytest.raises(ValueError, match="differ in length"):
        ss.surface_spectrum(p, np.ones((3, 3)), 1.0)
    with pytest.raises(ValueError, match="spacing"):
        ss.surface_spectrum(p, np.ones((4, 3)), 0.0)
    with pytest.raises(ValueError, match="shape"):
        ss.surface_spectrum(np.zeros((4, 2)), np.ones((4, 3)), 1.0)
    with pytest.raises(ValueError, match="epsilon"):
        ss.surface_spectrum(p, np.ones((4, 3)), 1.0, epsilon=-1.0)
