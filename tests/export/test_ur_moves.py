"""The URScript movep program replayed from its text: its path within the path tolerance
of the plan, the flow at the planned points, the tool speed as planned."""

import re

import numpy as np
import pytest
from program_replay import fractional_row
from scipy.spatial.transform import Rotation, Slerp

from offline_prog.export.density import DEFAULT_ANGLE_TOL_RAD, DEFAULT_CHORD_TOL_M
from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.ur.urscript import ANALOG_RANGE_V, ANALOG_STEP_V
from offline_prog.io_events import Signal

from conftest import CELLS, planned_text, with_own_io

IO_TOL_M = 1e-3  # an output switched within 1 mm of where the plan sets it
IO = (
    "tool:\n  process_io:\n    on:  {digital_output: 2, lead_mm: 3}\n"
    "    off: {digital_output: 2, lead_mm: 4}\n"
    "    flow: {analog_output: 1, per_mps: 30.0, offset: 1.0, min: 0.0, max: 10.0}\n"
)

POSE = r"p\[([^\]]*)\]"
NUMBER = r"([\d.]+)"
MOVE = re.compile(
    rf"^\s*(movep|movel)\(pose_trans\((\w+), {POSE}\), a={NUMBER}, v={NUMBER}, r={NUMBER}\)"
)
SAMPLES_PER_PIECE = 24  # the replayed path: samples per straight piece and per blend


@pytest.fixture(scope="module")
def data(planned_job):
    return JobProgramData.load(planned_job("tape_cylinder_ur10e")[1])


def pose(text: str) -> np.ndarray:
    """4×4 of a URScript pose's numbers ``x, y, z, rx, ry, rz``."""
    v = np.array(text.split(","), float)
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = Rotation.from_rotvec(v[3:]).as_matrix(), v[:3]
    return X


def read_program(folder):
    """(the frames' variables by name, the program's statements): ("movej", q),
    ("move", X_TP in the named feature, feature, a, v, r), ("ao", fraction) in order."""
    nominal = (folder / "offline_prog_frames.script").read_text()
    frames = {m[1]: pose(m[2]) for m in re.finditer(rf"^global (\w+) = {POSE}", nominal, re.M)}
    steps = []
    for line in (folder / "offline_prog.script").read_text().splitlines():
        if m := MOVE.match(line):
            steps.append(("move", pose(m[3]), m[2], *map(float, m.group(4, 5, 6))))
        elif line.strip().startswith("movej("):
            steps.append(("movej", np.array(re.search(r"\[([^\]]*)\]", line)[1].split(","), float)))
        elif m := re.match(r"^\s*set_standard_analog_out\(1, ([\d.]+)\)", line):
            steps.append(("ao", float(m[1])))
        elif m := re.match(r"^\s*set_standard_digital_out\((\d+), (True|False)\)", line):
            steps.append(("do", int(m[1]), m[2] == "True"))
        elif m := re.match(r"^\s*set_tcp\((\w+)\)", line):
            steps.append(("tcp", m[1]))
    return frames, steps


def replay(waypoints: list[np.ndarray], radii: list[float]) -> np.ndarray:
    """(M, 4, 4) the TCP's poses along straight moves between the waypoints (position
    linear, orientation slerp), each inner waypoint blended over ±r: the position on the
    quadratic curve of the blend's ends and the corner, the orientation slerped between
    the ends (the blend stays in that triangle)."""

    def on(k: int, s: float) -> np.ndarray:  # the pose s [m] along move k -> k+1
        A, B = waypoints[k], waypoints[k + 1]
        length = max(np.linalg.norm(B[:3, 3] - A[:3, 3]), 1e-12)
        lam = np.clip(s / length, 0.0, 1.0)
        X = np.eye(4)
        X[:3, 3] = A[:3, 3] + lam * (B[:3, 3] - A[:3, 3])
        rot = Slerp([0, 1], Rotation.from_matrix([A[:3, :3], B[:3, :3]]))
        X[:3, :3] = rot(lam).as_matrix()
        return X

    out, lam = [], np.linspace(0.0, 1.0, SAMPLES_PER_PIECE)
    for k in range(len(waypoints) - 1):
        length = np.linalg.norm(waypoints[k + 1][:3, 3] - waypoints[k][:3, 3])
        out += [on(k, s) for s in np.linspace(radii[k], length - radii[k + 1], SAMPLES_PER_PIECE)]
        if k + 1 < len(waypoints) - 1 and radii[k + 1] > 0:
            A, B, corner = on(k, length - radii[k + 1]), on(k + 1, radii[k + 1]), waypoints[k + 1]
            rot = Slerp([0, 1], Rotation.from_matrix([A[:3, :3], B[:3, :3]]))
            for u in lam:
                X = np.eye(4)
                weights = [(1 - u) ** 2, 2 * u * (1 - u), u**2]
                X[:3, 3] = weights @ np.array([A[:3, 3], corner[:3, 3], B[:3, 3]])
                X[:3, :3] = rot(u).as_matrix()
                out.append(X)
    return np.array(out)


