"""Seeded Monte Carlo and batch runs on local processes or a Dask cluster.

A *scenario* is a module-level function (so that it can be sent to worker
processes) that takes a :class:`numpy.random.Generator` and keyword
arguments and returns a mapping of named results: scalars (metrics such as
an RMSE) or arrays (time series such as NEES).  :func:`run_montecarlo` gives
run ``i`` the generator built from child ``i`` of
``numpy.random.SeedSequence(seed)``, whatever the executor, the number of
workers or the chunking, so the same seed gives the same numbers everywhere.

A *batched* scenario (``batched=True``) takes a list of generators and returns
a list of result mappings; it lets a vectorised or numba-batched scenario run
many Monte Carlo runs in one call.  Runs are cut into chunks of fixed size
(``chunk_size``), each chunk is one task.

Executors
---------
``"serial"``
    In this process (debugging, tiny jobs).
``"processes"`` (default)
    A local process pool (``concurrent.futures``, forkserver start method)
    with ``n_workers`` processes (default: all cores).
``"dask"``
    A Dask distributed cluster: an existing one by ``address``
    (``"tcp://host:8786"``), or a ``LocalCluster`` on loopback with
    ``n_workers`` single-threaded worker processes.  Needs ``imunav[dask]``.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from imunav.errors import InvalidInputError, MissingDependencyError
from imunav.filters.consistency import ConsistencyResult, consistency_test
from imunav.results import Result

__all__ = [
    "run_montecarlo",
    "run_batch",
    "MonteCarloResult",
    "spawn_generators",
]

Executor = Literal["serial", "processes", "dask"]


def spawn_generators(seed: int | np.random.SeedSequence, n: int, start: int = 0) -> list[np.random.Generator]:
    """Generators of runs ``start .. start+n-1`` of a Monte Carlo seeded with ``seed``.

    Run ``i`` always gets ``Generator(PCG64(SeedSequence(seed).spawn(...)[i]))``.

    Parameters
    ----------
    seed : int or numpy.random.SeedSequence
        Master seed of the Monte Carlo.
    n : int
        Number of generators.
    start : int
        Index of the first run.

    Returns
    -------
    list of numpy.random.Generator
        ``n`` independent PCG64 generators; run ``i``'s does not depend on ``start`` or ``n``.
    """
    ss = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(int(seed))
    # SeedSequence.spawn is stateful; derive children explicitly so that any
    # subset of runs can be regenerated independently.
    return [
        np.random.Generator(np.random.PCG64(np.random.SeedSequence(ss.entropy, spawn_key=(*ss.spawn_key, i))))
        for i in range(start, start + n)
    ]


def _run_chunk(
    fn: Callable[..., Any], seed: int, start: int, stop: int, batched: bool, kwargs: Mapping[str, Any]
) -> list[Mapping[str, Any]]:
    gens = spawn_generators(seed, stop - start, start)
    if batched:
        out = list(fn(gens, **kwargs))
        if len(out) != len(gens):
            raise InvalidInputError(
                f"batched scenario {getattr(fn, '__name__', fn)!r} returned {len(out)} results for {len(gens)} runs"
            )
        return out
    return [fn(g, **kwargs) for g in gens]


@dataclass(frozen=True)
class MonteCarloResult(Result):
    """Results of a Monte Carlo: one row per run.

    Attributes
    ----------
    metrics : pandas.DataFrame
        One row per run (index ``run``) and one column per scalar result.
    arrays : dict
        Name -> array stacked over runs, shape ``(n_runs, ...)``.
    seed : int
        Master seed.
    n_runs : int
        Number of runs.
    executor : str
        ``"serial"``, ``"processes"`` or ``"dask"``.
    meta : dict
        Scenario name, chunk size and the ``repr`` of the scenario's keyword arguments.
    """

    metrics: pd.DataFrame
    arrays: dict[str, NDArray[np.float64]]
    seed: int
    n_runs: int
    executor: str
    meta: dict[str, Any] = field(default_factory=dict)

    def summary(self, percentiles: Sequence[float] = (5, 50, 95)) -> pd.DataFrame:
        """Mean, standard deviation, min / max and percentiles of every scalar metric.

        Parameters
        ----------
        percentiles : sequence of float
            Percentiles to add, in [0, 100].

        Returns
        -------
        pandas.DataFrame
            Rows ``mean``, ``std`` (ddof=1; NaN for one run), ``min``, ``max``, ``p<q>``; one column per metric.
        """
        m = self.metrics
        rows = {
            "mean": m.mean(),
            "std": m.std(ddof=1) if len(m) > 1 else m.mean() * np.nan,
            "min": m.min(),
            "max": m.max(),
        }
        for p in percentiles:
            rows[f"p{p:g}"] = m.quantile(p / 100.0)
        return pd.DataFrame(rows).T

    def consistency(self, name: str, dof: int, confidence: float = 0.95) -> ConsistencyResult:
        """χ² consistency (:func:`imunav.filters.consistency_test`) of the stacked NEES / NIS array ``name``.

        Parameters
        ----------
        name : str
            An array result of shape ``(n_runs, steps)``.
        dof : int
            Dimension of the error (state for NEES, measurement for NIS).
        confidence : float
            Two-sided confidence of the acceptance band.

        Returns
        -------
        imunav.filters.ConsistencyResult
            Time-averaged statistic over the runs and its χ² acceptance band (Bar-Shalom, Li & Kirubarajan,
            "Estimation with Applications to Tracking and Navigation", Wiley 2001, §5.4).

        Raises
        ------
        InvalidInputError
            If ``name`` is not an array result.
        """
        if name not in self.arrays:
            raise InvalidInputError(f"no array result {name!r}; available: {sorted(self.arrays)}")
        return consistency_test(self.arrays[name], dof, confidence)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form.

        Returns
        -------
        dict
            ``seed``, ``n_runs``, ``executor``, ``metrics`` (column -> list), ``summary`` (:meth:`summary`),
            ``arrays`` (nested lists) and ``meta``.
        """
        return {
            "seed": self.seed,
            "n_runs": self.n_runs,
            "executor": self.executor,
            "metrics": {k: self.metrics[k].tolist() for k in self.metrics.columns},
            "summary": self.summary().to_dict(),
            "arrays": {k: v.tolist() for k, v in self.arrays.items()},
            "meta": self.meta,
        }


