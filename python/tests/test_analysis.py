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
