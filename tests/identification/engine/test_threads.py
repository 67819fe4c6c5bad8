"""``engine.threads.one_blas_thread``: one BLAS thread inside, the caller's limit after."""

from threadpoolctl import threadpool_info, threadpool_limits

from flightid.identification.engine.threads import one_blas_thread


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_one_blas_thread_inside_and_the_limit_lifted_after():
    seen = one_blas_thread(_blas_threads)()
    assert seen and all(n == 1 for n in seen)
    with threadpool_limits(limits=2, user_api="blas"):  # a caller's own limit comes back
        assert one_blas_thread(_blas_threads)() == [1] * len(seen)
        assert all(n == 2 for n in _blas_threads())