def _gather(results: list[Mapping[str, Any]]) -> tuple[pd.DataFrame, dict[str, NDArray[np.float64]]]:
    if not results:
        return pd.DataFrame(), {}
    scalars: dict[str, list[float]] = {}
    arrays: dict[str, list[NDArray[np.float64]]] = {}
    keys = list(results[0].keys())
    for i, r in enumerate(results):
        if list(r.keys()) != keys:
            raise InvalidInputError(f"run {i} returned keys {sorted(r)} but run 0 returned {sorted(keys)}")
        for k, v in r.items():
            a = np.asarray(v)
            if a.ndim == 0:
                scalars.setdefault(k, []).append(float(a))
            else:
                arrays.setdefault(k, []).append(a)
    df = pd.DataFrame(scalars)
    df.index.name = "run"
    stacked: dict[str, NDArray[np.float64]] = {}
    for k, lst in arrays.items():
        shapes = {a.shape for a in lst}
        if len(shapes) != 1:
            raise InvalidInputError(f"array result {k!r} has different shapes across runs: {sorted(shapes)}")
        stacked[k] = np.stack(lst)
    return df, stacked


def _chunks(n_runs: int, chunk_size: int) -> list[tuple[int, int]]:
    return [(s, min(s + chunk_size, n_runs)) for s in range(0, n_runs, chunk_size)]


class _Callback:
    """The progress-bar interface over a ``progress(done, total)`` callable."""

    def __init__(self, fn: Callable[[int, int], None], total: int) -> None:
        self.fn, self.total, self.done = fn, total, 0

    def __enter__(self) -> _Callback:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def add_task(self, description: str, total: int) -> int:
        return 0

    def advance(self, task: int, n: int = 1) -> None:
        self.done += n
        self.fn(self.done, self.total)


def _progress(enabled: bool | Callable[[int, int], None], total: int, description: str):
    if callable(enabled):
        return _Callback(enabled, total)

    prog = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        disable=not enabled,
        transient=True,
    )
    return prog


