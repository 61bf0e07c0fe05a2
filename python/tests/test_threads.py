"""Behaviour in a Python process: the GIL is released while preprocessing and
sampling (another Python thread keeps running), Ctrl-C cancels a preprocessing with
KeyboardInterrupt, and samples do not depend on the worker thread count."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np

import strata_sampling as ss
from conftest import icosphere


class Counter(threading.Thread):
    """Counts in a Python loop until stopped: it advances only while the GIL is free."""

    def __init__(self):
        super().__init__(daemon=True)
        self.count = 0
        self.stop = threading.Event()

    def run(self):
        while not self.stop.is_set():
            self.count += 1


def counted(work):
    """Runs `work` beside a counting thread; returns the count reached during it."""
    c = Counter()
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        c.start()
        time.sleep(0.05)
        before = c.count
        work()
        during = c.count - before
    finally:
        c.stop.set()
        c.join()
        sys.setswitchinterval(old)
    return during


def test_gil_is_released_while_sampling_and_preprocessing():
    v, f = icosphere(5)  # 20k faces
    field = ss.designed("curvature")
    result = {}

    def build():
        result["sampler"] = ss.Sampler(v, f, field, progress=False)

    assert counted(build) > 10_000
    sampler = result["sampler"]
    assert counted(lambda: sampler.sample(2_000_000, seed=1)) > 10_000


def run_child(tmp_path, body: str) -> subprocess.CompletedProcess:
    """Runs `body` in a fresh interpreter with the tests' folder importable and `v, f`
    a 328k-face sphere, `field` a constant anisotropic field (a build of seconds)."""
    script = textwrap.dedent(
        """
        import os, signal, sys, threading, time
        sys.path.insert(0, sys.argv[1])
        import strata_sampling as ss
        from conftest import icosphere
        v, f = icosphere(7)
        field = ss.constant((0, 0, 1), anisotropy=2.0)
        """
    ) + textwrap.dedent(body)
    path = tmp_path / "child.py"
    path.write_text(script)
    here = os.path.dirname(__file__)
    # The progress line from the start (not after a second), so that what it shows
    # does not depend on how fast this machine builds.
    env = dict(os.environ, STRATA_PROGRESS_AFTER="0")
    out = subprocess.run(
        [sys.executable, str(path), here], capture_output=True, text=True, timeout=600, env=env
    )
    assert out.returncode == 0, out.stderr
    return out


def test_ctrl_c_cancels_preprocessing(tmp_path):
    # SIGINT 0.3 s into a build, during its segmentation (about 2 s here): the build
    # stops before its next stage and raises KeyboardInterrupt. Its progress line (on,
    # every 50 ms from the start) shows that parameterization and cells were never
    # entered.
    out = run_child(
        tmp_path,
        """
        threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        try:
            ss.Sampler(v, f, field, progress=True)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted")
        """,
    )
    assert out.stdout.split() == ["interrupted"], out.stdout
    assert "parameterization" not in out.stderr and "cells" not in out.stderr, out.stderr


def test_progress_line_shows_the_stages(tmp_path):
    out = run_child(
        tmp_path,
        """
        s = ss.Sampler(v, f, field, progress=True)
        print(sum(s.stage_times.values()))
        """,
    )
    assert float(out.stdout) > 0.0
    assert out.stderr.count("strata: preprocessing: ") >= 1, out.stderr
    assert "segmentation" in out.stderr and "parameterization" in out.stderr, out.stderr
    # The line is cleared at the end (a carriage return, read as a newline here, and
    # an erase).
    assert out.stderr.endswith("\n\x1b[2K"), repr(out.stderr[-40:])


def test_no_progress_line_unless_asked(capfd):
    v, f = icosphere(2)
    ss.Sampler(v, f)  # standard error is not a terminal under pytest
    ss.Sampler(v, f, progress=False)
    assert "strata:" not in capfd.readouterr().err


def test_samples_do_not_depend_on_the_thread_count(tmp_path):
    script = textwrap.dedent(
        """
        import sys
        sys.path.insert(0, sys.argv[1])
        import numpy as np
        import strata_sampling as ss
        from conftest import icosphere
        v, f = icosphere(4)
        s = ss.sample(v, f, 50_000, field=ss.curvature(), seed=3)
        t = ss.sample(v, f, 20_000, field=ss.designed("smoothest"), seed=4, order="progressive")
        np.savez(sys.argv[2], a=s.positions, b=s.face_ids, c=t.positions, d=t.barycentrics)
        """
    )
    path = tmp_path / "threads.py"
    path.write_text(script)
    here = os.path.dirname(__file__)
    results = []
    for threads in ("1", "2", "3"):
        out = tmp_path / f"t{threads}.npz"
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        subprocess.run([sys.executable, str(path), here, str(out)], env=env, check=True, timeout=600)
        results.append(np.load(out))
    for r in results[1:]:
        for k in "abcd":
            assert r[k].tobytes() == results[0][k].tobytes(), k
