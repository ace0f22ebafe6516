"""Whole-job programs read back with independent parsers: KRL (KR 16-2 demo job), RAPID
(IRB 2400 weld seam as a one-seam job) and URScript (UR10e tape as a one-seam job).

Each asserts what a cell engineer checks on the controller: the links go through the
planned joint targets, approach and retract have the asked lengths, and the process
output switches within ±1 mm of the asked positions along the path (on ``lead_mm``
before each seam's start, off ``lead_mm`` before its end), reconstructed from the
program's own statements and poses."""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from krl_lint import assert_krllint_clean
from scipy.spatial.transform import Rotation

from offline_prog.config.cell import load_cell
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.merge import MIN_MOTION_M
from offline_prog.plan import plan_job
from offline_prog.results.job_folder import write_job_outputs

from conftest import CELLS, with_own_io
from rapid_reader import rapid_procs

IO_TOL_M = 1e-3  # the issue: within ±1 mm
LENGTH_TOL_M = 0.01e-3  # approach / retract lengths
JOINT_TOL_DEG = 1e-3
IO = (
    "tool:\n  process_io:\n    on:  {digital_output: 2, lead_mm: 3}\n"
    "    off: {digital_output: 2, lead_mm: 4}\n"
    "    flow: {analog_output: 1, per_mps: 30.0, offset: 1.0, min: 0.0, max: 10.0}\n"
)


def one_seam_job(tmp_path, name: str, home: str) -> object:
    text = (CELLS / f"{name}.yaml").read_text()
    if re.search(r"(?m)^job:", text):  # the cell's own job: block (its home) stays
        text = re.sub(r"(?m)^job:.*\n", lambda m: m.group(0) + "  order: given\n", text, count=1)
    else:
        text = text.replace("motion:", f"job: {{order: given{home}}}\nmotion:", 1)
    text = with_own_io(text, IO)
    file = tmp_path / f"{name}_job.yaml"
    file.write_text(text)
    return file


JOBS = {  # robot language ↦ (demo cell, job.home)
    "rapid": ("weld_seam_irb2400", ", home: {joints_deg: [0, -20, 20, 0, 60, 0]}"),
    "urscript": ("tape_cylinder_ur10e", ""),
}


class Folders(dict):
    """language ↦ (JobProgramData, programs folder, plan folder), planned when asked."""

    def __init__(self, planned_job, work):
        super().__init__()
        self.planned_job, self.work = planned_job, work
        self.cells = {"krl": CELLS / "seal_job_kr16.yaml"}  # language ↦ its cell file

    def __missing__(self, language):
        if language == "krl":
            folder = self.planned_job("seal_job_kr16")[1]
        else:
            if not (self.work / "data").exists():
                shutil.copytree(CELLS / "data", self.work / "data")  # path and mesh files
            self.cells[language] = one_seam_job(self.work, *JOBS[language])
            job = plan_job(self.cells[language])
            assert job.feasible, job.failure
            folder = self.work / language
            write_job_outputs(job, folder)
        self[language] = (JobProgramData.load(folder), folder / "programs", folder)
        return self[language]


@pytest.fixture(scope="module")
def folders(planned_job, tmp_path_factory):
    return Folders(planned_job, tmp_path_factory.mktemp("jobs"))


def asked(cell_file: Path, data: JobProgramData, k: int) -> tuple[float, float]:
    """(on, off) positions along seam k's path [m] the cell asks for: on ``on.lead_mm``
    before the seam's start, off ``off.lead_mm`` before its end (L the seam's planned
    length), from the cell file's own numbers."""
    io = load_cell(cell_file).tool.process_io
    return -io.on.lead_mm * 1e-3, data.seam_lengths_m[k] - io.off.lead_mm * 1e-3


# --- KRL --------------------------------------------------------------------------------

KRL_DECL = re.compile(r"^DECL (E6POS|E6AXIS) (\w+)=\{(.*)\}$")


def krl_fields(text: str) -> dict[str, float]:
    return {
        k: float(v) for k, v in (item.split() for item in text.split(",")) if k != "S" and k != "T"
    }


def krl_tool_in_part(fields) -> np.ndarray:
    """p_PT [m]: the E6POS is P in T (X_TP, KUKA Z-Y'-X'' angles); the tool in P is its
    inverse's translation."""
    X = np.eye(4)
    X[:3, :3] = Rotation.from_euler(
        "ZYX", [fields["A"], fields["B"], fields["C"]], degrees=True
    ).as_matrix()
    X[:3, 3] = np.array([fields["X"], fields["Y"], fields["Z"]]) * 1e-3
    return np.linalg.inv(X)[:3, 3]


