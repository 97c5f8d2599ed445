"""`pendkit.sweep`: one model at many parameter values, in this process's threads or on a
Dask cluster, in chunks that each take long enough to pay for their dispatch."""

from __future__ import annotations

import math
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._pendkit import Model, PendkitError, _sweep_chunk

What = Union[str, Tuple[Any, ...]]

#: The least work in one chunk (s): a Dask task costs about a millisecond to schedule and
#: a thread pool's a few microseconds, so at 50 ms the dispatch is a few per cent at most.
CHUNK_SECONDS = 0.05
#: How long the first points are timed for (s), to size the chunks.
CALIBRATION_SECONDS = 0.02


def _what(what: What) -> Tuple[str, Dict[str, Any]]:
    """`what` as the chunk function's (kind, keyword arguments)."""
    if isinstance(what, str):
        if what == "modes":
            return "modes", {}
        raise PendkitError(
            f"what: '{what}' is not \"modes\", (\"tf\", input, output, freqs) or "
            "(\"noise\", output, freqs)"
        )
    if not isinstance(what, tuple) or not what or not isinstance(what[0], str):
        raise TypeError(
            "what: expected \"modes\", (\"tf\", input, output, freqs) or "
            f"(\"noise\", output, freqs), got {type(what).__name__}"
        )
    kind, args = what[0], what[1:]
    if kind == "tf" and len(args) == 3:
        return "tf", {"input": args[0], "output": args[1], "freqs": args[2]}
    if kind == "noise" and len(args) == 2:
        return "noise", {"output": args[0], "freqs": args[1]}
    raise PendkitError(
        f"what: expected (\"tf\", input, output, freqs) or (\"noise\", output, freqs), "
        f"got {kind!r} with {len(args)} more items"
    )


def _table(values: Mapping[str, Any]) -> Tuple[List[str], npt.NDArray[np.float64]]:
    """The names and the points × names table of finite float64 values."""
    if not isinstance(values, Mapping):
        raise TypeError(
            f"values: expected a dict {{name: values}}, got {type(values).__name__}"
        )
    if not values:
        raise PendkitError("values: no parameters to sweep")
    names: List[str] = []
    columns: List[npt.NDArray[np.float64]] = []
    for name, column in values.items():
        if not isinstance(name, str):
            raise TypeError(
                f"values: the keys are parameter names (str), got {type(name).__name__}"
            )
        array = np.asarray(column)
        if array.dtype.kind not in "fiu":
            raise TypeError(
                f"values['{name}']: expected real numbers, got an array of {array.dtype}"
            )
        if array.ndim != 1:
            raise PendkitError(
                f"values['{name}']: expected a one-dimensional array, got shape {array.shape}"
            )
        array = array.astype(np.float64)
        bad = np.flatnonzero(~np.isfinite(array))
        if bad.size:
            raise PendkitError(
                f"values['{name}'][{bad[0]}]: value {float(array[bad[0]])!r} is not finite"
            )
        if columns and array.shape != columns[0].shape:
            raise PendkitError(
                f"values['{name}']: {array.size} values, where values['{names[0]}'] has "
                f"{columns[0].size} (the parameters are swept together, point by point)"
            )
        names.append(name)
        columns.append(array)
    if columns[0].size == 0:
        raise PendkitError(f"values['{names[0]}']: no values")
    return names, np.ascontiguousarray(np.column_stack(columns))


def _run_chunk(
    model: Model, names: List[str], block: npt.NDArray[np.float64], kind: str,
    kwargs: Dict[str, Any],
) -> Tuple[npt.NDArray[Any], List[Tuple[int, str]]]:
    """One chunk, where it runs (this process's thread or a Dask worker)."""
    return _sweep_chunk(model, names, block, kind, **kwargs)


