"""Every speed written to a program is in the controller's unit and range.

Reproduction: ``motion.speed: 100`` (mm/s meant) reached KRL as ``$VEL.CP = 100`` (m/s).
The cell check now refuses it (tests/config/test_safe_yaml.py); a plan file carrying
such speeds is refused by each writer as well.
"""

import dataclasses
import re

import pytest

from offline_prog.export.abb.rapid import MAX_SPEED_MMS, write_rapid
from offline_prog.export.kuka.krl import write_krl
from offline_prog.export.kuka.kuka import VEL_CP_MAX_M_S
from offline_prog.export.program import ProgramData
from offline_prog.export.ur.urscript import MOVEL_MAX_SPEED_M_S, write_urscript


def mm_per_s_slip(data: ProgramData) -> ProgramData:
    """The plan as if its speeds had been given in mm/s: 1000 times too fast."""
    return dataclasses.replace(
        data,
        process_speed_m_s=data.process_speed_m_s * 1e3,
        tcp_speed=data.tcp_speed * 1e3,
        t=data.t * 1e-3,
    )


@pytest.fixture(scope="module")
def plans(planned_folder):
    names = ("seal_plate_kr16", "weld_seam_irb2400", "tape_cylinder_ur10e")
    return [ProgramData.load(planned_folder(name)[1]) for name in names]


def test_written_speeds_are_in_range(plans, tmp_path):
    kuka, abb, ur = plans
    krl = write_krl(kuka, tmp_path / "krl").files[0].read_text()
    vel_cp = [float(v) for v in re.findall(r"\$VEL\.CP=([\d.]+)", krl)]
    assert vel_cp and all(0 < v <= VEL_CP_MAX_M_S for v in vel_cp)
    # In m/s: the fastest written speed is the cell's process speed (within the 0.1 mm/s
    # floor of $VEL.CP), not 1000 times it.
    assert max(vel_cp) == pytest.approx(kuka.process_speed_m_s, abs=1e-4)
    rapid = "".join(f.read_text() for f in write_rapid(abb, tmp_path / "rapid").files)
    speeds = [float(v) for v in re.findall(r"speeddata \w+ := \[([\d.]+),", rapid)]
    assert speeds and all(0 < v <= MAX_SPEED_MMS for v in speeds)
    assert max(speeds) == pytest.approx(abb.process_speed_m_s * 1e3, abs=0.1)  # mm/s
    ur_text = write_urscript(ur, tmp_path / "ur", mode="movel").file.read_text()
    movel = [float(v) for v in re.findall(r"v=([\d.]+), r=", ur_text)]
    assert movel and all(0 < v <= MOVEL_MAX_SPEED_M_S for v in movel)


def test_speeds_beyond_the_controller_are_refused(plans, tmp_path):
    kuka, abb, ur = (mm_per_s_slip(data) for data in plans)
    with pytest.raises(ValueError, match=r"m/s, not mm/s"):
        write_krl(kuka, tmp_path / "krl")
    with pytest.raises(ValueError, match=r"m/s, not mm/s"):
        write_rapid(abb, tmp_path / "rapid")
    with pytest.raises(ValueError, match=r"m/s, not mm/s"):
        write_urscript(ur, tmp_path / "ur", mode="movel")
    assert not any(p.is_file() for p in tmp_path.rglob("*"))
