"""Shared pieces of the pendkit Python tests: the repository, and the `pendkit` command
line as the independent reference (the same library reached through clap, text
formatting and a separate process; its CSV and JSON print every digit of an f64)."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[4]
CASES = REPO / "models"


def _cli_path():
    given = os.environ.get("PENDKIT_CLI")
    if given:
        return Path(given)
    # the debug command line is what `cargo test --workspace` builds; build it if needed
    subprocess.run(
        ["cargo", "build", "--quiet", "-p", "pendkit-cli"], cwd=REPO, check=True
    )
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "debug" / "pendkit"


@pytest.fixture(scope="session")
def cli():
    """Runs `pendkit ARGS...`: `cli(*args)` returns stdout (the command must succeed);
    `cli.error(*args)` returns the one-line message after `error: ` (it must fail)."""
    path = _cli_path()
    assert path.is_file(), f"no pendkit command line at {path}"

    class Cli:
        def __call__(self, *args):
            done = subprocess.run(
                [str(path), *args], capture_output=True, text=True, cwd=REPO
            )
            assert done.returncode == 0, done.stderr
            return done.stdout

        def error(self, *args):
            done = subprocess.run(
                [str(path), *args], capture_output=True, text=True, cwd=REPO
            )
            assert done.returncode != 0, f"pendkit {' '.join(args)} succeeded"
            first = done.stderr.splitlines()[0]
            assert first.startswith("error: "), done.stderr
            return first[len("error: "):]

    return Cli()


def parse_csv(text):
    """A CSV of numbers as (header, columns): every value with all its digits."""
    lines = text.strip().splitlines()
    header = lines[0].split(",")
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    return header, [list(col) for col in zip(*rows)]


@pytest.fixture(scope="session")
def dask_client():
    """A Dask client of a LocalCluster of two worker processes, one thread each, shared by
    the tests that need one (a cluster takes a few seconds to start)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        yield client
