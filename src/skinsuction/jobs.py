"""What a workflow script needs from the package: its job's preamble and writers.

Every script of ``workflow/scripts/`` starts the same way::

    from skinsuction.jobs import job

    with job(snakemake.log[0], threads=snakemake.threads):
        from skinsuction.space import compute_point   # NumPy is imported from here on
        ...                                           # one package call

:func:`job` sizes the BLAS/OpenMP thread pools to the job's threads before NumPy
is imported (the Snakemake preamble does not import it and ``skinsuction``'s
``__init__`` is lazy), then sends ``logging``, ``print`` and warnings output to
the rule's log file.  So this module imports no NumPy, and nothing above the
shared helpers: an FE job pays for nothing it does not run.

A script imports public names only (``tests/test_layers.py`` checks it): those of
this module and those the subpackages export from their ``__init__``.

Examples
--------
>>> import os, tempfile
>>> log = os.path.join(tempfile.mkdtemp(), "job.log")
>>> with job(log):
...     print("hello")
>>> open(log).read()
'hello\\n'
"""

from __future__ import annotations

from skinsuction._files import atomic_output, write_table
from skinsuction._memory import keep_freed_memory
from skinsuction._threads import limit_threads
from skinsuction.provenance import log_to_file

__all__ = ["job", "limit_threads", "log_to_file", "write_table", "atomic_output"]


def job(log, threads=None):
    """Start a workflow job: size the thread pools now, then log to ``log``.

    Parameters
    ----------
    log : str or path-like
        The rule's log file (``snakemake.log[0]``); its folder is made.
    threads : int, optional
        Size of the BLAS/OpenMP thread pools (``snakemake.threads``, or 1 where
        the job's threads are its worker processes).  Set when ``job`` is called,
        so call it before NumPy is imported.  ``None`` leaves the pools as they are.
        The job keeps its freed memory for reuse (:mod:`skinsuction._memory`).

    Returns
    -------
    contextlib.AbstractContextManager
        Entered, it sends ``logging``, ``print`` and warnings output to ``log``
        (:func:`skinsuction.provenance.log_to_file`) and yields the open file; an
        exception in the block is logged there, then raised.
    """
    if threads is not None:
        limit_threads(threads)
    keep_freed_memory()
    return log_to_file(log)
