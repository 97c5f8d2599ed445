"""Measures the Python package's cost over the Rust library: per-call overhead and a
1000-point noise curve, against `pendkit bench` (the same library calls timed in Rust, in
one process, no Python).

    python crates/interface/python/bench.py [path/to/pendkit]

Build both with the same profile for a fair comparison (run-tests.sh and `pip install`
use `--profile python`; `cargo build -p pendkit-cli --profile python` gives the matching
command line at target/python/pendkit). Prints medians over repetitions, in µs.
"""

import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import pendkit

REPO = Path(__file__).resolve().parents[3]


def median_time(call, repeat, inner=1):
    """(median, minimum) seconds of one call over `repeat` samples of `inner` calls each
    (the minimum is the steadier figure on a loaded machine)."""
    samples = []
    for _ in range(repeat):
        start = time.perf_counter()
        for _ in range(inner):
            call()
        samples.append((time.perf_counter() - start) / inner)
    return statistics.median(samples), min(samples)


def rust_noise(cli, points, repeat):
    """`pendkit bench quad --stage 2 --noise x3 --points N`: the noise phase's median (s)."""
    out = subprocess.run(
        [cli, "bench", "quad", "--stage", "2", "--noise", "x3", "--points", str(points),
         "--repeat", str(repeat), "--json"],
        capture_output=True, text=True, check=True,
    ).stdout
    phases = {p["name"]: p for p in json.loads(out)["phases"]}
    noise = phases["noise"]
    return (noise["median_s"], noise["min_s"]), json.loads(out)["total_median_s"]


def main():
    cli = sys.argv[1] if len(sys.argv) > 1 else str(REPO / "target" / "python" / "pendkit")
    result = pendkit.Model("quad").run()
    us = 1e6

    one = np.array([0.1])
    grid = pendkit.log_grid(0.1, 100.0, 1000)  # the grid `pendkit bench` uses
    py_1 = median_time(lambda: result.noise("x3", one), 50, 20)
    py_1000 = median_time(lambda: result.noise("x3", grid), 30)
    py_tf_1 = median_time(lambda: result.tf("force:x3", "x3", one), 50, 20)
    py_getter = median_time(lambda: result.stage, 50, 1000)
    py_run = median_time(lambda: pendkit.Model("quad").run(), 10)
    rust_1, rust_run = rust_noise(cli, 1, 200)
    rust_1000, _ = rust_noise(cli, 1000, 30)

    print(f"pendkit {pendkit.__version__}, quad stage 2, thermal noise of x3; "
          "median / minimum over repetitions")
    print(f"trivial call (Result.stage getter): {py_getter[0] * us:.3f} µs")
    print(f"tf, 1 point, Python: {py_tf_1[0] * us:.2f} / {py_tf_1[1] * us:.2f} µs")
    for name, py, rust, scale, unit in [("noise, 1 point", py_1, rust_1, us, "µs"),
                                        ("noise, 1000 points", py_1000, rust_1000, 1e3, "ms")]:
        print(f"{name}: Python {py[0] * scale:.3f} / {py[1] * scale:.3f} {unit}, "
              f"Rust {rust[0] * scale:.3f} / {rust[1] * scale:.3f} {unit}, "
              f"difference {(py[0] - rust[0]) * us:.2f} / {(py[1] - rust[1]) * us:.2f} µs, "
              f"ratio {py[0] / rust[0]:.3f} / {py[1] / rust[1]:.3f}")
    print(f"build + run stage 2: Python {py_run[0] * 1e3:.3f} ms, Rust {rust_run * 1e3:.3f} ms")

if __name__ == "__main__":
    main()