def distances_to_polyline(points: np.ndarray, line: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N,) distance of each point (N, 3) from the polyline (M, 3) and (N,) the index of
    the polyline's vertex nearest its closest point."""
    a, d = line[:-1], np.diff(line, axis=0)
    u = np.einsum("nmc,mc->nm", points[:, None] - a[None], d) / np.maximum((d * d).sum(1), 1e-30)
    u = np.clip(u, 0.0, 1.0)
    gap = np.linalg.norm(points[:, None] - a[None] - u[..., None] * d[None], axis=2)
    seg = gap.argmin(axis=1)
    return gap.min(axis=1), seg + np.round(u[np.arange(len(points)), seg]).astype(int)


def test_movep_program_replayed_from_its_text_stays_within_the_path_tolerance(data, tmp_path):
    check_movep_program(data, tmp_path)


@pytest.mark.slow  # plans a job of its own
def test_movep_program_switches_the_process_output_where_the_plan_sets_it(tmp_path):
    """The tape cell with a digital output and a flow of its own: the replay as above,
    and each ``set_standard_digital_out`` at the point where the plan sets it."""
    text = with_own_io((CELLS / "tape_cylinder_ur10e.yaml").read_text(), IO)
    _, data = planned_text(text, tmp_path)
    waypoints, steps = check_movep_program(data, tmp_path / "out")
    rows, switched = data.job, []
    run = [s for s in data.segments if s.seam]
    k = np.arange(run[0].start, min(run[-1].stop, len(rows.t) - 1) + 1)
    p_plan = (rows.X_BE[k] @ rows.X_EP)[:, :3, 3]
    first = next(n for n, s in enumerate(steps) if s[0] == "move")
    at = 0  # the waypoint the robot is at (blending into the next move)
    for step in steps[first - 1 :]:
        if step[0] == "move":
            at += 1
        elif step[0] == "do":
            i = int(np.argmin(np.linalg.norm(p_plan - waypoints[at][:3, 3], axis=1)))
            switched.append((step[2], rows.path_m[k[i]]))
    events = data.seam_events(data.seam_names[0])
    assert [state for state, _ in switched] == [e.state for e in events] == [True, False]
    for (_, path_m), event in zip(switched, events, strict=True):
        assert path_m == pytest.approx(event.set_path_m, abs=IO_TOL_M)


