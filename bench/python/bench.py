"""Benchmark of the Python package strata_sampling.

1. The binding against the engine: `Sampler.sample(n)` (new arrays) and
   `Sampler.sample_into(out)` (refilled arrays, as `strata bench` refills one buffer)
   from Python against `strata bench` (the same scene, count and machine) at 10^4 and
   10^6 samples, and the call overhead at 10^4 (Python's median minus the CLI's) and
   at 1 sample.
2. Import time and the size of the compiled module.
3. With --peers: strata (preprocessing plus sampling) beside the peers that are
   installed (Open3D's Poisson-disk and uniform samplers, trimesh's sample_surface and
   sample_surface_even), at each count: time, points produced against asked, and the
   spread of nearest-neighbour distances (coefficient of variation, lower is more even;
   needs scipy), measured the same way for all.

Usage (from the repository root, after `cargo build --release` and with the package
installed; the peers only for --peers, e.g. `pip install trimesh scipy open3d`):

    python bench/python/bench.py [--mesh PATH] [--repeat 5] [--peers]

Prints Markdown tables. The machine's load shows in the numbers: quote medians.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import strata_sampling as ss

ROOT = Path(__file__).resolve().parents[2]


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def cli_bench(cli: Path, mesh: Path, n: int, repeat: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "scene.ron"
        scene.write_text(f'(mesh: File("{mesh}"))\n')
        out = Path(tmp) / "bench.json"
        subprocess.run(
            [str(cli), "bench", str(scene), "-n", str(n), "--repeat", str(repeat), "--json", str(out)],
            check=True, capture_output=True,
        )
        return json.loads(out.read_text())


def binding(args, v, f) -> None:
    t = time.perf_counter()
    sampler = ss.Sampler(v, f, progress=False)
    pre = time.perf_counter() - t
    print(f"## strata_sampling against `strata bench` ({args.mesh.name}, {len(f)} faces, uniform field)\n")
    print("| what | Python (s) | `strata bench` (s) | ratio |")
    print("| --- | ---: | ---: | ---: |")
    results = {}
    for n in (10**4, 10**6):
        sampler.sample(n, seed=1)  # warm-up
        py = median_time(lambda: sampler.sample(n, seed=1), args.repeat)
        cli = cli_bench(args.cli, args.mesh, n, args.repeat)
        results[n] = (py, cli["sample_median_s"])
        out = sampler.sample(n, seed=1)
        into = median_time(lambda: sampler.sample_into(out, seed=1), args.repeat)
        if n == 10**4:
            print(f"| preprocessing | {pre:.3f} | {cli['preprocess_s']:.3f} | {pre / cli['preprocess_s']:.2f} |")
        cli_s = cli["sample_median_s"]
        print(f"| sample({n:.0e}) | {py:.4f} | {cli_s:.4f} | {py / cli_s:.2f} |")
        print(f"| sample_into(out of {n:.0e}) | {into:.4f} | {cli_s:.4f} | {into / cli_s:.2f} |")
    one = median_time(lambda: sampler.sample(1, seed=1), max(args.repeat, 20))
    py4, cli4 = results[10**4]
    print(f"\ncall overhead at 10^4: {1e3 * (py4 - cli4):.3f} ms (Python median minus the CLI's); "
          f"a call for 1 sample: {1e3 * one:.3f} ms\n")


def import_and_size() -> None:
    code = "import time; t = time.perf_counter(); import strata_sampling; print(time.perf_counter() - t)"
    times = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                  check=True).stdout) for _ in range(5)]
    so = next(Path(ss.__file__).parent.glob("_strata*.so"), None)
    size = f"{so.stat().st_size / 2**20:.1f} MiB" if so else "?"
    print(f"import strata_sampling: median {1e3 * statistics.median(times):.0f} ms over 5 fresh "
          f"interpreters (numpy included); compiled module {size}\n")


def nn_spread(points: np.ndarray) -> str:
    try:
        from scipy.spatial import cKDTree
    except ImportError:
        return "-"
    d, _ = cKDTree(points).query(points, k=2)
    nn = d[:, 1]
    return f"{nn.std() / nn.mean():.3f}"


def peer_samplers(v, f, args):
    samplers = {}

    def strata(n):
        return ss.sample(v, f, n, seed=1, progress=False).positions

    samplers["strata (preprocess + sample)"] = strata
    sampler = ss.Sampler(v, f, progress=False)
    samplers["strata (sample only)"] = lambda n: sampler.sample(n, seed=1).positions
    try:
        import open3d as o3d

        mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
        samplers["open3d sample_points_uniformly"] = lambda n: np.asarray(mesh.sample_points_uniformly(n).points)

        def poisson(n):
            if n > args.max_poisson:
                return None
            return np.asarray(mesh.sample_points_poisson_disk(n).points)

        samplers["open3d sample_points_poisson_disk"] = poisson
    except ImportError:
        pass
    try:
        import trimesh

        tm = trimesh.Trimesh(v, f, process=False)
        samplers["trimesh sample_surface"] = lambda n: trimesh.sample.sample_surface(tm, n, seed=1)[0]
        samplers["trimesh sample_surface_even"] = lambda n: trimesh.sample.sample_surface_even(tm, n, seed=1)[0]
    except ImportError:
        pass
    return samplers


def peers(v, f, args) -> None:
    print(f"## strata beside its peers ({args.mesh.name}, one run each)\n")
    print("| sampler | n asked | points | time (s) | NN-distance CV |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for name, fn in peer_samplers(v, f, args).items():
        for n in args.counts:
            t = time.perf_counter()
            pts = fn(n)
            took = time.perf_counter() - t
            if pts is None:
                print(f"| {name} | {n} | skipped (over --max-poisson) | | |")
                continue
            print(f"| {name} | {n} | {len(pts)} | {took:.3f} | {nn_spread(np.asarray(pts))} |")
    print()


def main() -> None:
    default_mesh = Path(os.environ.get("STRATA_MESH_DIR") or ROOT.parent / "shared" / "meshes") / "stanford-bunny.obj"
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--mesh", type=Path, default=default_mesh)
    p.add_argument("--cli", type=Path, default=ROOT / "target" / "release" / "strata")
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--peers", action="store_true")
    p.add_argument("--counts", type=int, nargs="+", default=[10**4, 10**5, 10**6])
    p.add_argument("--max-poisson", type=int, default=10**5,
                   help="largest count given to Open3D's Poisson-disk sampler (slow)")
    args = p.parse_args()
    v, f = ss.load_mesh(args.mesh)
    binding(args, v, f)
    import_and_size()
    if args.peers:
        peers(v, f, args)


if __name__ == "__main__":
    main()
