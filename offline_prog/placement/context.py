"""What a worker keeps of the cell between candidates, and the cell of one candidate.

A worker unpacks the payload once (``payload.unpack``), loads it as ``plan`` does and
fits each seam's path once: the seams do not move on the part, whatever the placement.
A candidate's cell is the loaded one with its X_IT and X_PE (``session.state.apply``,
which keeps every other value), and the obstacles that stand with the tool
(``place.moves_with_tool``) moved with it, their foot on the floor (``placement.stand``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from offline_prog.config.cell import Cell, transform
from offline_prog.config.edits import CellValues, apply, initial_values, schema_transform
from offline_prog.job.seams import job_seams, seam_inputs
from offline_prog.placement.payload import CellPayload, unpack
from offline_prog.placement.space import Candidate, Pose
from offline_prog.placement.stand import PlacedStand, Stand, place_stands, stands
from offline_prog.robot.model import ROBOTS_DIR
from offline_prog.stages import FittedPath, Inputs, fit_path, load_inputs

SCREEN_SAMPLES = 1000  # σ samples of a seam's path-IK screen (corners need ~10 each)


@dataclasses.dataclass
class SeamView:
    """One seam as the screen sees it: its Inputs, its fitted path and σ samples."""

    inputs: Inputs
    fit: FittedPath
    screen_s: np.ndarray  # (SCREEN_SAMPLES,) σ [m]


@dataclasses.dataclass
class Context:
    """The loaded cell of a worker.

    Attributes:
        inputs: the cell as given (a job's, for a job).
        seams: every seam (one for a ``path:`` cell, a one-seam job).
        initial: the cell's own editable values; stands: the obstacles that stand
            with the tool, as given; stand_max_m: how long a stand may be made [m].
        fits: (seam index, reversed) ↦ fitted path, for ``plan_loaded_job``: each seam
            is fitted once per direction in this process, whatever the placement.
    """

    inputs: Inputs
    seams: list[SeamView]
    initial: CellValues
    stands: list[Stand]
    stand_max_m: float
    fits: dict[tuple[int, bool], FittedPath] = dataclasses.field(default_factory=dict)


_CONTEXTS: dict[str, Context] = {}  # per worker process: one loaded cell per payload


def _seam(inputs: Inputs) -> SeamView:
    fit = fit_path(inputs)
    return SeamView(inputs, fit, np.linspace(0.0, fit.path.length, SCREEN_SAMPLES))


def load_context(cell_file: Path) -> Context:
    """The cell loaded as ``plan`` loads it, each seam fitted once.

    Raises:
        InputError: naming ``cell_file`` and the key (bad data, a fit that fails).
    """
    inputs = load_inputs(cell_file, ROBOTS_DIR)
    cell = inputs.cell
    seams = [_seam(seam_inputs(inputs, k)) for k in range(len(job_seams(cell)))]
    fits = {(k, False): seam.fit for k, seam in enumerate(seams)}
    limit = 1e-3 * cell.place.stand_max_length_mm if cell.place else 0.0
    return Context(inputs, seams, initial_values(cell), stands(cell), limit, fits)


def context(payload: CellPayload) -> Context:
    """This process's Context for ``payload``: kept, or loaded from its unpacked copy."""
    kept = _CONTEXTS.get(payload.digest)
    if kept is None:
        _CONTEXTS.clear()
        kept = _CONTEXTS[payload.digest] = load_context(unpack(payload))
    return kept


def keep(payload: CellPayload, ctx: Context) -> None:
    """Use ``ctx`` (loaded from the user's own file) as this process's copy of
    ``payload``: the in-process engine then loads nothing again."""
    _CONTEXTS.clear()
    _CONTEXTS[payload.digest] = ctx


def rigid(pose: Pose) -> RigidTransform:
    """The RigidTransform of (p [m], rpy [deg])."""
    p, rpy = pose
    return RigidTransform(RollPitchYaw(np.deg2rad(rpy)), np.asarray(p, dtype=float))


def pose_of(X: RigidTransform) -> Pose:
    """(p [m], rpy [deg]) of a RigidTransform, rounded to 1 µm and 1e-6 deg."""
    p = tuple(round(float(v), 6) + 0.0 for v in X.translation())
    rpy = RollPitchYaw(X.rotation()).vector()
    return p, tuple(round(float(np.rad2deg(a)), 6) + 0.0 for a in rpy)


def placed_stands(ctx: Context, candidate: Candidate) -> list[PlacedStand]:
    """The stands at the candidate's tool pose, their foot on the floor (poses and
    lengths rounded as :func:`pose_of` rounds: placed.yaml holds these numbers)."""
    placed = place_stands(ctx.stands, ctx.inputs.X_IT, rigid(candidate.X_IT), ctx.stand_max_m)
    return [
        dataclasses.replace(s, X_IO=rigid(pose_of(s.X_IO)), length_m=round(s.length_m, 6))
        for s in placed
    ]


def placed_cell(ctx: Context, candidate: Candidate) -> Cell:
    """The cell with the candidate's X_IT and X_PE and its stands placed."""
    state = dataclasses.replace(
        ctx.initial,
        p_IT=candidate.X_IT[0],
        rpy_IT_deg=candidate.X_IT[1],
        p_PE=candidate.X_PE[0],
        rpy_PE_deg=candidate.X_PE[1],
    )
    cell = apply(ctx.inputs.cell, ctx.initial, state)
    placed = placed_stands(ctx, candidate)
    if not placed:
        return cell
    obstacles = list(cell.obstacles)
    for stand in placed:
        i = stand.stand.index
        obstacles[i] = stand.shape(obstacles[i], schema_transform(*pose_of(stand.X_IO)))
    return dataclasses.replace(cell, obstacles=obstacles)


def placed_inputs(ctx: Context, candidate: Candidate) -> Inputs:
    """The loaded cell's Inputs with the candidate's cell and poses."""
    cell = placed_cell(ctx, candidate)
    return dataclasses.replace(
        ctx.inputs, cell=cell, X_IT=transform(cell.tool.X_IT), X_PE=transform(cell.part.X_PE)
    )