def krl_run(folder: Path, name: str = "offline_prog"):
    """(statements in execution order (module, line), declarations by module)."""
    decls, run = {}, []

    def read(module):
        decls[module] = {
            m[2]: (m[1], m[3])
            for line in (folder / f"{module}.dat").read_text().splitlines()
            if (m := KRL_DECL.match(line))
        }
        for line in (folder / f"{module}.src").read_text().splitlines():
            if line.startswith(";") or not line.strip():
                continue
            if re.fullmatch(rf"{name}_\d+\( \)", line):
                read(line.split("(")[0])
            else:
                run.append((module, line))

    read(name)
    return run, decls


def test_krl_job_links_approach_retract_and_io(folders, tmp_path):
    data, folder, _ = folders["krl"]
    run, decls = krl_run(folder)
    main = decls["offline_prog"]
    specs = {s.name: s for s in load_cell(CELLS / "seal_job_kr16.yaml").seams}
    # Links: every PTP target is the plan's waypoint, in order (home first).
    ptp = [main[line.split()[1]][1] for _, line in run if line.startswith("PTP ")]
    axes = np.array([[v for k, v in krl_fields(f).items() if k.startswith("A")] for f in ptp])
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    np.testing.assert_allclose(axes, np.rad2deg(planned), atol=JOINT_TOL_DEG)
    # Walk the statements: the tool's point on the part, its path position per seam
    # (from the seam's first planned sample: a flying seam's lead-in starts before 0).
    q_link, pending, here, position, k, switched = None, None, None, 0.0, -1, {}
    ends = {}  # seam k ↦ [p_PT where its approach starts, where its retract ends] [m]
    for module, line in run:
        if line.startswith("PTP "):
            if k in ends and ends[k][1] is None:
                ends[k][1] = here
            q_link = np.deg2rad(axes[[f for f in ptp].index(main[line.split()[1]][1])])
        elif line.startswith("TRIGGER") and "DO $OUT[" in line:  # the process output
            pending = (float(re.search(r"PATH=(-?[\d.]+)", line)[1]) * 1e-3, "TRUE" in line)
        elif line.startswith("LIN "):
            name = line.split()[1]
            p = krl_tool_in_part(krl_fields(decls[module][name][1]))
            in_seam = re.fullmatch(r"offline_prog_(\d+)(_\d+)?", module)
            if name.startswith("XA") or (in_seam and int(in_seam[1]) - 1 != k):
                # The seam's approach (a straight LIN) or its first LIN from the link's end
                # (a flying seam's lead took the straight move over: none is written).
                k += 1
                here = tool_in_part_from_joints(data, q_link)
                ends[k] = [here, None]
                position = data.seams[k].path_m[0]
                spec = specs[data.seam_names[k]].approach
                if name.startswith("XA"):  # it ends at the seam's first sample
                    length = np.linalg.norm(p - here)
                    assert length > MIN_MOTION_M  # no empty LIN where a lead took it over
                    if spec.kind == "tangent":
                        assert length == pytest.approx(spec.distance_mm * 1e-3, abs=LENGTH_TOL_M)
                    here = p
            if here is not p:
                step = np.linalg.norm(p - here)
                assert step > MIN_MOTION_M or not name.startswith("XR")  # none empty
                if name.startswith("XR") and specs[data.seam_names[k]].retract.kind == "tangent":
                    spec = specs[data.seam_names[k]].retract
                    assert step == pytest.approx(spec.distance_mm * 1e-3, abs=LENGTH_TOL_M)
                position += step
            if in_seam:  # a seam's point: where the plan's path puts it (a lead's σ is
                # shorter than the tool's path on a curved seam's lead: position it there)
                seam = data.seams[k]
                gap = np.linalg.norm(seam.X_PT[:, :3, 3] - p, axis=1)
                assert gap.min() < LENGTH_TOL_M  # the program's point is the plan's
                position = seam.path_m[np.argmin(gap)]
            here = p
            if pending is not None:  # PATH = -d: d before this motion's end point
                switched.setdefault(k, {})[pending[1]] = position + pending[0]
                pending = None
    # A normal approach starts, a normal retract ends its distance off the part along
    # the seams' normal (P's z, into the plate): at rest straight along it, flying partly
    # or wholly on the lead.
    for k, (start, end) in ends.items():
        spec = specs[data.seam_names[k]]
        for move, p in ((spec.approach, start), (spec.retract, end)):
            if move.kind == "normal":
                assert -p[2] == pytest.approx(move.distance_mm * 1e-3, abs=LENGTH_TOL_M)
    assert sorted(switched) == list(range(len(data.seam_names)))
    for k in switched:
        on, off = asked(folders.cells["krl"], data, k)
        assert switched[k][True] == pytest.approx(on, abs=IO_TOL_M)
        assert switched[k][False] == pytest.approx(off, abs=IO_TOL_M)
    # The cell's frame numbers (tool.controller_frame 3, part.controller_frame 2).
    cell = load_cell(folders.cells["krl"])
    base, tool = cell.tool.controller_frame, cell.part.controller_frame
    assert (base, tool) == (3, 2)
    assert {f"$BASE=BASE_DATA[{base}]", f"$TOOL=TOOL_DATA[{tool}]"} <= {line for _, line in run}
    frames = (folder / "offline_prog_frm.src").read_text()
    assert f"BASE_DATA[{base}]={{" in frames and f"TOOL_DATA[{tool}]={{" in frames
    assert_krllint_clean(folder, tmp_path)


