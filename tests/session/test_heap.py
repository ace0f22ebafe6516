"""The session process keeps freed memory: re-allocated arrays are not faulted in again."""

import resource
import sys

import numpy as np
import pytest

from offline_prog.session.heap import keep_freed_memory

ROWS = 20_000  # a re-plan's sample count order: (N, 6) float64, ~1 MB per array


def _page_faults(rounds: int) -> int:
    """Minor page faults while an (ROWS, 6) array is made, written and freed rounds times."""
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for _ in range(rounds):
        a = np.empty((ROWS, 6))
        a.fill(1.0)  # touch every page
        del a
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc")
def test_freed_arrays_are_reused_without_page_faults():
    assert keep_freed_memory()
    assert keep_freed_memory()  # once per process; asking again is harmless
    _page_faults(2)  # the heap grows once
    pages = ROWS * 6 * 8 // resource.getpagesize()
    # Without the settings each round faults in every page of the array again.
    assert _page_faults(20) < pages
