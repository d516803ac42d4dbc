"""Keep the BLAS/OpenMP thread pools of a job to its share of the cores."""

import os

_POOLS = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
)


def limit_threads(threads):
    """Set the thread-pool sizes; call before NumPy is imported to take effect.

    Parameters
    ----------
    threads : int
        Threads of every pool (``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS``, ...).

    Returns
    -------
    None
        The pools are set in ``os.environ``, read by NumPy's BLAS when it loads.
    """
    for name in _POOLS:
        os.environ[name] = str(threads)
