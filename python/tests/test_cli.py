"""Samples equal bit for bit to the `strata sample` CLI's for the same mesh, field,
count, seed and order, and the same preprocessing report."""

from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest

import strata_sampling as ss
from conftest import read_sample_ply

CASES = [
    # (scene field in RON, the same field from Python, count, seed, order)
    (None, None, 12345, 1, "stratified"),
    ("Constant(direction: (0.0, 1.0, 0.3), anisotropy: 2.5, density: 1.0)",
     lambda: ss.constant((0.0, 1.0, 0.3), anisotropy=2.5), 20000, 7, "stratified"),
    ("Curvature(floor: 0.3, max_anisotropy: 3.0)",
     lambda: ss.curvature(floor=0.3, max_anisotropy=3.0), 100000, 3, "stratified"),
    ("Curvature()", lambda: ss.curvature(), 5000, 11, "progressive"),
]


def run_cli(cli, tmp_path, mesh_path, field_ron, n, seed, order):
    field = f", field: {field_ron}" if field_ron else ""
    scene = tmp_path / "scene.ron"
    scene.write_text(f'(mesh: File("{mesh_path}"){field})\n')
    out = tmp_path / "samples.ply"
    run = subprocess.run(
        [str(cli), "sample", str(scene), "-n", str(n), "--seed", str(seed), "--order", order,
         "-o", str(out)],
        capture_output=True, text=True, check=True,
    )
    return read_sample_ply(out), run.stdout


def assert_equal_to_cli(s, ref):
    assert len(s) == len(ref)
    for ours, theirs in [
        (s.positions, ["x", "y", "z"]),
        (s.normals, ["nx", "ny", "nz"]),
        (s.major_axes, ["major_x", "major_y", "major_z"]),
        (s.spacings, ["spacing_major", "spacing_minor"]),
        (s.barycentrics[:, 1:], ["bary1", "bary2"]),
    ]:
        want = np.stack([ref[c] for c in theirs], axis=1)
        assert ours.tobytes() == np.ascontiguousarray(want).tobytes(), theirs
    assert s.face_ids.tobytes() == ref["face"].tobytes()
    assert s.segments.tobytes() == ref["segment"].tobytes()
    assert s.ranks.tobytes() == ref["index"].tobytes()


@pytest.mark.parametrize("field_ron,field,n,seed,order", CASES)
def test_bunny_samples_equal_the_cli(cli, tmp_path, bunny_path, bunny, field_ron, field, n, seed, order):
    ref, _ = run_cli(cli, tmp_path, bunny_path, field_ron, n, seed, order)
    v, f = bunny
    s = ss.sample(v, f, n, field=field() if field else None, seed=seed, order=order)
    assert_equal_to_cli(s, ref)
    if field_ron:
        # The scene description itself, as RON, gives the same samples.
        assert_equal_to_cli(ss.sample(v, f, n, field=field_ron, seed=seed, order=order), ref)


def test_designed_field_and_report_equal_the_cli(cli, tmp_path, bunny_path, bunny):
    ron = "Designed(guidance: Curvature(), weight: 1.0, anisotropy: Constant(2.0))"
    ref, stdout = run_cli(cli, tmp_path, bunny_path, ron, 30000, 5, "stratified")
    v, f = bunny
    sampler = ss.Sampler(v, f, ss.designed("curvature", weight=1.0, anisotropy=2.0))
    assert_equal_to_cli(sampler.sample(30000, seed=5), ref)
    m = re.search(r"surface: (\d+) singularities; \d+ segments after segmentation, (\d+) after", stdout)
    assert m, stdout
    assert sampler.singularities == int(m.group(1))
    assert sampler.segments == int(m.group(2))
    cells = re.search(r"on \d+ faces, (\d+) cells", stdout)
    assert cells and sampler.cells == int(cells.group(1))


def test_flat_mesh_equals_the_cli(cli, tmp_path, plane):
    v, f = plane
    obj = tmp_path / "plane.obj"
    lines = [f"v {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in v] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f]
    obj.write_text("\n".join(lines) + "\n")
    ron = "Constant(direction: (1.0, 1.0, 0.0), anisotropy: 3.0, density: 1.0)"
    ref, _ = run_cli(cli, tmp_path, obj, ron, 4321, 2, "stratified")
    s = ss.sample(*ss.load_mesh(obj), 4321, field=ron, seed=2)
    assert ss.Sampler(v, f, ron).path == "planar"
    assert_equal_to_cli(s, ref)
