#!/usr/bin/env python3
"""Side-by-side timing: pygwinc 0.6.2's quad suspension thermal noise against pendkit's.

Both compute the test mass's longitudinal suspension thermal noise of the aLIGO quad over
the same log-spaced grids (0.1 to 100 Hz, the grid `pendkit bench --noise` uses; 1000 and
10,000 points by default), interleaved in one run: each round times pygwinc, then pendkit,
for every grid size, so a change in the machine's load hits both sides alike.

- pygwinc: `precomp_suspension(f, ifo)` followed by `suspension_thermal(f, ifo.Suspension,
  pc)` on the aLIGO budget, timed together in this process (`time.perf_counter`), median
  of `--repeat` calls per round. Loading the budget is done once, outside the timing.
- pendkit: `pendkit bench quad --stage 2 --noise x3 --points N --repeat R --json`, which
  times every phase in its own process and prints per phase the median over R
  repetitions: `noise` (all N points of the thermal noise) and `total_median_s` (build,
  equilibrium, stage 2 and modes, from the model's name). The process start-up is not
  timed on either side.

Printed per grid size, as the median over the rounds and as each side's fastest round
(the least disturbed, on a loaded machine): pygwinc's time, pendkit's noise phase,
pendkit's whole pipeline (build to modes plus noise), and the ratios pygwinc/pendkit
(above 1: pendkit is faster).

The script makes its own virtual environment, `benches/.venv-gwinc` (git-ignored), with
gwinc==0.6.2 the first time (it needs the network then), and runs itself again inside it.
`--venv DIR` uses another environment that has gwinc. pendkit's release binary is built
with cargo unless `--pendkit PATH` names one. It is a benchmark, not a test: CI does not
run it.

    python3 benches/vs_pygwinc.py [--points 1000,10000] [--rounds 5] [--repeat 20]
                                  [--pendkit PATH] [--venv DIR]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DEFAULT_VENV = REPO / "benches" / ".venv-gwinc"
GWINC_VERSION = "0.6.2"
# The band of `pendkit bench --noise` (crates/interface/pendkit/src/lib.rs, `bench`): log-spaced,
# 0.1 to 100 Hz, end points included. pygwinc gets exactly the same grid.
BAND_HZ = (0.1, 100.0)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--points", default="1000,10000",
                   help="grid sizes, comma-separated (default 1000,10000)")
    p.add_argument("--rounds", type=int, default=5,
                   help="interleaved rounds (default 5)")
    p.add_argument("--repeat", type=int, default=20,
                   help="timed calls per side per round (default 20)")
    p.add_argument("--pendkit", type=Path,
                   help="pendkit binary (default: build target/release/pendkit with cargo)")
    p.add_argument("--venv", type=Path, default=DEFAULT_VENV,
                   help=f"virtual environment with gwinc (default {DEFAULT_VENV})")
    args = p.parse_args()
    try:
        args.points = [int(n) for n in args.points.split(",")]
    except ValueError:
        p.error(f"--points {args.points}: expected whole numbers separated by commas")
    if any(n < 2 for n in args.points) or args.rounds < 1 or args.repeat < 1:
        p.error("--points must be at least 2 each, --rounds and --repeat at least 1")
    return args


def venv_python(venv: Path) -> Path:
    return venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")


def ensure_gwinc(args):
    """Runs this script again inside a virtual environment with gwinc, making it if needed."""
    try:
        import gwinc  # noqa: F401

        if gwinc.__version__ == GWINC_VERSION:
            return
        print(f"note: gwinc {gwinc.__version__} here, want {GWINC_VERSION}", file=sys.stderr)
    except ImportError:
        pass
    python = venv_python(args.venv)
    if Path(sys.prefix).resolve() == args.venv.resolve():
        # already inside the environment and still no gwinc: do not loop
        sys.exit(f"error: {args.venv} has no gwinc {GWINC_VERSION}; delete it to rebuild it")
    if not python.exists():
        print(f"making {args.venv} with gwinc=={GWINC_VERSION} ...", file=sys.stderr)
        subprocess.run([sys.executable, "-m", "venv", str(args.venv)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "--quiet",
                        f"gwinc=={GWINC_VERSION}"], check=True)
    os.execv(str(python), [str(python), str(Path(__file__).resolve()), *sys.argv[1:]])


def pendkit_binary(args) -> Path:
    if args.pendkit is not None:
        if not args.pendkit.is_file():
            sys.exit(f"error: --pendkit {args.pendkit}: no such file")
        return args.pendkit
    print("building the release binary (cargo build --release -p pendkit-cli) ...",
          file=sys.stderr)
    subprocess.run(["cargo", "build", "--release", "-p", "pendkit-cli"], cwd=REPO, check=True)
    return REPO / "target" / "release" / "pendkit"


def log_grid(n):
    """The grid of pendkit's `log_grid(0.1, 100, n)`: log-spaced, end points exact."""
    import numpy as np

    f = np.logspace(np.log10(BAND_HZ[0]), np.log10(BAND_HZ[1]), n)
    f[0], f[-1] = BAND_HZ
    return f


