"""The placement folder: placement.json, placed.yaml, placement.html, best_preview.html.

* ``placement.json`` (the contract): ``best`` and ``candidates`` (top-k), each with
  ``X_IT`` and ``X_PE`` as ``{translation [m], rpy_deg}``, ``feasible``,
  ``cycle_time_s``, every objective term and the failure reason when infeasible;
  ``baseline`` (the cell as given), ``cycle_time_cut`` (the cut and, when it is under
  CUT_TARGET, why), ``stands`` (how each stand changed for the best), ``screening``
  (every screened candidate's fate: planned, screened out and by what, or why it was
  not planned), ``search`` and ``engine`` (scheduler, workers, candidates evaluated,
  wall time).
* ``placed.yaml``: the cell file's text with the best X_IT and X_PE written in (the
  stands moved and lengthened, the description saying what was placed), data files
  re-pointed from the new folder: ``offline-prog plan placed.yaml`` plans it.
* ``placement.html``: a top view of the search (screened grid, evaluated candidates
  coloured by cycle time, failures by reason), the top-k table and the best plan.
"""

from __future__ import annotations

import collections
import json
import math
from pathlib import Path

import numpy as np

from offline_prog.config.cell_text import relocated_text
from offline_prog.placement.context import Context, placed_stands, pose_of
from offline_prog.placement.objective import Evaluation
from offline_prog.placement.search import FATES, Placement
from offline_prog.placement.space import Pose, SearchSpace
from offline_prog.placement.top_view import Layout

CUT_TARGET = 0.15  # the cycle-time cut a placement search should find (issue 16)


def _pose(pose: Pose) -> dict:
    return {"translation": list(pose[0]), "rpy_deg": list(pose[1])}


def _finite(value: float):
    return value if math.isfinite(value) else None


def terms(e: Evaluation) -> dict:
    """One candidate in placement.json."""
    return {
        "X_IT": _pose(e.candidate.X_IT),
        "X_PE": _pose(e.candidate.X_PE),
        "grasp": e.candidate.grasp,
        "feasible": e.feasible,
        "cycle_time_s": _finite(e.cycle_time_s),
        "joint_limit_margin_deg": _finite(e.joint_limit_margin_deg),
        "singularity_margin_deg": _finite(e.singularity_margin_deg),
        "clearance_mm": _finite(e.clearance_mm),
        "tool_rotation_deg": e.tool_rotation_deg,
        "slowed_share": e.slowed_share,
        "limiting_axis": e.limiting_axis or None,
        "process_bound_s": _finite(e.process_bound_s),
        "air_time_s": e.air_time_s,
        "quality_share_within_band": _finite(e.quality_share),
        "tier": e.tier,
        "violation": e.violation,
        "reason": e.reason,
        "failure": e.failure,
        "evaluation_s": e.seconds,
        "lower_bound_s": _finite(e.bound_s),
    }


DISTINCT_M, DISTINCT_DEG = 0.005, 1.0  # candidates closer than this are one in the table


def _top(evaluated: list[Evaluation], k: int) -> list[Evaluation]:
    """The k best distinct candidates (the baseline included when it ranks): each
    differs from every better one by DISTINCT_M in its tool position, DISTINCT_DEG in
    its tool rotation, or in its grasp."""
    top = []
    for e in sorted(evaluated, key=Evaluation.key):
        if not any(_same(e.candidate, other.candidate) for other in top):
            top.append(e)
        if len(top) == k:
            break
    return top


def _same(a, b) -> bool:
    (p, rpy), (q, rpz) = a.X_IT, b.X_IT
    near = math.dist(p, q) < DISTINCT_M
    turned = max(abs((x - y + 180.0) % 360.0 - 180.0) for x, y in zip(rpy, rpz, strict=True))
    return near and turned < DISTINCT_DEG and a.X_PE == b.X_PE


