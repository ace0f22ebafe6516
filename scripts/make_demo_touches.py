"""Regenerate the demo touches file cells/calibration/seal_plate_kr16_touches.csv
(committed; run only to change it).

The touches a technician would take on the seal demo's cell as it "really" is: the
nozzle 1.5 mm and 0.3° from where cells/seal_plate_kr16.yaml puts it, the plate held
1.5 mm and 0.3° off its nominal grasp, the pointer's tip 0.8 mm from ``pointer_mm``;
8 tool_tip and 4 tool_axis touches with the flange tilted 15-30°, each part point
touched three times, 0.02 mm touch noise (scripts/support/synthetic_touches.py).
``offline-prog calibrate cells/seal_plate_kr16.yaml --touches ...`` recovers them.

    python scripts/make_demo_touches.py [--out cells/calibration]
"""

import argparse
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(Path(__file__).resolve().parent / "support")]

from synthetic_touches import TrueCell, perturbed, start_pose, synthetic_touches  # noqa: E402

OUT = REPO / "cells" / "calibration"
NAME = "seal_plate_kr16_touches.csv"
SEED = 38  # the seed the committed file was drawn with


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=OUT, help="folder to write %(default)s into")
    out = parser.parse_args().out / NAME
    inputs, X_IE0 = start_pose(REPO / "cells" / "seal_plate_kr16.yaml")
    rng = np.random.default_rng(SEED)
    true = TrueCell(
        perturbed(inputs.X_IT.GetAsMatrix4(), rng, mm=1.5, deg=0.3),
        perturbed(inputs.X_PE.GetAsMatrix4(), rng, mm=1.5, deg=0.3),
        np.array([0.5, -0.4, 250.5]),
    )
    touched = synthetic_touches(inputs, X_IE0, true, rng)
    header = (
        "# Demo touches of cells/seal_plate_kr16.yaml (scripts/make_demo_touches.py): the\n"
        "# robot's joints [deg, trajectory.csv's convention] with the pointer's tip on the\n"
        "# nozzle's tip (tool_tip), on its axis mark (tool_axis), and the plate's points on\n"
        "# the nozzle's tip.\n"
    )
    lines = touched.text.splitlines()
    # Four decimals, as a pendant shows them (0.0001° is < 2 µm at this reach).
    rows = [lines[0]] + [
        ",".join([row.split(",")[0]] + [f"{float(v):.4f}" for v in row.split(",")[1:]])
        for row in lines[1:]
    ]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(header + "\n".join(rows) + "\n", encoding="utf-8")
    p_IT, p_PE = true.X_IT[:3, 3] * 1e3, true.X_PE[:3, 3] * 1e3
    print(f"wrote {out}: true p_IT {np.round(p_IT, 3)} mm, p_PE {np.round(p_PE, 3)} mm")


if __name__ == "__main__":
    main()
