"""Independent jobs on a local process pool or a Dask distributed cluster, with a progress
bar: what ``make tradeoffs`` and ``make turntable`` spread their work with.

On a cluster each job is a task; its function and arguments must pickle, and a worker builds
the simulator models it needs into its own ``build/`` (on this machine the workers share the
client's, where the models are built before the jobs start)."""
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed

from tqdm import tqdm

__all__ = ["run"]


def run(fn, tasks, jobs=2, dask=None, desc="jobs", unit="job", label=None, key=None,
        quiet=False):
    """``fn(*task)`` for every task, the results in ``tasks``' order. ``dask``: a scheduler's
    address or a ``distributed.Client`` (none: a pool of ``jobs`` processes); ``label(result)``:
    the bar's note on a finished job; ``key(k, task)``: a task's Dask key."""
    bar = tqdm(total=len(tasks), desc=desc, unit=unit, file=sys.stderr, disable=quiet)
    out = [None] * len(tasks)

    def done(k, result):
        out[k] = result
        bar.update(1)
        if label:
            bar.set_postfix_str(label(result))

    try:
        if dask is None:
            with ProcessPoolExecutor(jobs) as pool:
                futs = {pool.submit(fn, *t): k for k, t in enumerate(tasks)}
                for fut in as_completed(futs):
                    done(futs[fut], fut.result())
        else:
            from distributed import Client, as_completed as dask_completed
            client = dask if isinstance(dask, Client) else Client(dask)
            try:
                futs = {client.submit(fn, *t, pure=False,
                                      **({"key": key(k, t)} if key else {})): k
                        for k, t in enumerate(tasks)}
                for fut in dask_completed(list(futs)):
                    done(futs[fut], fut.result())
            finally:
                if client is not dask:
                    client.close()
    finally:
        bar.close()
    return out