def sweep(
    model: Model,
    values: Mapping[str, Union[Sequence[float], npt.ArrayLike]],
    what: What = "modes",
    *,
    client: Any = None,
    stage: Union[str, int, None] = None,
    errors: str = "raise",
    threads: Optional[int] = None,
) -> npt.NDArray[Any]:
    """Runs `model` at every point of `values` and returns one row per point.

    `values` is a dict `{name: values}` of parameters swept together, point by point (all
    the same length; a grid is `np.meshgrid(...)` flattened), each value a real number in
    the parameter's SI unit. `what` is

    - `"modes"`: every mode's frequency (Hz), shape (points, modes);
    - `("tf", input, output, freqs)`: the transfer function at `freqs` (Hz), complex,
      shape (points, frequencies);
    - `("noise", output, freqs)`: the thermal-noise ASD (m/√Hz or rad/√Hz) at `freqs`,
      shape (points, frequencies).

    Each row is bit for bit what `model.with_set({name: value, ...}).run(stage)` gives
    (`.modes().frequencies`, `.tf(input, output, freqs)`, `.noise(output, freqs).asd`).

    The first points are computed here and timed; the rest go in chunks of at least
    `CHUNK_SECONDS` (50 ms) of work each: to `threads` threads of this process (default:
    one per core; the GIL is released while a chunk computes), or, given a Dask
    `distributed.Client` as `client`, one task per chunk on its workers, with the model
    scattered to them once. A cluster of several machines takes the same call: only the
    client's scheduler address differs.

    A point that fails (a value the model refuses, say) raises `PendkitError` naming the
    point and its values (the first such point), unless `errors="nan"`: then its row is NaN
    and a `RuntimeWarning` says how many failed and why the first did.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model: expected a pendkit.Model, got {type(model).__name__}")
    if errors not in ("raise", "nan"):
        raise PendkitError(f"errors: expected \"raise\" or \"nan\", got {errors!r}")
    if threads is not None and (not isinstance(threads, int) or threads < 1):
        raise PendkitError(f"threads: expected a positive integer, got {threads!r}")
    kind, kwargs = _what(what)
    if stage is not None:
        kwargs["stage"] = stage
    names, table = _table(values)
    n = table.shape[0]

    # the first points here, timed, until CALIBRATION_SECONDS have gone: 1, 2, 4, ... points
    parts: List[Tuple[int, npt.NDArray[Any], List[Tuple[int, str]]]] = []
    done, batch, spent = 0, 1, 0.0
    costs: List[float] = []
    while done < n and spent < CALIBRATION_SECONDS:
        block = table[done:done + batch]
        start = time.perf_counter()
        rows, failed = _run_chunk(model, names, block, kind, kwargs)
        elapsed = time.perf_counter() - start
        parts.append((done, rows, failed))
        costs.append(elapsed / len(block))
        done += len(block)
        spent += elapsed
        batch *= 2
    # a point's cost: the least of the batches' (other work on the machine only adds to a
    # batch's time), the first batch left out when there are others (its point also warms
    # the caches)
    cost = min(costs[1:] or costs) if costs else 0.0
    size = max(1, math.ceil(CHUNK_SECONDS / cost)) if cost > 0 else n
    starts = list(range(done, n, size))
    blocks = [table[s:s + size] for s in starts]

    if not blocks:
        results: List[Tuple[npt.NDArray[Any], List[Tuple[int, str]]]] = []
    elif client is not None:
        remote = client.scatter(model, broadcast=True)
        futures = [
            client.submit(_run_chunk, remote, names, block, kind, kwargs, pure=False)
            for block in blocks
        ]
        results = client.gather(futures)
    else:
        workers = min(threads or os.cpu_count() or 1, len(blocks))
        if workers == 1:
            results = [_run_chunk(model, names, b, kind, kwargs) for b in blocks]
        else:
            with ThreadPoolExecutor(workers) as pool:
                results = list(
                    pool.map(lambda b: _run_chunk(model, names, b, kind, kwargs), blocks)
                )
    parts.extend((s, rows, failed) for s, (rows, failed) in zip(starts, results))
    return _assemble(parts, n, names, table, kind, errors)


def _assemble(
    parts: List[Tuple[int, npt.NDArray[Any], List[Tuple[int, str]]]], n: int,
    names: List[str], table: npt.NDArray[np.float64], kind: str, errors: str,
) -> npt.NDArray[Any]:
    """The chunks' rows in one array, and the failures raised or warned about."""
    failures: List[Tuple[int, str]] = []
    # the width is the first successful chunk's: a chunk whose points all failed has none
    widths = [rows.shape[1] for _, rows, failed in parts if len(failed) < rows.shape[0]]
    width = widths[0] if widths else 0
    dtype = np.complex128 if kind == "tf" else np.float64
    out = np.full((n, width), np.nan, dtype=dtype)
    for start, rows, failed in parts:
        failures.extend((start + i, message) for i, message in failed)
        if rows.shape[1] == width:
            out[start:start + rows.shape[0]] = rows
        else:
            bad = {i for i, _ in failed}
            failures.extend(
                (start + i, f"{rows.shape[1]} modes, where the sweep's first point has "
                            f"{width}")
                for i in range(rows.shape[0]) if i not in bad
            )
    if failures:
        failures.sort()
        index, message = failures[0]
        point = ", ".join(f"{name}={float(x)!r}" for name, x in zip(names, table[index]))
        where = f"sweep point {index} ({point}): {message}"
        if errors == "raise":
            raise PendkitError(where)
        warnings.warn(
            f"{len(failures)} of {n} sweep points failed (their rows are NaN); the first, "
            f"{where}",
            RuntimeWarning,
            stacklevel=3,
        )
    return out
