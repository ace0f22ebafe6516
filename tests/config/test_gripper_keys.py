"""Bad gripper and payload keys give one line naming the file, the key and the reason."""

import pytest
from test_cell_errors import test_bad_cell_names_file_key_and_reason as refused

GRIPPER = (
    "gripper:\n  mass_kg: 3\n  geometry:\n    - {name: g_body, shape: box, "
    "size_mm: [100, 80, 60], pose: {translation: [0, 0, 0.03]}}\npart:\n"
)
MASS = "  mass_kg: 3\n"

CASES = [  # (replace in GRIPPER, with, key in message, reason fragment)
    (
        MASS,
        MASS + "  inertia_kgm2: [1, 1, 3, 0, 0, 0]\n",
        "gripper.inertia_kgm2",
        "at most the sum",
    ),
    (MASS, MASS + "  inertia_kgm2: [1, 1, 1, 0, 0]\n", "gripper.inertia_kgm2", "expected [Ixx"),
    (
        MASS,
        "  inertia_kgm2: [0.1, 0.1, 0.1, 0, 0, 0]\n",
        "gripper.inertia_kgm2",
        "needs gripper.mass",
    ),
    (MASS, MASS + "  inertia_kgm2: [.nan, 1, 1, 0, 0, 0]\n", "gripper.inertia_kgm2", "NaN"),
    (MASS, "  mass_kg: -3\n", "gripper.mass_kg", "must be within"),
    (MASS, MASS + "  center_of_mass_mm: [0, 80]\n", "gripper.center_of_mass_mm", "expected [x, y"),
    (MASS, MASS + "  mesh: nothere.stl\n", "gripper.mesh", "does not exist"),
    (MASS, MASS + "  mesh_units: inch\n", "gripper.mesh_units", "not a unit"),
    (MASS, MASS + "  grip_force: 3\n", "gripper.grip_force", "unknown key"),
    ("shape: box, size_mm: [100, 80, 60]", "shape: cone", "gripper.geometry[0].shape", "use box"),
    ("size_mm: [100, 80, 60]", "size_mm: [100, 80]", "gripper.geometry[0].size_mm", "3 positive"),
    (
        "part:\n",
        "obstacles: [{name: g_body, shape: sphere, radius_mm: 5}]\npart:\n",
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
    assert old in GRIPPER
    refused(tmp_path, "part:\n", GRIPPER.replace(old, new, 1), key, reason)
