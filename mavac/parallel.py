"""Parallelism: one helper for trials and sweeps, built on joblib so the backend can be swapped,
and a context that keeps small numerical problems on one thread.

Locally it runs on processes (``loky``); on a cluster, wrap a call in
``joblib.parallel_backend("dask")`` after creating a ``dask.distributed.Client`` and the
experiment code does not change.
"""

from __future__ import annotations

import functools
import os
from typing import Callable, Iterable, Sequence

from joblib import Parallel, delayed
from threadpoolctl import ThreadpoolController
from tqdm.auto import tqdm

from .validate import check_callable, check_int, check_sequence


@functools.lru_cache(maxsize=1)
def _threadpools() -> ThreadpoolController:
    return ThreadpoolController()  # scanning the loaded libraries is slow: do it once


def single_thread():
    """Context limiting BLAS/OpenMP to one thread: small problems (K-means on a few thousand
    pixels, a GP on ~100 points) only lose to thread contention, 10-30x on a busy machine."""
    return _threadpools().limit(limits=1)


def map_trials(fn: Callable, items: Iterable, *, n_jobs: int | None = None, backend: str | None = None,
               desc: str | None = None, progress: bool = True) -> list:
    """Apply ``fn`` to every item, in parallel, and return the results in item order.

    Parameters
    ----------
    fn : callable
        Picklable function of one argument. It must take its randomness from its argument
        (e.g. a seed), never from global state, so results do not depend on scheduling.
    items : iterable
        Arguments, one per trial.
    n_jobs : int, optional
        Worker count; default ``MAVAC_JOBS`` or 1 (``-1`` uses every core).
    backend : str, optional
        joblib backend name (``"loky"``, ``"threading"``, ``"dask"`` ...).
    desc : str, optional
        tqdm label.
    progress : bool
        Show a tqdm progress bar.
    """
    check_callable("fn", fn, "of one item")
    items: Sequence = check_sequence("items", items)
    if n_jobs is None:
        env = os.environ.get("MAVAC_JOBS", "1")
        try:
            n_jobs = int(env)
        except ValueError:
            raise ValueError(f"MAVAC_JOBS must be an integer worker count, got {env!r}") from None
    n_jobs = check_int("n_jobs", n_jobs, -1)
    if n_jobs == 0:
        raise ValueError("n_jobs must be a positive worker count or -1 (all cores), got 0")
    iterator = tqdm(items, desc=desc, disable=not progress, leave=False)
    if n_jobs == 1 and backend is None:
        return [fn(item) for item in iterator]
    return list(Parallel(n_jobs=n_jobs, backend=backend)(delayed(fn)(item) for item in iterator))
