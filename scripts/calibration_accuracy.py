"""How well calibrate recovers a known cell: synthetic touches (0.02 mm noise) of the
demo cells, many seeded draws per robot, the worst error of each frame against the
acceptance tolerances of issue 38, and the mean square of error / reported σ (1 when
the standard deviations are right; a t-distribution's ~1.05-1.15 with these few
touches).

    python scripts/calibration_accuracy.py [--draws 50] [--fanuc]

``--fanuc`` also imports the FANUC M-20iA from ../shared (about 15 s).
"""

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "tests"), str(REPO / "tests" / "calibration")]

from synthetic_touches import (  # noqa: E402
    calibration_cell,
    import_fanuc,
    nominal_truth,
    start_pose,
    synthetic_touches,
)
from test_estimate import errors, solve  # noqa: E402

TOLERANCES = {"tip_mm": 0.1, "axis_deg": 0.1, "pointer_mm": 0.1, "grasp_mm": 0.1, "grasp_deg": 0.05}
DEMOS = ["seal_plate_kr16", "weld_seam_irb2400", "tape_cylinder_ur10e"]


def measure(inputs, X_IE0, draws: int) -> tuple[dict, float]:
    worst, z2 = dict.fromkeys(TOLERANCES, 0.0), []
    rng = np.random.default_rng(0)
    for _ in range(draws):
        true = nominal_truth(inputs, rng)
        estimate = solve(inputs, synthetic_touches(inputs, X_IE0, true, rng).text)
        for key, value in errors(estimate, true).items():
            worst[key] = max(worst[key], value)
        v = estimate.values
        z2 += list(((v.p_IT - true.X_IT[:3, 3] * 1e3) / estimate.sigma("p_IT")) ** 2)
        z2 += list(((v.p_PE - true.X_PE[:3, 3] * 1e3) / estimate.sigma("grasp_translation")) ** 2)
        turn = Rotation.from_matrix(v.R_PE.T @ true.X_PE[:3, :3]).as_rotvec()
        z2 += list((turn / estimate.sigma("grasp_rotation")) ** 2)
    return worst, float(np.mean(z2))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=50)
    parser.add_argument("--fanuc", action="store_true")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="calibration-accuracy-"))
    cells = {name: calibration_cell(folder, name) for name in DEMOS}
    if args.fanuc:
        import_fanuc(folder / "robots")
        (folder / "fanuc").mkdir()
        cells["seal_plate_fanuc_m20ia"] = calibration_cell(
            folder / "fanuc", "seal_plate_kr16", model="fanuc_m20ia", robots_dir="../robots"
        )
    print(f"worst error over {args.draws} draws (tolerance), mean (error/σ)²:")
    for name, cell in cells.items():
        inputs, X_IE0 = start_pose(cell)
        worst, z2 = measure(inputs, X_IE0, args.draws)
        shown = ", ".join(
            f"{key} {value:.3f} ({TOLERANCES[key]:g})" for key, value in worst.items()
        )
        print(f"  {name:<24} {inputs.robot.name:<12} {shown}; (e/σ)² {z2:.2f}")


if __name__ == "__main__":
    main()
