"""strata_sampling beside the Python mesh samplers, on real meshes, at several counts.

For each mesh and count n: strata (preprocessing plus sampling, and sampling once
preprocessed), Open3D's `sample_points_poisson_disk` and `sample_points_uniformly`,
pymeshlab's Poisson disk (with and without `exactnumflag`) and Monte Carlo,
point-cloud-utils' Poisson disk and random, trimesh's `sample_surface` and
`sample_surface_even`. For each: the time of the call (median of --repeat runs; the
mesh objects are made beforehand), the points produced against n asked, and the
quality, measured the same way for every sampler from the positions alone:

- the face under each point is found again from the mesh (the nearest face among the
  8 of nearest centroid, by the point's distance to the triangle), so that every
  sampler is judged by the same faces and normals;
- patch spread: the RMS deviation of the point counts over 300 breadth-first patches
  of 60 faces from the count the area predicts, divided by that of independent
  uniform points (the square root of the expected count): about 1 for white noise,
  lower is more even (the measure of strata's Rust tests, normalised);
- the differential-domain spectrum (`strata_sampling.surface_spectrum`, the engine's
  DDA, differences unfolded into each point's tangent plane, in units of
  `sqrt(area / points)`): `low` is the mean power over normalised frequencies
  0.2 to 0.5 (white noise about 1, blue noise much less), `peak` the largest power
  from 0.2 on and its frequency (the kernel adds a bump below 0.2). It is measured on counts up to --spectrum-max (its
  cost grows with the count).

A peer whose time at a smaller count, scaled by the count, predicts more than
--timeout seconds is skipped at the larger count (and says so).

The peers are benchmark-only dependencies, never needed to build or test strata.
Install them in a virtual environment of the benchmark's own, with the package built
from this repository (from the repository root):

    python3 -m venv target/peers-venv
    target/peers-venv/bin/pip install numpy scipy open3d pymeshlab point-cloud-utils trimesh
    target/peers-venv/bin/pip install ./python
    target/peers-venv/bin/python bench/python/peers.py [--repeat 1] [--counts 10000 100000 1000000]

Prints one Markdown table per mesh. The machine's load shows in the times.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

import strata_sampling as ss

ROOT = Path(__file__).resolve().parents[2]


class Mesh:
    """A mesh with what the quality measures need: areas, normals, neighbours."""

    def __init__(self, path: Path):
        self.name = path.stem
        self.v, self.f = ss.load_mesh(path)
        self.f64 = self.f.astype(np.int64)
        tri = self.v[self.f64]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norm = np.linalg.norm(cross, axis=1)
        self.areas = 0.5 * norm
        self.normals = cross / np.maximum(norm, 1e-300)[:, None]
        self.tri = tri
        self.centroids = tri.mean(axis=1)
        self.tree = cKDTree(self.centroids)
        self.neighbours = self._neighbours()

    def _neighbours(self) -> list[list[int]]:
        edges: dict[tuple[int, int], list[int]] = {}
        for fi, (a, b, c) in enumerate(self.f64.tolist()):
            for e in ((a, b), (b, c), (c, a)):
                edges.setdefault((min(e), max(e)), []).append(fi)
        nb: list[list[int]] = [[] for _ in range(len(self.f64))]
        for faces in edges.values():
            for x in faces:
                nb[x].extend(y for y in faces if y != x)
        return nb

    def faces_of(self, points: np.ndarray, k: int = 8) -> np.ndarray:
        """The face nearest each point among the k of nearest centroid."""
        out = np.empty(len(points), dtype=np.int64)
        for s in range(0, len(points), 100_000):
            p = points[s : s + 100_000].astype(np.float64)
            _, cand = self.tree.query(p, k=k)
            out[s : s + len(p)] = cand[np.arange(len(p)), self._closest(p, cand).argmin(axis=1)]
        return out

    def _closest(self, p: np.ndarray, cand: np.ndarray) -> np.ndarray:
        """Squared distance from each point to each candidate triangle."""
        a, b, c = (self.tri[cand, i] for i in range(3))
        q = p[:, None, :]
        ab, ac = b - a, c - a
        n = np.cross(ab, ac)
        nn = np.maximum((n * n).sum(-1), 1e-300)
        # Barycentrics of the projection; inside: the plane distance, else the edges'.
        w = q - a
        u = (np.cross(w, ac) * n).sum(-1) / nn
        v = (np.cross(ab, w) * n).sum(-1) / nn
        inside = (u >= 0) & (v >= 0) & (u + v <= 1)
        plane = ((w * n).sum(-1)) ** 2 / nn

        def seg(x, y):
            d = y - x
            t = np.clip(((q - x) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0, 1)
            r = q - (x + t[..., None] * d)
            return (r * r).sum(-1)

        edge = np.minimum(np.minimum(seg(a, b), seg(b, c)), seg(c, a))
        return np.where(inside, plane, edge)

    def patches(self, count: int = 300, size: int = 60, seed: int = 77) -> list[np.ndarray]:
        rng = np.random.default_rng(seed)
        out = []
        for start in rng.integers(0, len(self.f64), count):
            patch, seen, i = [int(start)], {int(start)}, 0
            while len(patch) < size and i < len(patch):
                for nb in self.neighbours[patch[i]]:
                    if len(patch) < size and nb not in seen:
                        seen.add(nb)
                        patch.append(nb)
                i += 1
            out.append(np.array(patch))
        return out


def quality(mesh: Mesh, patches, pts: np.ndarray, spectrum: bool) -> dict:
    faces = mesh.faces_of(pts)
    per_face = np.bincount(faces, minlength=len(mesh.f64))
    total = mesh.areas.sum()
    n = len(pts)
    expect = np.array([n * mesh.areas[p].sum() / total for p in patches])
    counts = np.array([per_face[p].sum() for p in patches])
    spread = np.sqrt(((counts - expect) ** 2).mean()) / np.sqrt(expect.mean())
    q = {"spread": spread}
    if spectrum:
        freq, power, _ = ss.surface_spectrum(pts, mesh.normals[faces], np.sqrt(total / n))
        band = (freq >= 0.2) & (freq < 0.5)
        high = freq >= 0.2
        i = np.argmax(np.where(high, power, -np.inf))
        q.update(low=power[band].mean(), peak=power[i], peak_f=freq[i])
    return q


def samplers(mesh: Mesh) -> dict:
    v, f = mesh.v, mesh.f
    out = {}
    out["strata (preprocessing + sampling)"] = lambda n: ss.sample(v, f, n, seed=1, progress=False).positions
    sampler = ss.Sampler(v, f, progress=False)
    out["strata (sampling once preprocessed)"] = lambda n: sampler.sample(n, seed=1).positions
    try:
        import open3d as o3d

        tm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
        out["open3d sample_points_poisson_disk"] = lambda n: np.asarray(tm.sample_points_poisson_disk(n).points)
        out["open3d sample_points_uniformly"] = lambda n: np.asarray(tm.sample_points_uniformly(n).points)
    except ImportError:
        pass
    try:
        import pymeshlab

        def meshlab(filt, **kw):
            def run(n):
                ms = pymeshlab.MeshSet()
                ms.add_mesh(pymeshlab.Mesh(v, f.astype(np.int32)))
                getattr(ms, filt)(samplenum=n, **kw)
                return ms.current_mesh().vertex_matrix()

            return run

        out["pymeshlab poisson disk"] = meshlab("generate_sampling_poisson_disk")
        out["pymeshlab poisson disk, exactnumflag"] = meshlab("generate_sampling_poisson_disk", exactnumflag=True)
        out["pymeshlab montecarlo"] = meshlab("generate_sampling_montecarlo")
    except ImportError:
        pass
    try:
        import point_cloud_utils as pcu

        fi = f.astype(np.int32)

        def pcu_points(fid, bc):
            return pcu.interpolate_barycentric_coords(fi, fid, bc, v)

        out["point-cloud-utils poisson disk"] = lambda n: pcu_points(*pcu.sample_mesh_poisson_disk(v, fi, n, random_seed=1))
        out["point-cloud-utils random"] = lambda n: pcu_points(*pcu.sample_mesh_random(v, fi, n, random_seed=1))
    except ImportError:
        pass
    try:
        import trimesh

        tmesh = trimesh.Trimesh(v, f, process=False)
        out["trimesh sample_surface"] = lambda n: trimesh.sample.sample_surface(tmesh, n, seed=1)[0]
        out["trimesh sample_surface_even"] = lambda n: trimesh.sample.sample_surface_even(tmesh, n, seed=1)[0]
    except ImportError:
        pass
    return out


def run(mesh: Mesh, args) -> None:
    patches = mesh.patches()
    print(f"## {mesh.name} ({len(mesh.f)} faces), median of {args.repeat} run(s)\n")
    print("| sampler | n asked | points | time (s) | patch spread | spectrum low | peak (at f) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, fn in samplers(mesh).items():
        last = None  # (n, seconds)
        for n in args.counts:
            if last and last[1] * n / last[0] > args.timeout:
                print(f"| {name} | {n} | skipped: {last[1]:.1f} s at {last[0]} predicts over {args.timeout:.0f} s | | | | |", flush=True)
                continue
            times, pts = [], None
            for _ in range(args.repeat):
                t = time.perf_counter()
                pts = np.asarray(fn(n))
                times.append(time.perf_counter() - t)
            took = statistics.median(times)
            last = (n, took)
            q = quality(mesh, patches, pts, len(pts) <= args.spectrum_max and len(pts) > 0)
            spec = f"{q['low']:.3f} | {q['peak']:.2f} ({q['peak_f']:.2f})" if "low" in q else "- | -"
            print(f"| {name} | {n} | {len(pts)} | {took:.3f} | {q['spread']:.3f} | {spec} |", flush=True)
    print()


def main() -> None:
    meshes = Path(os.environ.get("STRATA_MESH_DIR") or ROOT.parent / "shared" / "meshes")
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--meshes", type=Path, nargs="+",
                   default=[meshes / "stanford-bunny.obj", meshes / "spot.obj"])
    p.add_argument("--counts", type=int, nargs="+", default=[10**4, 10**5, 10**6])
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--timeout", type=float, default=60.0,
                   help="skip a sampler at a count where its time at the last count, scaled, exceeds this")
    p.add_argument("--spectrum-max", type=int, default=10**5,
                   help="largest point count whose spectrum is measured")
    args = p.parse_args()
    for path in args.meshes:
        run(Mesh(path), args)


if __name__ == "__main__":
    main()
