"""The control-point count a fit's search found, kept between runs.

``bspline_fit.fit_bspline`` picks the smallest number of control points that keeps
every given point within the tolerance: about ten trial fits (doubling, then
bisection), 60–80 ms of the seal demo's plan. An engineer plans the same cell again
and again with another tool pose or speed; the points do not change, so neither does
the count. It is kept on disk (``disk_cache.cache_dir("fits")``), keyed by a hash of
everything the search reads: the points and weights (their bytes), closed, degree,
the tolerance, the fit module's source, and the numpy and scipy versions. A kept count
is a hint: the fit on it is computed as the search computes it (the same numbers) and
used only if it holds the tolerance; else the search runs as if nothing were kept.

A cache that cannot be read or written costs the search, never the answer.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import numpy as np

from offline_prog.disk_cache import cache_dir, keep


@functools.cache
def _code_version(source_file: str) -> bytes:
    """What else decides the search's answer: the fit module's source and the versions
    of the numerical libraries it runs on."""
    import scipy

    source = Path(source_file).read_bytes()
    return source + f"numpy {np.__version__} scipy {scipy.__version__}".encode()


def hint_key(
    points: np.ndarray,
    weights: np.ndarray | None,
    *,
    closed: bool,
    degree: int,
    tolerance_m: float,
    source_file: str,
) -> str:
    """The key of one search: a hash of its inputs and code (module doc).

    Args:
        points: (N, 3) the given points [m]; weights: (N,) or None.
        source_file: the fit module's file (its bytes are part of the key).
    """
    digest = hashlib.sha256(_code_version(source_file))
    for array in (points, weights):
        if array is not None:
            array = np.ascontiguousarray(array, dtype=float)
            digest.update(repr(array.shape).encode() + array.tobytes())
        else:
            digest.update(b"none")
    digest.update(f"{bool(closed)} {int(degree)} {float(tolerance_m)!r}".encode())
    return digest.hexdigest()[:32]


def read_hint(key: str) -> int | None:
    """The kept count of the search ``key``, or None (none kept, or unreadable)."""
    try:
        return int((cache_dir("fits") / key).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def keep_hint(key: str, n_control_points: int) -> None:
    """Keep the count the search ``key`` found (written whole or not at all)."""
    keep(cache_dir("fits") / key, lambda stream: stream.write(str(int(n_control_points)).encode()))
