"""Independent cases of a study or benchmark, run in parallel with dask.distributed.

By default a local cluster of processes (one per core, one thread each) is started for the
sweep; ``scheduler`` connects to an existing cluster instead.  Workers share the C kernel
cache safely (``runtime.kernels.jit`` compiles each kernel once, whatever the number of processes).
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Sequence

from runtime.progress import Bar


class SchedulerError(ValueError):
    """The requested dask scheduler cannot be reached."""


def _connect(scheduler: str, timeout_s: float):
    """A dask Client of ``scheduler``; SchedulerError when it cannot connect or when the peer
    accepts the connection but does not answer as a scheduler within ``timeout_s`` (dask's own
    timeout does not bound that wait)."""
    from dask.distributed import Client

    outcome: dict = {}

    def connect() -> None:
        try:
            outcome["client"] = Client(scheduler, timeout=f"{timeout_s}s")
        except Exception as error:  # noqa: BLE001 - reported below, in the caller's thread
            outcome["error"] = error

    thread = threading.Thread(target=connect, name="dask-connect", daemon=True)
    thread.start()
    thread.join(timeout_s + 5.0)
    if "client" in outcome:
        return outcome["client"]
    reason = (f"{outcome['error']}" if "error" in outcome else
              f"the address accepted the connection but no dask scheduler answered within "
              f"{timeout_s + 5.0:g} s")
    raise SchedulerError(f"--scheduler {scheduler}: cannot connect to a dask scheduler there "
                         f"({reason})")


def run_cases(function: Callable, cases: Sequence[dict], scheduler: str | None = None,
              workers: int | None = None, serial: bool = False,
              connect_timeout_s: float = 10.0, label: str = "cases") -> list:
    """``[function(**case) for case in cases]``, computed in parallel.

    function: a module-level (picklable) function; cases: keyword arguments of each call.
    scheduler: address of an existing dask scheduler (e.g. ``tcp://host:8786``); None starts
    a local cluster with ``workers`` processes (default: the number of cores).
    serial: run in this process instead (debugging, or a single case).
    connect_timeout_s: the longest wait (plus 5 s of grace) for ``scheduler`` to answer.
    label: names the sweep in the progress line (n of N cases, elapsed, ETA).
    Results come back in the order of ``cases``; an exception in a case is raised here.
    """
    if not cases:
        raise ValueError("sweep: no cases to run (the study declared no runs)")
    if serial or (len(cases) == 1 and scheduler is None):
        with Bar(label, len(cases), "cases") as bar:
            results = []
            for case in cases:
                results.append(function(**case))
                bar.advance()
            return results
    from dask.distributed import Client, LocalCluster, as_completed

    if scheduler is not None:
        client = _connect(scheduler, connect_timeout_s)
        cluster = None
    else:
        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                               processes=True, dashboard_address=":0")
        client = Client(cluster)
    try:
        futures = [client.submit(function, pure=False, **case) for case in cases]
        with Bar(label, len(cases), "cases") as bar:
            for _ in as_completed(futures):
                bar.advance()
        return client.gather(futures)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
