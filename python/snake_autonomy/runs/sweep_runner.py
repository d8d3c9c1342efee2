"""Sweeps and experiments on an existing distributed engine: Dask.distributed, written
against concurrent.futures so that the local path stays a plain executor.

    with open_executor("dask", n_workers=2) as ex:          # a LocalCluster (processes)
        results = run_tasks(ex, simulate_one, tasks, desc="gait map")
    with open_executor("dask", scheduler="tcp://host:8786") as ex:   # the same sweep on a cluster
    with open_executor("serial") as ex:                      # or "threads": the reference paths

Every engine gets the same (function, task) pairs and returns results in task order; a task carries
its own seed, so results are identical whatever the engine (test_nav_sweep_runner). The Dask engine
is Client.get_executor(): a concurrent.futures.Executor whose futures are concurrent.futures.Future,
so run_tasks uses concurrent.futures.as_completed for every engine. Progress: a tqdm bar on stderr.
"""
import concurrent.futures as cf
import contextlib
import sys
from typing import Callable, Iterable, List, Optional

from tqdm import tqdm

ENGINES = ("dask", "threads", "serial")


class SerialExecutor(cf.Executor):
    """Runs each task when submitted, in the caller's thread: the simplest reference engine."""

    def submit(self, fn, /, *args, **kwargs) -> cf.Future:
        f = cf.Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as e:  # noqa: BLE001 - handed to the caller through the future
            f.set_exception(e)
        return f


@contextlib.contextmanager
def open_executor(engine: str = "dask", scheduler: Optional[str] = None, n_workers: int = 2):
    """A concurrent.futures.Executor for engine (dask | threads | serial), closed on exit.

    dask without scheduler: a LocalCluster of n_workers processes, one thread each (MuJoCo runs
    are CPU bound); with scheduler (ADDRESS of a running dask scheduler): that cluster."""
    if engine not in ENGINES:
        raise ValueError(f"engine: expected one of {', '.join(ENGINES)}, got {engine!r}")
    if n_workers < 1:
        raise ValueError(f"n_workers: must be >= 1, got {n_workers}")
    if engine == "serial":
        yield SerialExecutor()
        return
    if engine == "threads":
        with cf.ThreadPoolExecutor(max_workers=n_workers) as ex:
            yield ex
        return
    from distributed import Client, LocalCluster  # lazy: Dask is heavy and only this path needs it
    if scheduler:
        with Client(scheduler) as client:
            yield client.get_executor(pure=False)
        return
    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client.get_executor(pure=False)


def progress_bar(total: float, desc: str, unit: str, enabled: bool = True) -> Optional[tqdm]:
    """The commands' progress bar on stderr (kept when done), or None when not enabled."""
    if not enabled:
        return None
    return tqdm(total=total, desc=desc, unit=unit, leave=True, file=sys.stderr)


def run_tasks(executor: cf.Executor, fn: Callable, tasks: Iterable, desc: str = "tasks",
              progress: bool = True) -> List:
    """fn(task) for every task on executor; the results in task order (a task's exception is
    raised here). fn must be importable (a module-level function) for process-based engines."""
    tasks = list(tasks)
    futures = {executor.submit(fn, t): i for i, t in enumerate(tasks)}
    results: List = [None] * len(tasks)
    bar = progress_bar(len(tasks), desc, "run", enabled=progress)
    try:
        for f in cf.as_completed(futures):
            results[futures[f]] = f.result()
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return results