def tool_in_part_from_joints(data: JobProgramData, q: np.ndarray) -> np.ndarray:
    """p_PT [m] at joints q: X_PT = X_EP⁻¹ · X_BE(q)⁻¹ · X_BT (forward kinematics)."""
    from offline_prog.robot.model import load_robot

    X_BE = load_robot(data.robot).forward(q[None])[0]
    return (np.linalg.inv(data.job.X_EP) @ np.linalg.inv(X_BE) @ data.job.X_BT)[:3, 3]


# --- RAPID ------------------------------------------------------------------------------

ROBTARGET = re.compile(r"robtarget (\w+) := \[\[([^\]]*)\],\[([^\]]*)\]")
JOINTTARGET = re.compile(r"jointtarget (\w+) := \[\[([^\]]*)\]")
MOVE = re.compile(r"^(MoveL|TriggL|MoveAbsJ) (\w+)")


def rapid_run(module_text: str):
    """(statements in execution order, robtarget positions [m], jointtargets [deg])."""
    points = {
        m[1]: np.array(m[2].split(","), float) * 1e-3 for m in ROBTARGET.finditer(module_text)
    }
    joints = {m[1]: np.array(m[2].split(","), float) for m in JOINTTARGET.finditer(module_text)}
    procs = rapid_procs(module_text)
    run = []
    for line in procs["main"]:
        call = line.split(";")[0]
        run += procs.get(call, [line])
    return run, points, joints


@pytest.mark.slow  # plans a job of its own (CI runs it: pytest -m slow)
def test_rapid_job_links_approach_retract_and_io(folders):
    data, folder, _ = folders["rapid"]
    text = (folder / "OfflineProg.mod").read_text()
    run, points, joints = rapid_run(text)
    targets = [MOVE.match(line)[2] for line in run if line.startswith("MoveAbsJ")]
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    axes = np.rad2deg(planned)
    axes[:, 2] += axes[:, 1]  # the IRB 2400's axis 3: q2 + q3 (its robot.yaml j23_factor 1)
    np.testing.assert_allclose([joints[t] for t in targets], axes, atol=JOINT_TOL_DEG)
    triggs, here, position, switched, q_link = {}, None, 0.0, {}, None
    # The seam's plane: its start point p0 and the surface normal n in P (a DXF seam);
    # a flying seam's lead lifts off it, the straight approach and retract the rest.
    seam = data.seams[0]
    p0 = np.array([np.interp(0.0, seam.path_m, seam.X_PT[:, i, 3]) for i in range(3)])
    n_P = np.array(load_cell(folders.cells["rapid"]).path.normal, float)
    for line in run:
        if line.startswith("TriggIO"):
            name, rest = line.split()[1].rstrip(","), line.split(",", 1)[1]
            triggs[name] = (float(rest.split("\\")[0]) * 1e-3, rest.strip().endswith(", 1;"))
            continue
        m = MOVE.match(line)
        if m is None:
            continue
        if m[1] == "MoveAbsJ":
            q_link = planned[targets.index(m[2])]
            continue
        p = points[m[2]]
        if m[2] == "pA1":  # it ends at the seam's first sample (a flying lead-in's start)
            start = tool_in_part_from_joints(data, q_link)
            off_part = (p0 - start) @ n_P  # the tool backs off the surface along −n
            assert off_part == pytest.approx(0.05, abs=LENGTH_TOL_M)  # its distance
            position = seam.path_m[0]
        else:
            step = np.linalg.norm(p - here)
            position += step
            if m[2] == "pR1":  # it ends its distance off the part
                assert (p0 - p) @ n_P == pytest.approx(0.05, abs=LENGTH_TOL_M)
        here = p
        if m[1] == "TriggL":
            for name in re.findall(r"\b(tOn|tOff)\b", line):
                distance, state = triggs[name]
                switched[state] = position - distance
    on, off = asked(folders.cells["rapid"], data, 0)
    assert switched[True] == pytest.approx(on, abs=IO_TOL_M)
    assert switched[False] == pytest.approx(off, abs=IO_TOL_M)
    assert "TriggSpeed tFlow" in text and f"ao{data.process_io.analog_output}" in text


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # rapidchecker's pyparsing calls
@pytest.mark.slow
def test_rapid_job_passes_rapidchecker(folders):
    rapidchecker = pytest.importorskip("rapidchecker.cli", reason="rapidchecker not installed")
    _, folder, _ = folders["rapid"]
    assert [str(e) for e in rapidchecker.check_file((folder / "OfflineProg.mod").read_text())] == []


