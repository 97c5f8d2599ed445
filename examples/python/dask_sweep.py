"""A sweep of the quad's test-mass mass on a Dask cluster with `pendkit.sweep`, against the
plain loop: the same numbers, bit for bit, and the parallel efficiency.

`pendkit.sweep(model, {"m3": values}, client=client)` times the first points here, then
sends the rest in chunks of at least 50 ms of work, one Dask task each, with the model
scattered to the workers once: a task costs about a millisecond to schedule, so a task per
point (a millisecond or two of work) would cost as much as the point. Without `client` the
chunks go to this process's threads.

    python examples/python/dask_sweep.py [--points 2000] [--workers 2] [--rounds 1]
    python examples/python/dask_sweep.py --scheduler tcp://scheduler-host:8786

The first runs a `LocalCluster` of `--workers` processes; the second the same call on a
running cluster of any number of machines (`dask scheduler` on one, `dask worker
tcp://scheduler-host:8786` on each, pendkit installed on all): the scheduler's address is
the only change. Not timed: the cluster's start and the workers' first import of pendkit.
The parallel efficiency is the plain loop's time over (worker threads × the sweep's); on a
machine shared with other work, `--rounds` alternates the two and takes each one's
fastest.
"""

import argparse
import time

import numpy as np
import numpy.typing as npt

import pendkit


def plain_loop(model: pendkit.Model, values: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The sweep as a plain loop: every mode's frequency (Hz) at each test-mass mass (kg)."""
    return np.array([model.with_set({"m3": m3}).run().modes().frequencies
                     for m3 in np.asarray(values)])


def on_cluster(client: object, model: pendkit.Model,
               values: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The same sweep on the Dask cluster of `client`."""
    return pendkit.sweep(model, {"m3": values}, "modes", client=client)


def main() -> None:
    import os

    from dask.distributed import Client, LocalCluster

    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--points", type=int, default=2000, help="values of m3")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster processes")
    parser.add_argument("--scheduler", help="a running cluster's scheduler address")
    parser.add_argument("--rounds", type=int, default=1,
                        help="times to run the loop and the sweep, alternately; the "
                             "efficiency is from each one's fastest")
    args = parser.parse_args()

    model = pendkit.Model("quad")
    values = np.linspace(39.0, 41.0, args.points)  # kg
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    with client:
        client.run(lambda: __import__("pendkit") and None)  # the workers' first import
        threads = sum(w["nthreads"] for w in client.scheduler_info()["workers"].values())
        t_loop, t_dask = [], []
        for _ in range(args.rounds):
            start = time.perf_counter()
            loop = plain_loop(model, values)
            t_loop.append(time.perf_counter() - start)
            start = time.perf_counter()
            swept = on_cluster(client, model, values)
            t_dask.append(time.perf_counter() - start)
            identical = bool(np.array_equal(loop, swept))
            print(f"{args.points} points, {loop.shape[1]} modes each: plain loop "
                  f"{t_loop[-1]:.2f} s, pendkit.sweep on {threads} Dask worker threads "
                  f"{t_dask[-1]:.2f} s; identical: {identical}")
            if not identical:
                raise SystemExit("the Dask sweep differs from the plain loop")
    if not args.scheduler:
        cluster.close()
    print(f"parallel efficiency {min(t_loop) / (threads * min(t_dask)):.0%} (fastest loop "
          f"{min(t_loop):.2f} s, fastest sweep {min(t_dask):.2f} s; load average "
          f"{os.getloadavg()[0]:.1f})")


if __name__ == "__main__":
    main()
