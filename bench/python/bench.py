"""Benchmark of the Python package strata_sampling against the engine.

1. The binding against `strata bench` (the same scene, count and machine) at 10^4 and
   10^6 samples: `Sampler.sample(n)` in a loop that lets each result go (its memory is
   reused by the next call), `sample(n)` with every result kept (fresh memory each
   call), and `Sampler.sample_into(out)` (refilled arrays, as `strata bench` refills
   one buffer); the call overhead at 10^4 (Python's median minus the CLI's) and at 1
   sample.
2. Import time and the size of the compiled module.

The peers (Open3D, pymeshlab, point-cloud-utils, trimesh) are in `peers.py` beside
this file, with their own install instructions.

Usage (from the repository root, after `cargo build --release -p strata-systems --bin
strata` and with the package installed, e.g. `pip install ./python`):

    python bench/python/bench.py [--mesh PATH] [--repeat 5]

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
        kept = []
        fresh = median_time(lambda: kept.append(sampler.sample(n, seed=1)), args.repeat)
        del kept
        cli = cli_bench(args.cli, args.mesh, n, args.repeat)
        results[n] = (py, cli["sample_median_s"])
        out = sampler.sample(n, seed=1)
        into = median_time(lambda: sampler.sample_into(out, seed=1), args.repeat)
        if n == 10**4:
            print(f"| preprocessing | {pre:.3f} | {cli['preprocess_s']:.3f} | {pre / cli['preprocess_s']:.2f} |")
        cli_s = cli["sample_median_s"]
        print(f"| sample({n:.0e}), results let go | {py:.4f} | {cli_s:.4f} | {py / cli_s:.2f} |")
        print(f"| sample({n:.0e}), results kept | {fresh:.4f} | {cli_s:.4f} | {fresh / cli_s:.2f} |")
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


def main() -> None:
    default_mesh = Path(os.environ.get("STRATA_MESH_DIR") or ROOT.parent / "shared" / "meshes") / "stanford-bunny.obj"
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--mesh", type=Path, default=default_mesh)
    p.add_argument("--cli", type=Path, default=ROOT / "target" / "release" / "strata")
    p.add_argument("--repeat", type=int, default=5)
    args = p.parse_args()
    v, f = ss.load_mesh(args.mesh)
    binding(args, v, f)
    import_and_size()


if __name__ == "__main__":
    main()
