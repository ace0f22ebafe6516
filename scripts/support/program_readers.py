"""Controller programs read back from their text, as the tests and the figures scripts
do it: the tool's point on the part at each motion's end (from the program's own poses
and joints) and each switch statement's point, independently of the writers' code.

A KRL ``TRIGGER WHEN PATH=-d`` and a RAPID ``TriggIO``/``TriggSpeed`` at distance d
switch d before the end of the motion that follows them; the switch's point is d
before that motion's target on its chord. The readers return the motions' ends and
the switches in run order (``Point`` and ``Switch`` items) for ``program_replay`` to
place on the plan's rows, or tests to place on a known line.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from offline_prog.robot.model import load_robot

from rapid_reader import rapid_procs

# KRL's speed-following flow: ANOUT ON $ANOUT[n]=FK*$VEL_ACT+offset DELAY=-τ MIN MAX.
KRL_FLOW_LAW = re.compile(
    r"ANOUT ON \$ANOUT\[(\d+)\]=(\w+)\*\$VEL_ACT\+([-\d.]+) DELAY=([-\d.]+) "
    r"MINIMUM=([-\d.]+) MAXIMUM=([-\d.]+)"
)


@dataclasses.dataclass(frozen=True)
class Point:
    """A motion's end: the tool's point on the part p_PT (3,) [m]; ``joint`` when the
    motion is a joint move (a link's point, not on a seam's rows)."""

    p_PT: np.ndarray
    joint: bool = False


@dataclasses.dataclass(frozen=True)
class Switch:
    """A switch statement: output ``what`` set to ``value`` (the program's text) where
    the tool's point on the part is ``p_PT`` (3,) [m], ``delay_s`` after it passes
    there (KRL's DELAY); ``lag_s`` the controller's own lead (RAPID's ScaleLag) or None.
    It follows the ``Point`` of the motion it lies on."""

    what: str
    value: str
    p_PT: np.ndarray | None
    delay_s: float = 0.0
    lag_s: float | None = None


def tool_in_part(data, q: np.ndarray) -> np.ndarray:
    """p_PT [m] at joints q (6,) [rad]: X_PT = X_EP⁻¹ · X_BE(q)⁻¹ · X_BT (forward
    kinematics of the plan's robot)."""
    X_BE = load_robot(data.robot).forward(q[None])[0]
    return (np.linalg.inv(data.job.X_EP) @ np.linalg.inv(X_BE) @ data.job.X_BT)[:3, 3]


def point_before(p_from: np.ndarray, p_to: np.ndarray, d: float) -> np.ndarray:
    """The point d [m] before p_to on the straight move from p_from."""
    return p_to - d * (p_to - p_from) / np.linalg.norm(p_to - p_from)


def _placed(pending, here, target) -> list[Switch]:
    """The pending switches [(d [m] before the motion's end, Switch)] placed on the
    chord from ``here`` to ``target``."""
    return [dataclasses.replace(s, p_PT=point_before(here, target, d)) for d, s in pending]


# --- KRL ------------------------------------------------------------------------------


def krl_p_PT(decl: str) -> np.ndarray:
    """p_PT [m] of an E6POS (P in T: X, Y, Z [mm], A, B, C [deg] Z-Y'-X'')."""
    f = {k: float(v) for k, v in (i.split() for i in decl.split(",")) if k not in "ST"}
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler("ZYX", [f["A"], f["B"], f["C"]], degrees=True).as_matrix()
    X[:3, 3] = np.array([f["X"], f["Y"], f["Z"]]) * 1e-3
    return np.linalg.inv(X)[:3, 3]


def krl_run(folder: Path) -> list[tuple[str, tuple[str, str] | None]]:
    """The statements of ``offline_prog.src`` in run order, the called seam modules'
    inlined, each with the E6POS / E6AXIS it names as its module's .dat declares it:
    (kind, values), or None."""
    decls = {}
    for module in sorted(p.stem for p in folder.glob("*.src")):
        own = decls.setdefault(module, {})
        for line in (folder / f"{module}.dat").read_text(encoding="utf-8").splitlines():
            if m := re.match(r"DECL (E6POS|E6AXIS) (\w+)=\{(.*)\}$", line):
                own[m[2]] = (m[1], m[3])
    run = []

    def read(module):
        for line in (folder / f"{module}.src").read_text(encoding="utf-8").splitlines():
            if re.fullmatch(r"offline_prog_\d+\( \)", line):
                read(line.split("(")[0])
            elif line and not line.startswith(";"):
                words = line.split()
                run.append((line, decls[module].get(words[1]) if len(words) > 1 else None))

    read("offline_prog")
    return run


def krl_items(data, folder: Path) -> tuple[list[str], list[Point | Switch]]:
    """(the run's statements, its motions' ends and TRIGGERs in run order)."""
    here, pending, items = None, [], []
    run = krl_run(folder)
    for line, decl in run:
        if line.startswith("PTP "):
            axes = [float(v.split()[1]) for v in decl[1].split(",")[:6]]
            here = tool_in_part(data, np.deg2rad(axes))
            items.append(Point(here, joint=True))
        elif line.startswith("TRIGGER"):
            m = re.match(r"TRIGGER WHEN PATH=(-?[\d.]+) DELAY=(-?\d+) DO (.+)=(.+) PRIO", line)
            switch = Switch(m[3], m[4], None, delay_s=float(m[2]) * 1e-3)
            pending.append((-float(m[1]) * 1e-3, switch))
        elif line.startswith("LIN "):
            target = krl_p_PT(decl[1])
            items += [Point(target), *_placed(pending, here, target)]
            here, pending = target, []
    return [line for line, _ in run], items


# --- RAPID ----------------------------------------------------------------------------


def rapid_items(data, text: str) -> list[Point | Switch]:
    """A RAPID module's motions' ends and TriggIO / TriggSpeed switches in run order
    (a TriggSpeed's ``value`` is its ScaleValue, V per mm/s; ``lag_s`` its ScaleLag)."""
    points = {
        m[1]: np.array(m[2].split(","), float) * 1e-3
        for m in re.finditer(r"robtarget (\w+) := \[\[([^\]]*)\]", text)
    }
    joints = {
        m[1]: np.deg2rad(np.array(m[2].split(","), float))
        for m in re.finditer(r"jointtarget (\w+) := \[\[([^\]]*)\]", text)
    }
    procs = rapid_procs(text)
    run = [s for line in procs["main"] for s in procs.get(line.split(";")[0], [line])]
    defined, here, items = {}, None, []
    for line in run:
        if m := re.match(r"TriggIO (\w+), ([\d.]+)\\DOp:=(\w+), (\d);", line):
            defined[m[1]] = (float(m[2]) * 1e-3, Switch(m[3], m[4], None))
        elif m := re.match(r"TriggSpeed (\w+), ([\d.]+), ([\d.]+), (\w+), ([\d.]+);", line):
            defined[m[1]] = (float(m[2]) * 1e-3, Switch(m[4], m[5], None, lag_s=float(m[3])))
        elif m := re.match(r"MoveAbsJ (\w+)", line):
            here = tool_in_part(data, joints[m[1]])
            items.append(Point(here, joint=True))
        elif m := re.match(r"(MoveL|TriggL) (\w+)", line):
            target = points[m[2]]
            names = re.findall(r"\b(t(?:Flow)?O(?:n|ff)\d*)\b", line)
            items += [Point(target), *_placed([defined[n] for n in names], here, target)]
            here = target
    return items


# --- URScript -------------------------------------------------------------------------


def urscript_stream(script: str, output: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(K, 6) the servoj joint targets [rad], (K,) the analog output's value [V] while
    each runs, and the period [s] of the first servoj block (one-seam job: one block)."""
    period = float(re.search(r"servoj\(.*t=([\d.]+)", script)[1])
    q, value, current = [], [], 0.0
    for line in script.splitlines():
        line = line.strip()
        if m := re.match(rf"set_standard_analog_out\({output}, ([-\d.]+)\)", line):
            current = float(m[1]) * 10.0  # URScript's 0..1 of the 10 V range
        elif line.startswith("servoj("):
            q.append(np.array(re.search(r"\(\[([^\]]*)\]", line)[1].split(","), float))
            value.append(current)
    return np.array(q), np.array(value), period


def urscript_digital(script: str) -> list[tuple[int, bool, int]]:
    """[(output, state, k)]: each ``set_standard_digital_out`` and the index k of the
    servoj command that runs next (the output is set as the one before it ends)."""
    out, k = [], 0
    for line in script.splitlines():
        line = line.strip()
        if m := re.match(r"set_standard_digital_out\((\d+), (True|False)\)", line):
            out.append((int(m[1]), m[2] == "True", k))
        elif line.startswith("servoj("):
            k += 1
    return out
