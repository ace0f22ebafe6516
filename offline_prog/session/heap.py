"""The session process keeps freed memory for its next re-plan (glibc's malloc).

A re-plan allocates and frees the same few hundred arrays of a few hundred kB each
(N samples × 6 joints × 8 bytes) every time. glibc hands blocks of that size out as
fresh ``mmap`` pages and returns them on ``free``, so every array is page-faulted in
again: a fifth of a weld seam's joint plan. A long-lived interactive process is better
served by keeping them: blocks up to ``MMAP_THRESHOLD_BYTES`` come from the heap, and
up to ``TRIM_THRESHOLD_BYTES`` of freed heap stay with the process. The numbers the
plan computes do not change, only where its arrays live. Elsewhere than glibc (macOS,
Windows, musl) nothing is changed.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging

log = logging.getLogger(__name__)

# mallopt(3) parameters (glibc's malloc.h).
M_TRIM_THRESHOLD, M_TOP_PAD, M_MMAP_THRESHOLD = -1, -2, -3
MMAP_THRESHOLD_BYTES = 32 * 2**20  # glibc's largest on 64-bit (4 MiB × sizeof(long))
TRIM_THRESHOLD_BYTES = 256 * 2**20  # freed heap kept before it is returned to the OS
TOP_PAD_BYTES = 16 * 2**20  # the heap grows by at least this much at a time

_done = False


def keep_freed_memory() -> bool:
    """Set glibc's malloc to keep blocks below MMAP_THRESHOLD_BYTES on the heap and
    freed heap up to TRIM_THRESHOLD_BYTES (once per process).

    Returns:
        Whether glibc took the settings (False elsewhere).
    """
    global _done
    if _done:
        return True
    name = ctypes.util.find_library("c")
    try:
        mallopt = ctypes.CDLL(name).mallopt
    except (OSError, AttributeError, TypeError):  # not glibc: nothing to set
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    settings = (
        (M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES),
        (M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES),
        (M_TOP_PAD, TOP_PAD_BYTES),
    )
    _done = all(mallopt(option, value) == 1 for option, value in settings)
    if not _done:
        log.debug("mallopt refused the session's heap settings")
    return _done
