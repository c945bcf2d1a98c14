"""Where a sweep's cases run: ``local`` (a pool of processes on this
machine), ``ray`` (remote tasks) or ``dask`` (distributed futures).

Each engine takes the tasks (one per case to run), the number of workers
and a cluster's address, and yields the cases' outcomes as they finish; it
schedules nothing itself — the pool, Ray or Dask do. A Ray or Dask
cluster given by its address must see the sweep's directory at the same
path (a shared file system: the cases write their outputs there) and have
this package installed; without an address a local cluster of ``workers``
processes is started for the sweep and stopped after it.

On Ctrl-C (``KeyboardInterrupt`` in the driver) the cases not started are
cancelled; running ones stop after their step with a checkpoint (local:
the workers get SIGINT, as from a terminal; ray: ``ray.cancel`` interrupts
the task the same way) or are abandoned (dask cannot interrupt a running
task); the next run of the sweep resumes or reruns them.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Dict, Iterator, List, Optional

from ._case import init_local_worker, run_case

#: An engine: (tasks, workers, address) -> the outcomes, as they come.
Engine = Callable[[List[Dict[str, Any]], int, Optional[str]], Iterator[Dict[str, Any]]]


def get(name: str) -> Engine:
    """The engine called ``name``; ImportError (with what to install) when
    its package is missing, before any case runs."""
    if name == "local":
        return local
    if name == "ray":
        try:
            import ray  # noqa: F401
        except ImportError as e:
            raise ImportError(
                f"engine 'ray' needs Ray, which cannot be imported here ({e}): pip install \"drape[ray]\" "
                "(from a checkout: pip install \"./crates/drape-py[ray]\")"
            ) from e
        return ray_engine
    if name == "dask":
        try:
            import dask.distributed  # noqa: F401
        except ImportError as e:
            raise ImportError(
                f"engine 'dask' needs Dask's distributed scheduler, which cannot be imported here ({e}): "
                "pip install \"drape[dask]\" (from a checkout: pip install \"./crates/drape-py[dask]\")"
            ) from e
        return dask_engine
    raise ValueError(f"no engine called {name!r}: local, ray or dask")


def _failed(task: Dict[str, Any], error: BaseException) -> Dict[str, Any]:
    """The outcome of a task the engine could not run (a worker that died)."""
    return {
        "index": task["index"],
        "status": "failed",
        "message": f"the worker running the case failed: {type(error).__name__}: {error}",
        "summary": None,
    }


def local(tasks: List[Dict[str, Any]], workers: int, address: Optional[str]) -> Iterator[Dict[str, Any]]:
    """A pool of ``workers`` processes on this machine (``address`` unused).

    The processes are started by ``spawn``, not ``fork``: a forked copy of
    a process that has run drape would inherit its thread pools without
    their threads.

    A worker that dies (the OOM killer, a crash, SIGKILL) breaks the pool:
    every case it had not finished ends with ``BrokenProcessPool``, whoever
    ran it. Those cases run again on a fresh pool; cases that break that
    one too run one by one, each on a pool of its own, so that a case that
    kills its worker fails alone and the others complete (issue 34).
    """
    context = multiprocessing.get_context("spawn")
    stop = context.Event()
    broken = yield from _local_round(tasks, workers, context, stop)
    if broken:
        broken = yield from _local_round(broken, workers, context, stop)
    for task in broken:
        alone = yield from _local_round([task], 1, context, stop)
        for t in alone:
            yield _failed(t, BrokenProcessPool("its worker died (killed, or out of memory) twice, the second time running this case alone"))


def _local_round(tasks: List[Dict[str, Any]], workers: int, context: Any, stop: Any) -> Iterator[Dict[str, Any]]:
    """Runs ``tasks`` on one pool, yielding their outcomes; returns the tasks
    the pool broke on (a worker died) without running them to the end."""
    if not tasks:
        return []
    pool = ProcessPoolExecutor(
        max_workers=max(1, min(workers, len(tasks))),
        mp_context=context,
        initializer=init_local_worker,
        initargs=(stop,),
    )
    futures: Dict[Future, Dict[str, Any]] = {pool.submit(run_case, task): task for task in tasks}
    pending = set(futures)
    broken: List[Dict[str, Any]] = []
    interrupted = False
    try:
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                error = future.exception()
                if isinstance(error, BrokenProcessPool):
                    broken.append(futures[future])
                else:
                    yield _failed(futures[future], error) if error is not None else future.result()
    except BaseException:
        interrupted = True
        stop.set()
        for future in pending:
            future.cancel()
        # The running cases stop after their step (their workers' handler
        # is Python's while a case runs); idle workers ignore the signal.
        # (`_processes`, pid -> process, is the pool's own record: private,
        # but the only list of its processes, and there since Python 3.2.)
        for pid in list(getattr(pool, "_processes", None) or {}):
            try:
                os.kill(pid, signal.SIGINT)
            except OSError:
                pass
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=interrupted)
    broken.sort(key=lambda t: t["index"])
    return broken


def ray_engine(tasks: List[Dict[str, Any]], workers: int, address: Optional[str]) -> Iterator[Dict[str, Any]]:
    """Ray remote tasks of one CPU each, on the cluster at ``address`` or a
    local one of ``workers`` CPUs."""
    import logging

    import ray

    started = not ray.is_initialized()
    if started:
        if address:
            ray.init(address=address, logging_level=logging.WARNING)
        else:
            ray.init(num_cpus=workers, include_dashboard=False, logging_level=logging.WARNING)
    remote = ray.remote(num_cpus=1)(run_case)
    refs = {remote.remote(task): task for task in tasks}
    pending = list(refs)
    try:
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                try:
                    yield ray.get(ref)
                except Exception as e:  # the task's worker died or was killed
                    yield _failed(refs[ref], e)
    except BaseException:
        for ref in pending:
            ray.cancel(ref)
        raise
    finally:
        if started:
            ray.shutdown()


def dask_engine(tasks: List[Dict[str, Any]], workers: int, address: Optional[str]) -> Iterator[Dict[str, Any]]:
    """Dask futures on the scheduler at ``address`` or a local cluster of
    ``workers`` single-threaded worker processes."""
    import logging

    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    if address:
        client = Client(address)
    else:
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.WARNING,
        )
        client = Client(cluster)
    futures = {}
    try:
        for task in tasks:
            # pure=False: every submission runs (a rerun must not be served
            # from a result Dask remembers).
            futures[client.submit(run_case, task, pure=False)] = task
        for future in as_completed(list(futures)):
            try:
                yield future.result()
            except Exception as e:  # the task's worker died
                yield _failed(futures[future], e)
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