# --- URScript ---------------------------------------------------------------------------


@pytest.mark.slow  # plans a job of its own
def test_urscript_job_links_and_io(folders):
    data, folder, _ = folders["urscript"]
    lines = (folder / "offline_prog.script").read_text().splitlines()
    q_of = lambda line: np.array(re.search(r"\(\[([^\]]*)\]", line)[1].split(","), float)  # noqa: E731
    movej = [q_of(line) for line in lines if line.strip().startswith("movej(")]
    planned = [data.link_waypoints[0][0]] + [q for w in data.link_waypoints for q in w[1:]]
    np.testing.assert_allclose(movej, planned, atol=1e-7)
    # The path position of the tool at each servoj: along the approach from its start,
    # then along the seam's planned points (σ of the nearest dense sample).
    seam = data.seams[0]
    p_seam = seam.X_PT[:, :3, 3]
    switched, last_q = {}, None
    pending = None
    for line in lines:
        line = line.strip()
        if line.startswith("set_standard_digital_out"):
            pending = "True" in line
        elif line.startswith("servoj("):
            last_q = q_of(line)
            if pending is not None:
                p = tool_in_part_from_joints(data, last_q)
                gap = np.linalg.norm(p_seam - p, axis=1)
                i = int(np.argmin(gap))
                if seam.path_m[i] < 1e-6 and gap[i] > 1e-4:  # off the seam's start: approach
                    position = -gap[i]
                else:
                    position = seam.path_m[i]
                switched[pending] = position
                pending = None
    on, off = asked(folders.cells["urscript"], data, 0)
    assert switched[True] == pytest.approx(on, abs=IO_TOL_M)
    assert switched[False] == pytest.approx(off, abs=IO_TOL_M)
    assert any(line.strip().startswith("set_standard_analog_out") for line in lines)


def test_export_offers_only_what_a_plan_accepts_and_refuses_the_rest_in_one_line(folders, capsys):
    """``export --help`` lists no option that every plan refuses (the one-seam
    writers' ``--style`` is gone; ``--mode`` is URScript's servoj / movel / movep); a flag
    of another format is one line, exit 2, naming the flags the format takes."""
    from offline_prog.cli import main

    _, _, plan_folder = folders["krl"]
    out = plan_folder.parent / "reexport"
    assert main(["export", str(plan_folder), "--format", "krl", "--out", str(out)]) == 0
    assert (out / "offline_prog.src").is_file()
    with pytest.raises(SystemExit):
        main(["export", "--help"])
    usage = capsys.readouterr().out
    assert "--style" not in usage and "--tcp-pose-convention" in usage
    assert "--mode {servoj,movel,movep}" in usage
    for flags, words in [
        (["--style", "flange"], "unrecognized arguments: --style flange"),
        (["--mode", "movep"], "--mode: not an option of --format krl"),
    ]:
        argv = ["export", str(plan_folder), "--format", "krl", *flags, "--out", str(out)]
        try:
            code = main(argv)
        except SystemExit as error:  # argparse's own
            code = error.code
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and words in err[0], err
