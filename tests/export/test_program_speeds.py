"""Every speed written to a program is in the controller's unit and range.

Reproduction: ``motion.speed: 100`` (mm/s meant) reached KRL as ``$VEL.CP = 100`` (m/s).
The cell check now refuses it (tests/config/test_safe_yaml.py); a plan file carrying
such speeds is refused by each writer as well.
"""

import dataclasses
import re

import pytest

from offline_prog.export.abb.rapid import MAX_SPEED_MMS
from offline_prog.export.formats import export
from offline_prog.export.job_program import JobProgramData
from offline_prog.export.kuka.kuka import VEL_CP_MAX_M_S
from offline_prog.export.program import ProgramData


def slipped(data: ProgramData) -> ProgramData:
    """Rows as if their speeds had been given in mm/s: 1000 times too fast."""
    return dataclasses.replace(
        data,
        process_speed_m_s=data.process_speed_m_s * 1e3,
        tcp_speed=data.tcp_speed * 1e3,
        t=data.t * 1e-3,
    )


def mm_per_s_slip(data: JobProgramData) -> JobProgramData:
    """The job as if its speeds had been given in mm/s: the job's and each seam's rows."""
    seams = tuple(slipped(seam) for seam in data.seams)
    return dataclasses.replace(data, job=slipped(data.job), seams=seams)


@pytest.fixture(scope="module")
def plans(planned_job):
    return [
        JobProgramData.load(planned_job(name)[1]) for name in ("seal_job_kr16", "weld_seam_irb2400")
    ]


def test_written_speeds_are_in_range(plans, tmp_path):
    kuka, abb = plans
    krl = "".join(
        f.read_text() for f in export(kuka, "krl", tmp_path / "krl") if f.suffix == ".src"
    )
    vel_cp = [float(v) for v in re.findall(r"\$VEL\.CP=([\d.]+)", krl)]
    assert vel_cp and all(0 < v <= VEL_CP_MAX_M_S for v in vel_cp)
    # In m/s: the fastest written speed is a seam's process speed (within the 0.1 mm/s
    # floor of $VEL.CP), not 1000 times it.
    fastest = max(seam.process_speed_m_s for seam in kuka.seams)
    assert max(vel_cp) == pytest.approx(fastest, abs=1e-4)
    rapid = "".join(f.read_text() for f in export(abb, "rapid", tmp_path / "rapid"))
    speeds = [float(v) for v in re.findall(r"speeddata \w+ := \[([\d.]+),", rapid)]
    assert speeds and all(0 < v <= MAX_SPEED_MMS for v in speeds)
    assert max(speeds) == pytest.approx(abb.seams[0].process_speed_m_s * 1e3, abs=0.1)  # mm/s


def test_speeds_beyond_the_controller_are_refused(plans, tmp_path):
    kuka, abb = (mm_per_s_slip(data) for data in plans)
    with pytest.raises(ValueError, match=r"m/s, not mm/s"):
        export(kuka, "krl", tmp_path / "krl")
    with pytest.raises(ValueError, match=r"m/s, not mm/s"):
        export(abb, "rapid", tmp_path / "rapid")
    assert not any(p.is_file() for p in tmp_path.rglob("*") if p.suffix in (".src", ".mod"))


def off_seam(data: JobProgramData, *, approach_m_s: float, link_percent: float):
    """The job as planned with motion.approach_speed and motion.link_speed_percent."""
    seams = tuple(dataclasses.replace(s, approach_speed_m_s=approach_m_s) for s in data.seams)
    job = dataclasses.replace(data.job, link_speed_percent=link_percent)
    return dataclasses.replace(data, job=job, seams=seams)


def test_the_approach_speed_and_the_link_override_are_written(
    planned_with_moves, planned_job, tmp_path
):
    """Approach and retract LIN / MoveL at motion.approach_speed; KRL's PTP override
    and URScript's movej speed at motion.link_speed_percent (issue 37). (The demos
    planned with straight approach and retract moves: at the default approach speed a
    flying seam's leads take them over.)"""
    with_moves = [planned_with_moves(n)[1] for n in ("seal_plate_kr16", "weld_seam_irb2400")]
    kuka, abb = (off_seam(d, approach_m_s=0.05, link_percent=40.0) for d in with_moves)
    krl = "".join(f.read_text() for f in export(kuka, "krl", tmp_path / "krl"))
    assert "BAS(#VEL_PTP,40)" in krl
    assert "$VEL.CP=0.0500" in krl
    rapid = "".join(f.read_text() for f in export(abb, "rapid", tmp_path / "rapid"))
    (approach,) = re.findall(r"MoveL pA1, (\w+),", rapid)
    assert re.search(rf"speeddata {approach} := \[50,", rapid)
    ur_full = JobProgramData.load(planned_job("tape_cylinder_ur10e")[1])
    ur = off_seam(ur_full, approach_m_s=0.05, link_percent=40.0)

    def movej_speeds(data, folder):
        text = "".join(f.read_text() for f in export(data, "urscript", tmp_path / folder))
        return [float(x) for x in re.findall(r"movej\(.*v=([\d.]+)\)", text)]

    v, v_full = movej_speeds(ur, "ur"), movej_speeds(ur_full, "ur_full")
    assert v and v[0] == pytest.approx(0.4 * v_full[0], abs=1e-3)
