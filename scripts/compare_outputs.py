"""Compare two plan folders numerically (issue 25: "no output changes beyond 1e-9 relative").

    python scripts/compare_outputs.py REF NEW [--rtol 1e-9] [--atol 1e-12]

Every file of REF must exist in NEW and the other way round. Per file:

- ``.json``: the same keys and strings; every number within tolerance. Keys whose value
  is a measured run time (``timings_s``, ``time_s``, ``*_solve_s``, ``planning_time_s``)
  and the ``generated`` stamp are skipped: they change from run to run.
- ``.npz``: the same arrays, shapes and dtypes; numbers within tolerance, strings equal
  after masking time stamps and the checkout's folder (``meta`` holds the report's
  header and the robot's files: two checkouts have them in two places).
- everything else (CSV, programs, HTML): read as text, cut into numbers and the text
  between them; the text must be equal (time stamps masked, run times listed in
  VOLATILE_TEXT masked), the numbers within tolerance.

"Within tolerance": |a − b| ≤ rtol · max(|a|, |b|, atol / rtol), i.e. relative, with an
absolute floor atol for numbers near zero. It prints the worst
difference of each file and exits 1 if any file differs beyond it.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import numpy as np

NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
STAMP = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(?:\.\d+)?(?:[+-]\d\d:\d\d|Z)?")
# The checkout a folder was planned from (two trees: two places of the bundled robots).
CHECKOUT = re.compile(r"/[^'\"\s]*?/(?=offline_prog/robots)")
VOLATILE_KEYS = {"timings_s", "time_s", "planning_time_s", "generated", "seconds", "elapsed_s"}
VOLATILE_TEXT = re.compile(
    r"(planning_time_s|time_s|_solve_s|timings_s|elapsed_s)\W{1,4}[-+.\deE]+"
)


def _masked(text: str) -> str:
    """``text`` with time stamps and the checkout's folder masked."""
    return CHECKOUT.sub("<checkout>/", STAMP.sub("<stamp>", text))


def _volatile(key: str) -> bool:
    return key in VOLATILE_KEYS or key.endswith("_solve_s")


def _walk(a, b, path: str, worst: list, rtol: float, atol: float) -> None:
    """Compare JSON values a, b; append (relative difference, path) of numbers to worst,
    and (inf, path: reason) of structural differences."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            worst.append((np.inf, f"{path}: keys {sorted(a.keys() ^ b.keys())}"))
        for key in a.keys() & b.keys():
            if not _volatile(key):
                _walk(a[key], b[key], f"{path}/{key}", worst, rtol, atol)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            worst.append((np.inf, f"{path}: length {len(a)} != {len(b)}"))
            return
        numeric = all(_is_number(x) for x in a) and all(_is_number(x) for x in b)
        if numeric and a:
            worst.append((*_numbers(np.array(a, float), np.array(b, float), atol), path))
            return
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _walk(x, y, f"{path}[{i}]", worst, rtol, atol)
    elif _is_number(a) and _is_number(b):
        worst.append((*_numbers(np.array([a], float), np.array([b], float), atol), path))
    elif isinstance(a, str) and isinstance(b, str):
        if _masked(a) != _masked(b):
            worst.append((np.inf, f"{path}: {a[:40]!r} != {b[:40]!r}"))
    elif a != b:
        worst.append((np.inf, f"{path}: {a!r} != {b!r}"))


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _numbers(a: np.ndarray, b: np.ndarray, atol: float) -> tuple[float]:
    """The largest |a − b| / max(|a|, |b|, floor): the relative difference, with an
    absolute floor for numbers near zero; NaN equals NaN. ``atol`` here is the floor."""
    a, b = a.ravel(), b.ravel()
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    if same.all():
        return (0.0,)
    a, b = a[~same], b[~same]
    scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), atol)
    with np.errstate(invalid="ignore"):
        return (float(np.nanmax(np.where(np.isfinite(a - b), np.abs(a - b) / scale, np.inf))),)


def compare_text(ref: str, new: str, atol: float) -> tuple[float, str]:
    """(worst relative difference, where) of two texts cut into numbers and the rest."""
    ref, new = (VOLATILE_TEXT.sub("<time>", _masked(t)) for t in (ref, new))
    ref_text, new_text = NUMBER.split(ref), NUMBER.split(new)
    if ref_text != new_text:
        i = next(
            (i for i, (x, y) in enumerate(zip(ref_text, new_text, strict=False)) if x != y),
            min(len(ref_text), len(new_text)),
        )
        got = ref_text[i] if i < len(ref_text) else "<end>"
        want = new_text[i] if i < len(new_text) else "<end>"
        return np.inf, f"text differs at piece {i}: {got[:60]!r} != {want[:60]!r}"
    a = np.array(NUMBER.findall(ref), float)
    b = np.array(NUMBER.findall(new), float)
    if len(a) == 0:
        return 0.0, ""
    (worst,) = _numbers(a, b, atol)
    return worst, f"{len(a)} numbers"


def compare_npz(ref: Path, new: Path, atol: float) -> tuple[float, str]:
    a, b = np.load(ref, allow_pickle=False), np.load(new, allow_pickle=False)
    if set(a.files) != set(b.files):
        return np.inf, f"arrays {sorted(set(a.files) ^ set(b.files))}"
    worst, where = 0.0, ""
    for name in a.files:
        x, y = a[name], b[name]
        if x.shape != y.shape or x.dtype.kind != y.dtype.kind:
            return np.inf, f"{name}: {x.shape} {x.dtype} != {y.shape} {y.dtype}"
        if x.dtype.kind in "US":
            if x.dtype.kind == "U" and x.ndim == 0 and str(x).startswith("{"):
                found, place = compare_json(json.loads(str(x)), json.loads(str(y)), atol)
            else:
                found, place = compare_text(str(x), str(y), atol)
        else:
            (found,), place = _numbers(x.astype(float), y.astype(float), atol), ""
        if found > worst:
            worst, where = found, f"{name} {place}".strip()
    return worst, where


def compare_json(a, b, atol: float) -> tuple[float, str]:
    worst: list = []
    _walk(a, b, "", worst, 0.0, atol)
    if not worst:
        return 0.0, ""
    value, where = max(worst, key=lambda w: w[0])
    return value, where


def compare_file(ref: Path, new: Path, atol: float) -> tuple[float, str]:
    if ref.suffix == ".npz":
        return compare_npz(ref, new, atol)
    if ref.suffix == ".json":
        return compare_json(json.loads(ref.read_text()), json.loads(new.read_text()), atol)
    return compare_text(ref.read_text(errors="replace"), new.read_text(errors="replace"), atol)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ref", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--rtol", type=float, default=1e-9)
    parser.add_argument("--atol", type=float, default=1e-12, help="absolute floor (zeros)")
    args = parser.parse_args()
    files = {p.relative_to(args.ref) for p in args.ref.rglob("*") if p.is_file()}
    others = {p.relative_to(args.new) for p in args.new.rglob("*") if p.is_file()}
    failed = False
    for name in sorted(files ^ others):
        print(f"{str(name):40s} only in {'REF' if name in files else 'NEW'}")
        failed = True
    for name in sorted(files & others):
        floor = args.atol / args.rtol
        worst, where = compare_file(args.ref / name, args.new / name, floor)
        bad = worst > args.rtol
        failed |= bad
        where = where if worst > 0 else ""
        print(f"{str(name):40s} worst {worst:9.2e} {'FAIL ' if bad else ''}{where}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
