"""Count the short and slow motion statements of exported programs (issue 42).

Usage:
    python scripts/motion_statements.py PROGRAMS_DIR [PROGRAMS_DIR ...]

Reads each folder's programs back from their text (FANUC ``.ls``, KRL ``.src``/``.dat``,
RAPID ``.mod``, URScript ``.script``) and prints, per folder and controller: the linear
motion statements, how many move the programmed TCP less than 0.5 mm (and 0.1 mm), how
many are at or below 5 mm/sec (FANUC), and the deviation from the plan the programs'
headers state. A statement's length is the distance between its target and the one
before it in the same program part (the first target of a part is not counted).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import numpy as np

SHORT_M = 0.5e-3


def _fanuc(folder: Path):
    lengths, speeds = [], []
    for file in sorted(folder.glob("*.ls")):
        text = file.read_text(encoding="utf-8")
        mn, pos = text.split("/MN\n", 1)[1].split("/POS\n", 1)
        xyz = {
            int(k): np.array([float(x), float(y), float(z)]) * 1e-3
            for k, x, y, z in re.findall(
                r"P\[(\d+)\]\{[^}]*?X = (\S+)\s+mm,\s*Y = (\S+)\s+mm,\s*Z = (\S+)\s+mm", pos
            )
        }
        here = None
        for k, speed in re.findall(r"L P\[(\d+)\] (\d+)mm/sec", mn):
            p = xyz[int(k)]
            if here is not None:
                lengths.append(float(np.linalg.norm(p - here)))
                speeds.append(int(speed))
            here = p
    return lengths, speeds


def _krl(folder: Path):
    lengths = []
    for src in sorted(folder.glob("*.src")):
        dat = src.with_suffix(".dat").read_text(encoding="utf-8")
        xyz = {
            name: np.array([float(x), float(y), float(z)]) * 1e-3
            for name, x, y, z in re.findall(r"DECL E6POS (\w+)=\{X (\S+),Y (\S+),Z ([^,]+),", dat)
        }
        here = None
        for name in re.findall(r"^LIN (\w+)", src.read_text(encoding="utf-8"), re.M):
            if name in xyz:
                if here is not None:
                    lengths.append(float(np.linalg.norm(xyz[name] - here)))
                here = xyz[name]
    return lengths, []


def _rapid(folder: Path):
    lengths = []
    for mod in sorted(folder.glob("*.mod")):
        text = mod.read_text(encoding="utf-8")
        xyz = {
            name: np.array([float(x), float(y), float(z)]) * 1e-3
            for name, x, y, z in re.findall(r"robtarget (\w+) := \[\[(\S+?),(\S+?),(\S+?)\]", text)
        }
        for proc in text.split("PROC ")[1:]:
            here = None
            for name in re.findall(r"(?:MoveL|TriggL) (\w+),", proc):
                if here is not None:
                    lengths.append(float(np.linalg.norm(xyz[name] - here)))
                here = xyz[name]
    return lengths, []


def _urscript(folder: Path):
    lengths = []
    for script in sorted(folder.glob("*.script")):
        text = script.read_text(encoding="utf-8")
        here = None
        for x, y, z in re.findall(r"move[lp]\(p\[([^,]+), ([^,]+), ([^,]+),", text):
            p = np.array([float(x), float(y), float(z)])
            if here is not None:
                lengths.append(float(np.linalg.norm(p - here)))
            here = p
    return lengths, []


READERS = {"fanuc": _fanuc, "krl": _krl, "rapid": _rapid, "urscript": _urscript}
SUFFIX = {"fanuc": ".ls", "krl": ".src", "rapid": ".mod", "urscript": ".script"}


def _deviation(folder: Path) -> str:
    """The deviation lines the programs' headers state."""
    found = set()
    for file in folder.iterdir():
        if file.suffix in SUFFIX.values():
            text = file.read_text(encoding="utf-8")
            text = re.sub(r" ;\n\s*\d+:\s*! ", " ", text)  # FANUC remarks: one line
            found |= set(re.findall(r"deviation[^\n;]*?(<=\s*[\d.]+ ?mm)", text))
    return ", ".join(sorted(found)) or "-"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="+", type=Path)
    args = parser.parse_args(argv)
    print(
        f"{'folder':40s} {'format':8s} {'linear':>7s} {'<0.5mm':>7s} {'<0.1mm':>7s} "
        f"{'<=5mm/s':>8s}  stated deviation"
    )
    for folder in args.folders:
        for fmt, suffix in SUFFIX.items():
            if not any(folder.glob(f"*{suffix}")):
                continue
            lengths, speeds = READERS[fmt](folder)
            lengths = np.asarray(lengths)
            slow = sum(s <= 5 for s in speeds) if speeds else "-"
            print(
                f"{str(folder)[-40:]:40s} {fmt:8s} {len(lengths):7d} "
                f"{int((lengths < SHORT_M).sum()):7d} {int((lengths < 1e-4).sum()):7d} "
                f"{slow!s:>8s}  {_deviation(folder)}"
            )


if __name__ == "__main__":
    main()