def screening(result: Placement) -> dict:
    """placement.json's ``screening``: what became of every screened candidate."""
    counts = collections.Counter(result.fates)
    return {
        "fates": {fate: counts.get(fate, 0) for fate in FATES},
        "meaning": FATES,
        "candidates": [
            {
                "X_IT": _pose(e.candidate.X_IT),
                "grasp": e.candidate.grasp,
                "fate": fate,
                "stage": e.stage,
                "estimate_s": _finite(e.cycle_time_s) if e.stage != "plan" else None,
                "lower_bound_s": _finite(e.bound_s),
                "reason": e.reason,
            }
            for e, fate in zip(result.screened, result.fates, strict=True)
        ],
    }


def stand_changes(ctx: Context, best: Evaluation) -> list[dict]:
    """placement.json's ``stands``: each stand as given and as placed for the best."""
    return [
        {
            "name": s.stand.name,
            "length_mm_given": 1e3 * s.stand.length_m,
            "length_mm": 1e3 * s.length_m,
            "lengthened_mm": 1e3 * (s.length_m - s.stand.length_m),
            "foot_z_mm": 1e3 * s.stand.foot_z,
            "X_IO": _pose(pose_of(s.X_IO)),
            "reason": s.reason,
        }
        for s in placed_stands(ctx, best.candidate)
    ]


WRIST_AXES = (4, 5, 6)


def cycle_time_cut(result: Placement, tool=None) -> dict:
    """The cut of the cycle time against the cell as given, and why it is not larger
    when it is under CUT_TARGET (``tool``: the cell's ToolConfig, for the hint that a
    round tool fixed about its axis could turn along the path)."""
    base, best = result.baseline, result.best
    if not best.feasible:
        return {"percent": None, "why_not_more": "no feasible placement was found"}
    if not base.feasible:
        return {"percent": None, "why_not_more": "", "note": "the cell as given is infeasible"}
    cut = 1.0 - best.cycle_time_s / base.cycle_time_s
    out = {"percent": 100.0 * cut, "why_not_more": ""}
    if cut >= CUT_TARGET:
        return out
    bound = best.process_bound_s
    possible = 1.0 - bound / base.cycle_time_s
    why = (
        f"the process speed alone takes {bound:.2f} s (path length / speed with the time "
        f"law's ramps), so no placement can cut more than {100 * possible:.1f} %"
    )
    if best.air_time_s > 0:  # a job: approach, retract and links come on top
        possible = 1.0 - (bound + best.air_time_s) / base.cycle_time_s
        why = (
            f"the seams at the process speed alone take {bound:.2f} s and the best job "
            f"spends {best.air_time_s:.2f} s off them (approach, retract, links): with those "
            f"moves no placement cuts more than {100 * possible:.1f} %"
        )
    feasible = [e for e in result.evaluated if e.feasible]
    axes = collections.Counter(e.limiting_axis for e in feasible if e.limiting_axis)
    if axes and possible >= CUT_TARGET:
        axis, count = axes.most_common(1)[0]
        least = min(e.slowed_share for e in feasible)
        why += (
            f"; every feasible placement evaluated ({len(feasible)}) still slows at least "
            f"{100 * least:.0f} % of the path below the process speed, limited by axis "
            f"{axis} in {count} of them: the seam's shape needs that joint motion wherever "
            "the tool stands"
        )
        fixed = tool is not None and tool.free_rotation_deg > 0 and tool.turn_smoothing_mm == 0
        if fixed and axis in WRIST_AXES:  # the part's turns land on the wrist
            why += (
                " with the tool's turn fixed: tool.turn_smoothing_mm would let the tool "
                "take up the part's turns"
            )
    out["why_not_more"] = why
    return out


