"""The jobs whose programs the replay tests and ``scripts/program_bead_figures.py`` read
back: demo cells laying the sealing demo's bead (lag 0.08 s) with their seams flying,
planned and exported to one controller's program.

Per controller: KUKA the seal job (border, two holes, stripe) with every seam flying;
ABB the weld demo's seam; UR the sealing demo's plate border carried by the tape demo's
UR10e past the nozzle, flying on its default leads (``plate_on_ur10e``); FANUC the seal
job's stripe on the M-20iA imported from the ROS-Industrial support packages.

The tape demo's own seam does not fly on its default leads: the lead-in, 76 mm of tool
path before a start where the UR10e's forearm is already near its wrist, stretches the
elbow (joint 3 from 49° to 35°) and link_3 meets link_6; the seam falls back to rest.
Its leads reach into the clearance from 26 mm on, and the ramp to 0.15 m/s under the
bead's caps needs 54 mm; 8, 12 and 20 mm leads leave the approach's start closer to the
part than the clearance; 5 mm is too short for the ramp (the seam starts at 0.03 m/s).
The replay tests still run its program with 5 mm leads (``UR_LEAD_MM``).
"""

from __future__ import annotations

import re
from pathlib import Path

BEAD = (  # the bead of the sealing demo (lag 0.08 s), for any demo's robot
    "process:\n  model: bead\n"
    "  bead: {area_mm2: 12.0, tolerance_pct: 5, flow_mm3_s_per_unit: 250.0, lag_s: 0.08}\n"
)
UR_LEAD_MM = 5.0  # the tape demo's leads that fly (module docstring)
# Where the sealing demo's nozzle stands for the UR10e: the tape demo's roller contact
# (X_IT) 0.7 m in front of the robot, 0.3 m high; its stand's top 0.2 m under the tip,
# as in the sealing demo.
UR_NOZZLE = ("[1.0, 0.0, 0.5]", "[0.7, 0.0, 0.3]")
UR_NOZZLE_STAND = (
    "size_mm: [200, 200, 300], pose: {translation: [1.0, 0, 0.150]}",
    "size_mm: [200, 200, 100], pose: {translation: [0.7, 0, 0.050]}",
)
FLYING_IO = (  # the gun at the seam's ends, the flow following the speed
    "tool:\n  process_io:\n    on:  {digital_output: 2}\n    off: {digital_output: 2}\n"
    "    flow: {analog_output: 1}\n"
)


def with_own_io(text: str, io: str) -> str:
    """A demo cell's text with its process model and its process I/O replaced by ``io``
    (``"tool:\\n  process_io: ..."``): tests of the I/O writers bring their own outputs."""
    text = re.sub(r"(?ms)^process:.*?(?=^\S)", "", text)
    text = re.sub(r"(?m)^  # The dispenser's flow output.*\n", "", text)
    text = re.sub(r"(?m)^  process_io:\n(    .*\n)*", "", text)
    return text.replace("tool:\n", io, 1)


def one_seam_flying(cells: Path, name: str, *, lead_mm: float | None = None) -> str:
    """cells/<name>.yaml (a one-seam demo, ``path:``) laying BEAD with FLYING_IO, its
    seam ``entry: flying`` with ``motion.lead_mm`` (None: the default)."""
    text = with_own_io((cells / f"{name}.yaml").read_text(encoding="utf-8"), FLYING_IO)
    text = text.replace("  closed: false\n", "  closed: false\n  entry: flying\n", 1)
    motion = "motion:\n" + (f"  lead_mm: {lead_mm}\n" if lead_mm is not None else "")
    text = text.replace("motion:\n", BEAD + motion, 1)
    return text.replace(": data/", f": {cells}/data/")


