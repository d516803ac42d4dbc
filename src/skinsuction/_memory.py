"""Keep freed memory in the process instead of handing it back to the system.

The fits evaluate a thousand candidates at every sample of a time curve: arrays of
tens of MB made and freed thousands of times. glibc's malloc serves such arrays by
``mmap`` and returns them on ``free``, so every new one faults its pages in afresh:
a quarter of a time-curve diagnosis's CPU was the kernel's (101 of 371 s,
``docs/workflow.md``). Raising the thresholds keeps them in the heap, reused.
"""

import ctypes
import ctypes.util

#: mallopt's parameters (glibc's malloc.h)
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
#: Blocks below this come from the heap, and the heap keeps this much free at its top.
KEEP_BYTES = 1 << 30


def keep_freed_memory(keep_bytes: int = KEEP_BYTES) -> bool:
    """Ask glibc's malloc to keep up to ``keep_bytes`` of freed memory for reuse.

    A process's settings, inherited by the workers it forks. Without glibc (macOS,
    musl) nothing is changed: the results are the same, only slower.

    Parameters
    ----------
    keep_bytes : int
        The mmap and trim thresholds, in bytes.

    Returns
    -------
    bool
        Whether both thresholds were set.

    Examples
    --------
    >>> isinstance(keep_freed_memory(), bool)
    True
    """
    name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError, TypeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    # older glibc caps the mmap threshold at 32 MiB: the arrays of a fit fit under it
    ok = any(mallopt(_M_MMAP_THRESHOLD, v) == 1 for v in (int(keep_bytes), 1 << 25))
    return bool(mallopt(_M_TRIM_THRESHOLD, int(keep_bytes)) == 1 and ok)