def run_montecarlo(
    scenario: Callable[..., Any],
    n_runs: int,
    *,
    seed: int = 0,
    executor: Executor = "processes",
    n_workers: int | None = None,
    address: str | None = None,
    batched: bool = False,
    chunk_size: int | None = None,
    progress: bool | Callable[[int, int], None] = False,
    description: str = "Monte Carlo",
    **kwargs: Any,
) -> MonteCarloResult:
    """Run ``n_runs`` seeded runs of ``scenario`` and gather the results.

    Parameters
    ----------
    scenario : callable
        Module-level function ``f(rng, **kwargs) -> {name: scalar | array}``, or with ``batched=True``
        ``f([rng, ...], **kwargs) -> [{...}, ...]``.
    n_runs : int
        Number of runs, >= 1.
    seed : int
        Master seed; run ``i`` uses :func:`spawn_generators` ``(seed, ...)[i]``.
    executor : {"serial", "processes", "dask"}
        Where the runs execute (see module docstring).
    n_workers : int, optional
        Worker processes (default: number of cores).
    address : str, optional
        Dask scheduler address; if None with ``executor="dask"`` a LocalCluster is started on 127.0.0.1 and
        closed afterwards.
    batched : bool
        ``scenario`` takes a list of generators (one chunk) and returns one mapping per generator.
    chunk_size : int, optional
        Runs per task (default: ``ceil(n_runs / (4 n_workers))``). Chunking does not change the numbers.
    progress : bool or callable
        True for a rich progress bar, or a callable ``progress(done, total)`` called after each chunk (with
        ``chunk_size=1``, after each run).
    description : str
        Label of the progress bar.
    **kwargs
        Passed to ``scenario``.

    Returns
    -------
    MonteCarloResult
        Scalars in ``metrics``, arrays stacked in ``arrays``, in run order.

    Raises
    ------
    InvalidInputError
        If ``n_runs`` < 1, ``scenario`` is not callable, ``address`` is given without the Dask executor or
        ``executor`` is unknown.
    """
    if n_runs < 1:
        raise InvalidInputError(f"n_runs must be >= 1, got {n_runs}")
    if not callable(scenario):
        raise InvalidInputError("scenario must be a callable")
    _check_address(executor, address)
    workers = n_workers or os.cpu_count() or 1
    cs = chunk_size or max(1, math.ceil(n_runs / (4 * workers)))
    chunks = _chunks(n_runs, cs)
    per_chunk: dict[int, list[Mapping[str, Any]]] = {}

    if executor == "serial":
        with _progress(progress, n_runs, description) as prog:
            task = prog.add_task(description, total=n_runs)
            for ci, (a, b) in enumerate(chunks):
                per_chunk[ci] = _run_chunk(scenario, seed, a, b, batched, kwargs)
                prog.advance(task, b - a)
    elif executor == "processes":

        ctx = mp.get_context("forkserver")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
            futs = {
                pool.submit(_run_chunk, scenario, seed, a, b, batched, dict(kwargs)): ci
                for ci, (a, b) in enumerate(chunks)
            }
            with _progress(progress, n_runs, description) as prog:
                task = prog.add_task(description, total=n_runs)
                for f in as_completed(futs):
                    ci = futs[f]
                    per_chunk[ci] = f.result()
                    prog.advance(task, chunks[ci][1] - chunks[ci][0])
    elif executor == "dask":
        client, cluster = _dask_client(address, workers)
        # optional: dask (imunav[dask]) only for a cluster run
        from dask.distributed import as_completed as das_completed

        try:
            futs = [
                client.submit(_run_chunk, scenario, seed, a, b, batched, dict(kwargs), pure=False)
                for (a, b) in chunks
            ]
            index = {f.key: ci for ci, f in enumerate(futs)}
            with _progress(progress, n_runs, description) as prog:
                task = prog.add_task(description, total=n_runs)
                for f in das_completed(futs):
                    ci = index[f.key]
                    per_chunk[ci] = f.result()
                    prog.advance(task, chunks[ci][1] - chunks[ci][0])
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    else:
        raise InvalidInputError(f"executor must be 'serial', 'processes' or 'dask', not {executor!r}")

    results = [r for ci in range(len(chunks)) for r in per_chunk[ci]]
    metrics, arrays = _gather(results)
    return MonteCarloResult(
        metrics,
        arrays,
        seed=int(seed),
        n_runs=n_runs,
        executor=executor,
        meta={"scenario": getattr(scenario, "__qualname__", str(scenario)), "chunk_size": cs, "kwargs": {k: repr(v) for k, v in kwargs.items()}},
    )


