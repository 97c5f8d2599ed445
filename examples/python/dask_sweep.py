"""A parameter sweep of pendkit's quad on a Dask cluster, checked against the same sweep run
serially.

pendkit models pickle (model name or case-file text, and the overrides), so a sweep is a
list of models mapped over workers: here the fibre attachment height ``d4`` of the test
mass, each point giving the lowest modes, the test mass's thermal noise and the
longitudinal transfer function. Any Dask cluster works the same way (a `LocalCluster` here;
`dask_jobqueue.HTCondorCluster` or a `distributed.Client` to a running scheduler for a
real one).

    python examples/python/dask_sweep.py [--points 11] [--workers 2]
"""

import argparse
import time

import numpy as np

import pendkit


def sweep_models(values):
    """One quad per value of d4 (m): the distance of the fibres' lower break-off above the
    test mass's centre of mass."""
    return [pendkit.Model("quad", set={"d4": float(d)}) for d in values]


def evaluate(model, freqs):
    """What one sweep point computes: the six lowest mode frequencies (Hz), the thermal noise
    ASD of the test mass's longitudinal displacement x3 (m/√Hz) and the transfer function
    from the support's x00 to x3 (m/m) at `freqs` (Hz)."""
    result = model.run()
    return {
        "sets": model.sets,
        "mode_hz": result.modes().frequencies[:6],
        "asd_x3": result.noise("x3", freqs).asd,
        "tf_x00_x3": result.tf("x00", "x3", freqs),
    }


def run_serial(models, freqs):
    return [evaluate(m, freqs) for m in models]


def run_on(client, models, freqs, timeout=None):
    """The sweep on a Dask client: each model is pickled to a worker process. With
    `timeout` (s), a sweep not done by then raises TimeoutError instead of waiting on
    (e.g. for workers that cannot start)."""
    from dask.distributed import wait

    futures = client.map(evaluate, models, freqs=freqs, pure=False)
    wait(futures, timeout=timeout)
    return client.gather(futures)


def same(a, b):
    """Whether two sweeps gave bit-identical numbers."""
    return len(a) == len(b) and all(
        x["sets"] == y["sets"] and all(np.array_equal(x[k], y[k]) for k in x if k != "sets")
        for x, y in zip(a, b)
    )


def main():
    from dask.distributed import Client, LocalCluster

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=11, help="values of d4")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    args = parser.parse_args()

    values = np.linspace(0.0, 0.02, args.points)  # m
    freqs = pendkit.log_grid(0.1, 100.0, 200)  # Hz
    models = sweep_models(values)

    start = time.perf_counter()
    serial = run_serial(models, freqs)
    t_serial = time.perf_counter() - start
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        run_on(client, models[:1], freqs)  # start-up (imports on the workers) not timed
        start = time.perf_counter()
        distributed = run_on(client, models, freqs)
        t_dask = time.perf_counter() - start

    print("d4_m,mode1_hz,mode2_hz,mode3_hz,asd_x3_at_10hz_m_per_rthz")
    i10 = int(np.argmin(abs(freqs - 10.0)))
    for d, point in zip(values, distributed):
        hz = point["mode_hz"]
        print(f"{d:.4g},{hz[0]:.7g},{hz[1]:.7g},{hz[2]:.7g},{point['asd_x3'][i10]:.6e}")
    print(f"serial {t_serial:.2f} s, dask ({args.workers} workers) {t_dask:.2f} s; "
          f"results identical: {same(serial, distributed)}")
    if not same(serial, distributed):
        raise SystemExit("the Dask sweep differs from the serial one")


if __name__ == "__main__":
    main()
