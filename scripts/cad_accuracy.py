"""Print how closely CAD seams follow the analytic edge (issue 26's acceptance figures).

Builds the test parts of tests/cad (scripts/support/cad_parts.py: filleted plate,
L-bracket, chamfered cylinder) with Open CASCADE, writes STEP and STL (0.01 mm chords),
plans each seam's fit as ``plan`` does and prints the path error against the analytic
edge [mm], the normal error [deg], the arc-length error [%], the fit's reported error
against the exact edge and, for a mesh, the chord error it reports. Run:
``python scripts/cad_accuracy.py [--parts plate bracket cylinder] [--stl-chord-mm 0.01]``.
"""

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(Path(__file__).resolve().parent / "support")]

from cad_parts import (  # noqa: E402
    CYLINDER,
    PLATE,
    PLATE_R,
    angle_deg,
    bracket_profile,
    cad_cell,
    chamfered_cylinder,
    filleted_plate,
    l_bracket,
    rounded_rectangle,
    sampled,
    write_step,
    write_stl,
)

from offline_prog.job.seams import seam_inputs  # noqa: E402
from offline_prog.robot.model import ROBOTS_DIR  # noqa: E402
from offline_prog.stages import fit_path, load_inputs  # noqa: E402


def cylinder_truth(p, chamfer_normal):
    radius, height, chamfer = CYLINDER
    d = np.hypot(np.linalg.norm(p[:, :2], axis=1) - (radius - chamfer), p[:, 2] - height)
    radial = p[:, :2] / np.linalg.norm(p[:, :2], axis=1, keepdims=True)
    if chamfer_normal:
        return d, np.column_stack([radial, np.ones(len(p))]) / np.sqrt(2.0)
    return d, np.tile([0.0, 0.0, 1.0], (len(p), 1))


CASES = [
    (
        "plate top loop",
        "plate",
        {"loop": {"face_near_mm": [150, 100, 10]}},
        lambda p: (rounded_rectangle(p, PLATE[2])[0], np.tile([0, 0, 1.0], (len(p), 1))),
        2 * (PLATE[0] + PLATE[1] - 4 * PLATE_R) + 2 * np.pi * PLATE_R,
    ),
    (
        "plate bottom chain, side normal",
        "plate",
        {
            "chain": {"near_mm": [[100, 0, 0], [300, 100, 0]]},
            "normal": {"face_near_mm": [150, 0, 5]},
        },
        lambda p: rounded_rectangle(p, 0.0),
        PLATE[0] + PLATE[1] - 4 * PLATE_R + np.pi * PLATE_R / 2,
    ),
    (
        "bracket chain across the fillet",
        "bracket",
        {
            "chain": {"near_mm": [[60, 0, 10], [10, 0, 60]]},
            "normal": {"face_near_mm": [12.9289, 30, 12.9289]},
        },
        bracket_profile,
        160 + 5 * np.pi,
    ),
    (
        "cylinder rim, chamfer normal",
        "cylinder",
        {"loop": {"face_near_mm": [0, 10, 40]}, "normal": {"face_near_mm": [33.09, 34.07, 37.5]}},
        lambda p: cylinder_truth(p, True),
        2 * np.pi * 45,
    ),
]


PARTS = {"plate": filleted_plate, "bracket": l_bracket, "cylinder": chamfered_cylinder}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--parts", nargs="+", choices=list(PARTS), default=list(PARTS), help="(all three)"
    )
    parser.add_argument(
        "--stl-chord-mm", type=float, default=0.01, help="the STL's chord tolerance (0.01)"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="cad_accuracy_") as folder:
        accuracy(Path(folder), args.parts, args.stl_chord_mm)


def accuracy(folder: Path, parts: list[str], chord_mm: float) -> None:
    """Write the ``parts`` (STEP and STL within ``chord_mm``) into ``folder``; print each
    case's figures."""
    stdout = os.dup(1)
    os.dup2(os.open(os.devnull, os.O_WRONLY), 1)  # the STEP writer's banner (C++ stdout)
    for name in parts:
        shape = PARTS[name]()
        write_step(shape, folder / f"{name}.step")
        write_stl(shape, folder / f"{name}.stl", chord_mm)
    sys.stdout.flush()
    os.dup2(stdout, 1)
    print(
        f"{'seam':34} {'model':5} {'path mm':>9} {'normal °':>9} {'length %':>9} "
        f"{'fit→edge mm':>11} {'chord mm':>9}"
    )
    for label, part, cad, truth, length in CASES:
        if part not in parts:
            continue
        for kind, tolerance in (("step", 0.005), ("stl", 0.02)):
            if kind == "stl" and "bottom chain" in label:
                continue  # a mesh run is the whole outline: no edge ends at the fillets
            seam = {
                "cad": cad,
                "fit_tolerance_mm": tolerance,
                "normal_tolerance_deg": 0.05 if kind == "step" else 2.0,
            }
            file = cad_cell(folder, f"{part}.{kind}", [seam], mesh_units="mm")
            inputs = seam_inputs(load_inputs(file, ROBOTS_DIR), 0)
            fit = fit_path(inputs)
            p, n = sampled(fit)
            distance, outward = truth(p)
            print(
                f"{label:34} {kind:5} {distance.max():9.5f} {angle_deg(n, -outward).max():9.4f}"
                f" {abs(fit.path.length * 1e3 - length) / length * 100:9.5f}"
                f" {fit.normal_fit.edge_max_error_mm:11.5f}"
                f" {inputs.points.exact.tolerance_m * 1e3:9.5f}"
            )


if __name__ == "__main__":
    main()