def check_movep_program(data: JobProgramData, tmp_path):
    """Export the job's movep program, replay it from its text and compare it with the
    plan's rows (see the module docstring); returns (the waypoints P in B, the
    statements)."""
    files = export(data, "urscript", tmp_path, mode="movep")
    assert [f.name for f in files] == ["offline_prog.script", "offline_prog_frames.script"]
    frames, steps = read_program(tmp_path)
    (tcp,) = [s[1] for s in steps if s[0] == "tcp"]
    rows = data.job
    # The nominal frames are the cell's; no frame value in the motion program.
    np.testing.assert_allclose(frames[tcp], rows.X_EP, atol=1e-7)
    motion_text = (tmp_path / "offline_prog.script").read_text()
    assert "global" not in motion_text and "set_tcp(p[" not in motion_text
    robot = data.load_robot()
    moves = [s for s in steps if s[0] == "move"]
    feature = {s[2] for s in moves}
    assert len(feature) == 1
    X_BT = frames[feature.pop()]
    np.testing.assert_allclose(X_BT, rows.X_BT, atol=1e-7)
    # Waypoints: where the link before the seam ends, then each move's target (P in B).
    first_move = steps.index(moves[0])
    last_movej = [k for k, s in enumerate(steps[:first_move]) if s[0] == "movej"][-1]
    start = robot.forward(steps[last_movej][1][None])[0] @ rows.X_EP
    waypoints = [start] + [X_BT @ s[1] for s in moves]
    radii = [0.0] + [s[5] for s in moves]
    assert radii[-1] == 0.0 and all(r > 0 for r in radii[1:-1])
    path = replay(waypoints, radii)
    # The plan's rows from the approach's start to the retract's end: the tool in P.
    run = [s for s in data.segments if s.seam]
    k = np.arange(run[0].start, min(run[-1].stop, len(rows.t) - 1) + 1)
    X_BP_plan = rows.X_BE[k] @ rows.X_EP
    X_PT_plan = np.linalg.inv(X_BP_plan) @ rows.X_BT
    X_PT_path = np.linalg.inv(path) @ X_BT
    gap, nearest = distances_to_polyline(X_PT_plan[:, :3, 3], X_PT_path[:, :3, 3])
    assert gap.max() <= DEFAULT_CHORD_TOL_M + 1e-7, gap.max()
    R_err = np.swapaxes(X_PT_path[nearest, :3, :3], 1, 2) @ X_PT_plan[:, :3, :3]
    angle = Rotation.from_matrix(R_err).magnitude()
    # the nearest replayed sample's orientation: within the tolerance plus the turn
    # between two replayed samples
    assert angle.max() <= DEFAULT_ANGLE_TOL_RAD + np.deg2rad(0.02), np.rad2deg(angle.max())
    # The planned speed: the moves' times at their speeds add up to the planned time.
    length = np.linalg.norm(np.diff([w[:3, 3] for w in waypoints], axis=0), axis=1)
    speeds = np.array([s[4] for s in moves])
    assert (length / speeds).sum() == pytest.approx(rows.t[k[-1]] - rows.t[k[0]], rel=0.01)
    # The flow at each point: the value last written before the move off it, against
    # the plan's ao column there (interpolated between its rows; not at its steps).
    written, at_point = None, []
    for step in steps[last_movej:]:
        if step[0] == "ao":
            written = step[1] * ANALOG_RANGE_V
        elif step[0] == "move":
            at_point.append(written)
    p_plan = X_BP_plan[:, :3, 3]
    edges = [e.t_s for e in data.events if e.signal is Signal.ANALOG]
    skipped = 0
    for m, value in enumerate(at_point):  # value: set at waypoint m, held on move m+1
        row = fractional_row(p_plan, waypoints[m][:3, 3])
        a, b = int(np.floor(row)), int(np.ceil(row))
        if any(rows.t[k[a]] - 1e-9 <= t <= rows.t[k[b]] + 1e-9 for t in edges):
            skipped += 1  # the flow's edge between these rows
            continue
        planned = np.interp(row, np.arange(len(k)), data.analog[k])
        assert value == pytest.approx(planned, abs=ANALOG_STEP_V + 0.01), m
    assert skipped <= len(edges)
    return waypoints, steps[last_movej:]


def test_servoj_takes_no_path_tolerance_and_an_unknown_mode_is_refused(data, tmp_path):
    with pytest.raises(ValueError, match="apply to mode movel or movep"):
        export(data, "urscript", tmp_path, chord_tol_m=1e-4)
    with pytest.raises(ValueError, match="mode='movec': use one of servoj, movel, movep"):
        export(data, "urscript", tmp_path, mode="movec")
    with pytest.raises(ValueError, match="need chord_tol_m > 0"):
        export(data, "urscript", tmp_path, mode="movep", chord_tol_m=0.0)
    assert not list(tmp_path.glob("*.script"))
