"""strata's one call (preprocessing plus sampling) against Open3D's Poisson disk, alternated.

Runs `strata_sampling.sample(V, F, n)` with the default cells, the same with coarser
cells (`options={"curve": {"max_cell_share": 2**-k}}` for each k of --coarse, default
12), and Open3D's
`sample_points_poisson_disk(n)` (its mesh made beforehand) one after the other,
--repeat times, in one process, and prints each one's times, medians and Open3D's
median over strata's: the ratio of the two under the same load.

With --quality, also prints peers.py's quality measures (patch spread, spectrum low
and peak) of each sampler's points from the last run, so that the speed of the coarser
cells can be weighed against what they do to the samples.

Needs Open3D (benchmark-only; see peers.py for the environment; --quality also needs
scipy). From the repository root:

    target/peers-venv/bin/python bench/python/poisson_ratio.py [--mesh PATH] [-n 100000] [--repeat 3] [--quality]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np
import open3d as o3d

import strata_sampling as ss

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    meshes = Path(os.environ.get("STRATA_MESH_DIR") or ROOT.parent / "shared" / "meshes")
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--mesh", type=Path, default=meshes / "stanford-bunny.obj")
    p.add_argument("-n", type=int, default=10**5)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--coarse", type=int, nargs="*", default=[12],
                   help="exponents k of the coarser cell settings max_cell_share 2^-k to time too")
    p.add_argument("--quality", action="store_true",
                   help="also print the quality measures of peers.py for each sampler's last points")
    args = p.parse_args()
    v, f = ss.load_mesh(args.mesh)
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
    ss.sample(v, f, 1000, progress=False)  # starts the thread pool
    runs = {
        "strata": lambda: ss.sample(v, f, args.n, seed=1, progress=False).positions,
        **{
            f"strata, max_cell_share 2^-{k}": (lambda k=k: ss.sample(
                v, f, args.n, seed=1, progress=False,
                options={"curve": {"max_cell_share": 2.0**-k}}).positions)
            for k in args.coarse
        },
        "open3d sample_points_poisson_disk": lambda: np.asarray(mesh.sample_points_poisson_disk(args.n).points),
    }
    times: dict[str, list[float]] = {k: [] for k in runs}
    last: dict[str, np.ndarray] = {}
    for _ in range(args.repeat):
        for name, fn in runs.items():
            t = time.perf_counter()
            last[name] = fn()
            times[name].append(time.perf_counter() - t)
    med = {k: statistics.median(x) for k, x in times.items()}
    for k, x in times.items():
        print(f"{k}: {', '.join(f'{t:.3f}' for t in x)} s; median {med[k]:.3f} s")
    o = med["open3d sample_points_poisson_disk"]
    print(f"Open3D / strata: {o / med['strata']:.1f}x"
          + "".join(f"; with max_cell_share 2^-{k}: {o / med[f'strata, max_cell_share 2^-{k}']:.1f}x"
                    for k in args.coarse))
    if args.quality:
        from peers import Mesh, quality  # the script's own folder is on sys.path

        m = Mesh(args.mesh)
        patches = m.patches()
        for k, pts in last.items():
            q = quality(m, patches, pts, True)
            print(f"{k}: patch spread {q['spread']:.3f}, spectrum low {q['low']:.3f}, "
                  f"peak {q['peak']:.2f} (at {q['peak_f']:.2f})")


if __name__ == "__main__":
    main()
