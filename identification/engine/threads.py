"""One BLAS thread for work made of many small matrices.

A multi-threaded BLAS wakes its threads for every call, and on 4 x 4 to 22 x 22
matrices that costs more than the arithmetic: the filter's matrix exponentials and
Riccati solutions took 20 s of CPU instead of 2 s on a loaded 2-core machine, and a gap
diagnosis of the NASA Twin Otter record 22-23 s of CPU instead of 13-15 s (its batched
colored-residual bounds).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from threadpoolctl import threadpool_limits

P = ParamSpec("P")
R = TypeVar("R")


def one_blas_thread(function: Callable[P, R]) -> Callable[P, R]:
    """``function`` run with a single BLAS thread (the limit is lifted on return).

    Parameters
    ----------
    function : callable
        The function to wrap.

    Returns
    -------
    callable
        The wrapped function.
    """

    @functools.wraps(function)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)

    return wrapper