#: Seconds to wait for a Dask scheduler given by address before giving up.
DASK_CONNECT_TIMEOUT_S = 5.0


def _check_address(executor: str, address: str | None) -> None:
    """A scheduler address only makes sense with the Dask executor (it would be silently ignored)."""
    if address is not None and executor != "dask":
        raise InvalidInputError(f"a scheduler address ({address}) is used only with the dask executor, not "
                                f"{executor!r}: add --executor dask (executor='dask') or drop --address")


def _dask_client(address: str | None, workers: int) -> tuple[Any, Any]:
    """(client, local cluster or None): a local cluster without ``address``; a scheduler that does not
    answer within :data:`DASK_CONNECT_TIMEOUT_S` is an :class:`~imunav.errors.InvalidInputError`."""
    try:
        # optional: dask (imunav[dask]) only for a cluster run
        from dask.distributed import Client, LocalCluster
    except ImportError as e:  # pragma: no cover - depends on the extra
        raise MissingDependencyError("dask[distributed]", "dask", "The Dask executor") from e
    if address is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address=None)
        return Client(cluster), cluster
    try:
        return Client(address, timeout=DASK_CONNECT_TIMEOUT_S), None
    except (OSError, TimeoutError) as exc:
        raise InvalidInputError(
            f"the Dask scheduler at {address} did not answer within {DASK_CONNECT_TIMEOUT_S:g} s ({exc}); "
            "start it (dask scheduler), check the address, or drop --address to use a local cluster"
        ) from None


def run_batch(
    fn: Callable[..., Mapping[str, Any]],
    items: Sequence[Any],
    *,
    executor: Executor = "processes",
    n_workers: int | None = None,
    address: str | None = None,
    progress: bool = False,
    description: str = "batch",
    **kwargs: Any,
) -> list[Mapping[str, Any] | BaseException]:
    """Apply ``fn(item, **kwargs)`` to every item (e.g. every recording of a
    production batch) in parallel, keeping the input order.

    A failing item does not stop the others: its entry is the exception, so
    the caller can report which unit failed and why.

    Parameters
    ----------
    fn : callable
        Module-level function ``fn(item, **kwargs) -> mapping``.
    items : sequence
        The inputs, at least one.
    executor : {"serial", "processes", "dask"}
        Where the calls execute (see module docstring).
    n_workers : int, optional
        Worker processes (default: number of cores).
    address : str, optional
        Dask scheduler address (Dask executor only; None: a local cluster).
    progress : bool
        Show a rich progress bar (processes executor).
    description : str
        Label of the progress bar.
    **kwargs
        Passed to ``fn``.

    Returns
    -------
    list
        One entry per item, in input order: ``fn``'s result or the exception it raised.

    Raises
    ------
    InvalidInputError
        If ``items`` is empty, ``address`` is given without the Dask executor or ``executor`` is unknown.
    """
    items = list(items)
    if not items:
        raise InvalidInputError("run_batch needs at least one item")
    _check_address(executor, address)
    out: list[Any] = [None] * len(items)
    if executor == "serial":
        for i, it in enumerate(items):
            out[i] = _safe_call(fn, it, kwargs)
        return out
    workers = n_workers or os.cpu_count() or 1
    if executor == "processes":

        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("forkserver")) as pool:
            futs = {pool.submit(_safe_call, fn, it, dict(kwargs)): i for i, it in enumerate(items)}
            with _progress(progress, len(items), description) as prog:
                task = prog.add_task(description, total=len(items))
                for f in as_completed(futs):
                    out[futs[f]] = f.result()
                    prog.advance(task)
        return out
    if executor == "dask":
        client, cluster = _dask_client(address, workers)
        try:
            futs = [client.submit(_safe_call, fn, it, dict(kwargs), pure=False) for it in items]
            return list(client.gather(futs))
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    raise InvalidInputError(f"executor must be 'serial', 'processes' or 'dask', not {executor!r}")


def _safe_call(fn: Callable[..., Any], item: Any, kwargs: Mapping[str, Any]) -> Any:
    try:
        return fn(item, **kwargs)
    except Exception as e:  # reported per item, never swallowed: the caller gets the exception object
        return e