def layout_of(ctx: Context, best: Evaluation) -> Layout:
    """The top view's robot base, its reach and the best's stands (``top_view``)."""
    robot, p_IB = ctx.inputs.robot, ctx.inputs.X_IB.translation()
    params = robot.params
    if robot.family == "opw":
        reach = params.a1 + params.c2 + math.hypot(params.a2, params.c3)
    elif robot.family == "ur":
        reach = abs(params.a2) + abs(params.a3) + abs(params.d5)
    else:
        reach = 0.0
    stands = []
    obstacles = ctx.inputs.cell.obstacles
    for stand in placed_stands(ctx, best.candidate):
        shape = obstacles[stand.stand.index]
        if shape.shape == "box":
            hx, hy = 0.5e-3 * shape.size_mm[0], 0.5e-3 * shape.size_mm[1]
            local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        else:
            angle = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)
            local = 1e-3 * shape.radius_mm * np.column_stack([np.cos(angle), np.sin(angle)])
        R = stand.X_IO.rotation().matrix()[:2, :2]
        corners = 1e3 * (local @ R.T + stand.X_IO.translation()[:2])
        stands.append((stand.stand.name, corners))
    return Layout((1e3 * p_IB[0], 1e3 * p_IB[1]), 1e3 * reach, stands)


def placement_json(
    result: Placement, space: SearchSpace, place, engine: dict, ctx: Context
) -> dict:
    """placement.json's content (see the module)."""
    return {
        "best": terms(result.best),
        "baseline": terms(result.baseline),
        "cycle_time_cut": cycle_time_cut(result, ctx.inputs.cell.tool),
        "candidates": [terms(e) for e in _top(result.evaluated, place.top_k)],
        "stands": stand_changes(ctx, result.best),
        "screening": screening(result),
        "search": {
            "budget": place.budget,
            "seed": place.seed,
            "screen_points": len(result.screened),
            "screen_feasible": sum(e.feasible for e in result.screened),
            "axes": [
                {
                    "key": a.key,
                    "low": a.low,
                    "high": a.high,
                    "unit": "m" if a.kind == "translation" else "deg",
                }
                for a in space.axes
            ],
            "grasps": [_pose(g) for g in space.grasps],
            # Infeasible candidates by kind (errors.Failure values, or "refused").
            "failures": dict(
                collections.Counter(e.failure for e in result.evaluated if not e.feasible)
            ),
        },
        "engine": engine,
    }


def placed_text(cell_file: Path, ctx: Context, best: Evaluation, out_dir: Path) -> str:
    """The cell file's text with the best placement, to be written into ``out_dir``."""
    poses = {"tool.X_IT": best.candidate.X_IT, "part.X_PE": best.candidate.X_PE}
    numbers = {}
    for stand in placed_stands(ctx, best.candidate):
        poses[f"obstacles.{stand.stand.index}.pose"] = pose_of(stand.X_IO)
        numbers[stand.length_key()] = round(1e3 * stand.length_m, 3)
    strings = {"description": placed_description(cell_file, ctx, best)}
    return relocated_text(cell_file, ctx.inputs.cell, out_dir, poses, strings, numbers)


def placed_description(cell_file: Path, ctx: Context, best: Evaluation) -> str:
    """placed.yaml's ``description``: what was placed, from which cell."""
    (p, rpy), c = best.candidate.X_IT, best.candidate
    what = (
        f"Placed by offline-prog place from {cell_file.name}: the tool at "
        f"({', '.join(f'{1e3 * v:.1f}' for v in p)}) mm, rpy "
        f"({', '.join(f'{v:g}' for v in rpy)}) deg"
    )
    if c.grasp >= 0:
        what += f", grasp {c.grasp + 1}"
    for stand in placed_stands(ctx, c):
        what += (
            f"; {stand.stand.name} {1e3 * stand.stand.length_m:.0f} -> "
            f"{1e3 * stand.length_m:.0f} mm long"
        )
    if best.feasible:
        return what + f"; cycle {best.cycle_time_s:.2f} s home to home."
    return what + f"; infeasible: {best.reason}."


def write_json(file: Path, data: dict) -> None:
    file.write_text(json.dumps(data, indent=1, allow_nan=False) + "\n", encoding="utf-8")