def plate_on_ur10e(cells: Path) -> str:
    """cells/seal_plate_kr16.yaml (the sealing demo: the plate's border, a closed seam)
    laying BEAD with FLYING_IO, carried by the tape demo's UR10e (its ``robot:``) past
    the nozzle placed for it (UR_NOZZLE, UR_NOZZLE_STAND); the seam flying (the default
    entry) on its default leads."""
    text = with_own_io((cells / "seal_plate_kr16.yaml").read_text(encoding="utf-8"), FLYING_IO)
    tape = (cells / "tape_cylinder_ur10e.yaml").read_text(encoding="utf-8")
    robot = re.search(r"(?ms)^robot:\n.*?(?=^\S)", tape).group(0)
    text = re.sub(r"(?ms)^robot:\n.*?(?=^\S)", lambda _: robot, text, count=1)
    for old, new in (UR_NOZZLE, UR_NOZZLE_STAND):
        assert old in text, old  # the sealing demo's nozzle, as this helper knows it
        text = text.replace(old, new, 1)
    return text.replace("motion:\n", BEAD + "motion:\n", 1)


def seal_job_flying(cells: Path) -> str:
    """cells/seal_job_kr16.yaml laying BEAD (the flow's gain from the bead model), every
    seam ``entry: flying`` (none sets an overlap)."""
    text = (cells / "seal_job_kr16.yaml").read_text(encoding="utf-8")
    text = text.replace("per_mps: 40.0, offset: 0.5, ", "")
    text = text.replace("    normal: [0, 0, 1]\n", "    normal: [0, 0, 1]\n    entry: flying\n")
    return text.replace("motion:", BEAD + "motion:", 1)


def stripe_job(text: str) -> tuple[str, str]:
    """The seal job's text cut to its stripe, run forward in the given order: (the text
    before ``seams:``, to edit; the rest from ``seams:`` on)."""
    head, rest = text.split("seams:", 1)
    seam = rest[rest.index("  - name: stripe") : rest.index("job:")]
    tail = rest[rest.index("job:") :].replace("order: auto", "order: given")
    return head, "seams:\n" + seam.replace("direction: auto", "direction: forward") + tail


def stripe_flying(text: str) -> str:
    """The seal job's text (on any robot) cut to its stripe laying BEAD, run flying with
    the gun on at its start and off at its end."""
    head, seams = stripe_job(text)
    head = head.replace("per_mps: 40.0, offset: 0.5, ", "")
    head = head.replace("lead_mm: 5}", "lead_mm: 0}").replace("lead_mm: 2}", "lead_mm: 0}")
    return (
        BEAD + head + seams.replace("direction: forward", "direction: forward\n    entry: flying")
    )


def on_m20ia(text: str) -> str:
    """A KR 16 cell's text on the M-20iA imported into ``robots/`` beside it."""
    return text.replace("model: kuka_kr16_2\n", "model: fanuc_m20ia\n  robots_dir: robots\n")


def import_m20ia(work: Path, fanuc: Path) -> None:
    """The M-20iA from the ROS-Industrial FANUC support packages in ``fanuc`` into
    ``work/robots``."""
    from offline_prog.robot_import.run import import_robot

    import_robot(
        fanuc / "fanuc_m20ia_support/urdf/m20ia.xacro",
        name="fanuc_m20ia",
        out=work / "robots",
        package_paths=[fanuc],
        vendor="fanuc",
        samples=500,
    )


def exported(cell: Path, fmt: str, *, flying: bool = False):
    """The cell planned, its outputs written beside it (``plan/``) and its program in
    ``fmt`` (``<fmt>/``): (job, plan folder, JobProgramData, the program's folder).
    ``flying``: every seam runs flying (no fallback to rest)."""
    from offline_prog.export.formats import controller_post
    from offline_prog.export.job_program import JobProgramData
    from offline_prog.export.post import write_program
    from offline_prog.plan import plan_job
    from offline_prog.results.job_folder import write_job_outputs

    job = plan_job(cell)
    assert job.feasible, job.failure
    if flying:
        entries = [o.plan.entry for o in job.chosen]
        assert all(e["entry"] == "flying" for e in entries), entries
    folder = cell.parent / "plan"
    write_job_outputs(job, folder)
    data = JobProgramData.load(folder)
    write_program(controller_post(data, fmt), cell.parent / fmt)
    return job, folder, data, cell.parent / fmt
