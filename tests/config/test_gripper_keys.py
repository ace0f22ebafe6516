"""Bad gripper and payload keys give one line naming the file, the key and the reason."""

import pytest
from test_cell_errors import BASE, write_cell

from offline_prog.errors import InputError
from offline_prog.plan import plan_cell

GRIPPER = (
    "gripper:\n  mass_kg: 3\n  geometry:\n    - {name: g_body, shape: box, "
    "size_mm: [100, 80, 60], pose: {translation: [0, 0, 0.03]}}\n"
)
CELL = BASE.replace("part:\n", GRIPPER + "part:\n")

CASES = [  # (replace, with, key in message, reason fragment)
    (
        "  mass_kg: 3\n",
        "  mass_kg: 3\n  inertia_kgm2: [1, 1, 3, 0, 0, 0]\n",
        "gripper.inertia_kgm2",
        "each at most the sum",
    ),
    (
        "  mass_kg: 3\n",
        "  mass_kg: 3\n  inertia_kgm2: [1, 1, 1, 0, 0]\n",
        "gripper.inertia_kgm2",
        "expected [Ixx",
    ),
    (
        "  mass_kg: 3\n",
        "  inertia_kgm2: [0.1, 0.1, 0.1, 0, 0, 0]\n",
        "gripper.inertia_kgm2",
        "needs gripper.mass_kg",
    ),
    (
        "  mass_kg: 3\n",
        "  mass_kg: 3\n  inertia_kgm2: [.nan, 1, 1, 0, 0, 0]\n",
        "gripper.inertia_kgm2",
        "NaN",
    ),
    ("  mass_kg: 3\n", "  mass_kg: -3\n", "gripper.mass_kg", "must be within"),
    (
        "  mass_kg: 3\n",
        "  mass_kg: 3\n  center_of_mass_mm: [0, 80]\n",
        "gripper.center_of_mass_mm",
        "expected [x, y, z]",
    ),
    ("  mass_kg: 3\n", "  mass_kg: 3\n  mesh: nothere.stl\n", "gripper.mesh", "does not exist"),
    ("  mass_kg: 3\n", "  mass_kg: 3\n  mesh_units: inch\n", "gripper.mesh_units", "not a unit"),
    ("shape: box, size_mm: [100, 80, 60]", "shape: cone", "gripper.geometry[0].shape", "use box"),
    ("size_mm: [100, 80, 60]", "size_mm: [100, 80]", "gripper.geometry[0].size_mm", "3 positive"),
    ("  mass_kg: 3\n", "  mass_kg: 3\n  grip_force: 3\n", "gripper.grip_force", "unknown key"),
    (
        "name: test",
        "name: test\nobstacles: [{name: g_body, shape: sphere, radius_mm: 5}]",
        "gripper.geometry[0].name",
        "used twice",
    ),
    (
        "part:\n",
        "part:\n  mass_kg: 1\n  inertia_kgm2: [0, 0, 0, 1, 0, 0]\n",
        "part.inertia_kgm2",
        "expected [Ixx",
    ),
]


@pytest.mark.parametrize(("old", "new", "key", "reason"), CASES)
def test_bad_gripper_key_names_file_key_and_reason(tmp_path, old, new, key, reason):
    assert old in CELL
    cell = write_cell(tmp_path, CELL.replace(old, new, 1))
    with pytest.raises(InputError) as info:
        plan_cell(cell)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(cell))
    assert f": {key}:" in message, message
    assert reason in message, message