class Pygwinc:
    def __init__(self):
        import gwinc

        # warnings from the budget's other noises are not ours to show
        self.ifo = gwinc.load_budget("aLIGO").ifo

    def time(self, f, repeat):
        """Median (s) of `repeat` calls of precomp_suspension + suspension_thermal."""
        from gwinc.noise.suspensionthermal import suspension_thermal
        from gwinc.suspension import precomp_suspension

        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            pc = precomp_suspension(f, self.ifo)
            noise = suspension_thermal(f, self.ifo.Suspension, pc)
            times.append(time.perf_counter() - start)
        if not (len(noise) == len(f) and all(x > 0 for x in noise)):
            sys.exit("error: pygwinc returned a noise curve that is not positive everywhere")
        return statistics.median(times)


def pendkit_time(binary, n, repeat):
    """(noise phase median, build-to-modes median) in s from `pendkit bench --json`."""
    out = subprocess.run(
        [str(binary), "bench", "quad", "--stage", "2", "--noise", "x3", "--points", str(n),
         "--repeat", str(repeat), "--json"],
        check=True, capture_output=True, text=True).stdout
    report = json.loads(out)
    noise = [p for p in report["phases"] if p["name"] == "noise"]
    if len(noise) != 1 or noise[0]["calls"] != n:
        sys.exit(f"error: pendkit bench printed no noise phase over {n} points")
    return noise[0]["median_s"], report["total_median_s"]


def main():
    args = parse_args()
    ensure_gwinc(args)
    import gwinc

    binary = pendkit_binary(args)
    version = subprocess.run([str(binary), "--version"], capture_output=True,
                             text=True).stdout.strip()
    gw = Pygwinc()
    grids = {n: log_grid(n) for n in args.points}
    samples = {n: {"gwinc": [], "noise": [], "pipeline": []} for n in args.points}
    for _ in range(args.rounds):
        for n in args.points:
            samples[n]["gwinc"].append(gw.time(grids[n], args.repeat))
            noise, build_to_modes = pendkit_time(binary, n, args.repeat)
            samples[n]["noise"].append(noise)
            samples[n]["pipeline"].append(build_to_modes + noise)

    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    print(f"pygwinc {gwinc.__version__} (python {sys.version.split()[0]}) against {version}")
    print(f"aLIGO quad, test-mass longitudinal suspension thermal noise, "
          f"{BAND_HZ[0]}-{BAND_HZ[1]} Hz log-spaced")
    print(f"{args.rounds} interleaved rounds x {args.repeat} calls per side; "
          f"each round's time is the median of its calls")
    print(f"load average at the end: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} "
          f"({os.cpu_count()} cores)")
    print()
    head = (f"{'points':>7}  {'pygwinc':>10}  {'pendkit noise':>13}  {'ratio':>6}  "
            f"{'pendkit pipeline':>16}  {'ratio':>6}  {'per point':>9}")
    # the median round, and the least disturbed one (each side's fastest round: on a
    # loaded machine the better estimate of the unloaded time)
    for title, pick in (("median over the rounds", statistics.median),
                        ("fastest round of each", min)):
        print(title)
        print(head)
        for n in args.points:
            g = pick(samples[n]["gwinc"])
            s = pick(samples[n]["noise"])
            p = pick(samples[n]["pipeline"])
            print(f"{n:>7}  {g * 1e3:>7.3f} ms  {s * 1e3:>10.3f} ms  {g / s:>5.1f}x  "
                  f"{p * 1e3:>13.3f} ms  {g / p:>5.1f}x  {s / n * 1e6:>6.3f} us")
        print()
    print("ratio = pygwinc time / pendkit time (above 1: pendkit is faster); "
          "pipeline = build + equilibrium + stage 2 + modes + noise, from the model's name; "
          "per point = pendkit noise phase / points")


if __name__ == "__main__":
    main()
