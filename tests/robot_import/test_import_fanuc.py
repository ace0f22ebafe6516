"""`robots import` with the ROS-Industrial FANUC support packages in ../shared: the
derived OPW parameters equal the published ones, the folder loads and plans the seal
demo, and the FANUC program it exports reconstructs the planned flange poses."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from fanuc_reader import joints_from_config, pose, read_ls

from offline_prog.errors import InputError
from offline_prog.robot.model import load_robot
from offline_prog.robot_import.run import import_robot

REPO = Path(__file__).resolve().parents[2]
SHARED = next(
    (p for p in (REPO.parent / "shared", Path("/work/shared")) if (p / "robots").is_dir()), None
)
FANUC = SHARED / "robots" / "ros-industrial-fanuc" if SHARED else None
pytestmark = pytest.mark.skipif(
    FANUC is None or not FANUC.is_dir(),
    reason="../shared/robots/ros-industrial-fanuc (ROS-I FANUC support packages) is absent",
)
MODELS = {"m10ia": "fanuc_m10ia_support", "m20ia": "fanuc_m20ia_support"}
POSITION_TOL_M, ANGLE_TOL_DEG = 1e-6, 1e-4


def _published(model: str) -> dict:
    text = (FANUC / MODELS[model] / "config" / f"opw_parameters_{model}.yaml").read_text()
    text = text.replace("deg(-90.0)", "-90.0").replace("deg(180.0)", "180.0")
    return yaml.safe_load(text)


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    out = tmp_path_factory.mktemp("robots")
    results = {
        model: import_robot(
            FANUC / MODELS[model] / "urdf" / f"{model}.xacro",
            name=f"fanuc_{model}",
            out=out,
            package_paths=[FANUC],
            vendor="fanuc",
            samples=500,
        )
        for model in MODELS
    }
    return out, results


@pytest.mark.parametrize("model", sorted(MODELS))
def test_opw_parameters_equal_the_published_ones(robots, model):
    _, results = robots
    params, published = results[model].params, _published(model)
    for key, value in published["opw_kinematics_geometric_parameters"].items():
        assert getattr(params, key) == pytest.approx(value, abs=1e-12), key
    assert np.allclose(np.degrees(params.offsets), published["opw_kinematics_joint_offsets"])
    assert list(params.sign_corrections) == published["opw_kinematics_joint_sign_corrections"]
    assert results[model].fk.samples >= 1000 and results[model].fk.max_position_m <= 1e-9


@pytest.mark.parametrize("model", sorted(MODELS))
def test_folder_has_the_bundled_layout(robots, model):
    out, results = robots
    folder = out / f"fanuc_{model}"
    for name in (
        "robot.yaml",
        "README.md",
        "self_collision.yaml",
        f"fanuc_{model}.urdf",
        "meshes/SOURCES.md",
        "meshes/LICENSE",
        "meshes/visual/link_4.obj",
        "meshes/collision/link_4.obj",
    ):
        assert (folder / name).is_file(), name
    robot = load_robot(f"fanuc_{model}", out)
    assert robot.family == "opw" and robot.language == "fanuc" and robot.j23_factor == -1
    assert {p.kind for p in results[model].pairs} >= {"adjacent", "check"}
    record = (folder / "robot.yaml").read_text()
    assert "velocity_deg_s: from the URDF" in record and "ASSUMED" in record


def test_fanuc_j3_counts_from_the_horizontal(robots):
    """With the controller's J3 = 0 the forearm (axis 3 -> wrist centre, minus the a2
    offset) is horizontal for any J2: FANUC's J2/J3 linkage convention."""
    out, _ = robots
    robot = load_robot("fanuc_m20ia", out)
    rng = np.random.default_rng(0)
    for j2 in rng.uniform(-1.0, 1.0, size=20):
        q = robot.urdf_joints(np.array([[0.0, j2, 0.0, 0.0, 0.3, 0.0]]))
        q2 = q.copy()
        q2[0, 4] = -0.3
        # The flange z direction at J4 = J6 = 0 turns with the forearm only.
        z = robot.forward(q)[0, :3, 2] + robot.forward(q2)[0, :3, 2]
        assert abs(z[2]) < 1e-12


@pytest.mark.slow  # plans a whole cell (CI runs the slow tests too)
def test_readme_walkthrough_plans_the_seal_demo_and_exports_fanuc(robots, tmp_path):
    """The README's steps with the shared M-20iA: import on the command line, a cell
    using robots_dir, plan, and a FANUC program that moves the robot as planned."""
    out = tmp_path / "robots"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "robots",
            "import",
            str(FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro"),
            "--name",
            "fanuc_m20ia",
            "--vendor",
            "fanuc",
            "--package-path",
            str(FANUC),
            "--out",
            str(out),
            "--samples",
            "500",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    cell = (REPO / "cells" / "seal_plate_kr16.yaml").read_text()
    assert "model: kuka_kr16_2\n" in cell
    cell = cell.replace("model: kuka_kr16_2\n", "model: fanuc_m20ia\n  robots_dir: robots\n")
    (tmp_path / "seal_m20ia.yaml").write_text(cell)
    plan_dir = tmp_path / "plan"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "plan",
            str(tmp_path / "seal_m20ia.yaml"),
            "--out",
            str(plan_dir),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ},
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "collision-free" in run.stdout
    program = plan_dir / "programs" / "OFFLINE_PROG.ls"
    _check_program(program, plan_dir, load_robot("fanuc_m20ia", out))
    # A line limit splits the moves into called sub-programs that run the same points.
    whole = _program_points(program.parent, program.stem)
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "export",
            str(plan_dir),
            "--format",
            "fanuc",
            "--line-limit",
            "100",
            "--out",
            str(tmp_path / "split"),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    split = sorted((tmp_path / "split").glob("*.ls"))
    assert len(split) > len(list(program.parent.glob("*.ls")))
    assert all(len(read_ls(file)["mn"]) <= 100 for file in split)
    points = _program_points(tmp_path / "split", "OFFLINE_PROG")
    assert [p.get("xyzwpr", p.get("joints")) for p in points] == [
        p.get("xyzwpr", p.get("joints")) for p in whole
    ]


def _program_points(folder: Path, name: str) -> list[dict]:
    """Every /POS entry the program runs, in execution order, following CALLs."""
    ls, points = read_ls(folder / f"{name}.ls"), []
    for statement in ls["mn"]:
        if statement.startswith("CALL "):
            points += _program_points(folder, statement.split()[1])
        elif m := re.match(r"[JL] P\[(\d+)\]", statement):
            points.append(ls["pos"][int(m.group(1))])
    return points


def _check_program(program: Path, plan_dir: Path, robot):
    """A path: cell is a one-seam job: every position the FANUC program moves to
    (joint-represented links and home, Cartesian approach, seam and retract points) is
    a planned row of trajectory.csv, in order, from home to home: the reconstructed
    Cartesian points' FK within 1 µm and 0.0001° of the row's and their joints within
    0.001°, the joint-represented ones within their written resolution."""
    from offline_prog.export.program import ProgramData

    data = ProgramData.load(plan_dir)  # the job's rows, home to home
    X_PE = np.linalg.inv(data.X_EP)
    X_plan, i = robot.forward(data.q), 0
    points = _program_points(program.parent, program.stem)
    assert len(points) > 10
    for k, entry in enumerate(points):
        if "joints" in entry:  # written to 0.0001°: each axis within half of that
            q = robot.urdf_joints(np.radians(entry["joints"])[None])[0]
            error = np.abs(data.q[i:] - q).max(axis=1)
            i += int(np.argmin(error))
            assert error.min() <= np.radians(0.5e-4) + 1e-12, k
            continue
        # P in the user frame T (UFRAME = X_BT), the written TCP is P (UTOOL = X_EP)
        X = data.X_BT @ pose(entry["xyzwpr"]) @ X_PE
        q = joints_from_config(robot, X, entry["config"], entry["turns"])
        # the planned row this point was written from (points follow the plan in order)
        gap = np.linalg.norm(X_plan[i:, :3, 3] - X[:3, 3], axis=1)
        near = np.flatnonzero(gap <= POSITION_TOL_M)
        i += int(near[0] if len(near) else np.argmin(gap))
        assert np.linalg.norm(X_plan[i, :3, 3] - X[:3, 3]) <= POSITION_TOL_M, k
        R_err = X_plan[i, :3, :3].T @ X[:3, :3]
        angle = np.degrees(np.arccos(np.clip((np.trace(R_err) - 1) / 2, -1, 1)))
        assert angle <= ANGLE_TOL_DEG, k
        assert np.abs(q - data.q[i]).max() < np.radians(1e-3), k
    assert np.abs(robot.forward(data.q[[0]])[0] - X_plan[0]).max() < 1e-12
    assert i == len(data.q) - 1, "the program ends at the plan's last row (home)"


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: t.replace('type="revolute"', 'type="prismatic"', 1), "not six revolute"),
        (lambda t: t.replace('lower="-2.967060"', 'lower="abc"'), "not a number"),
        (lambda t: t.replace("base_link.stl", "missing.stl", 1), "mesh file not found"),
        (lambda t: t.replace("$(find fanuc_resources)", "$(find no_such_pkg)"), "no_such_pkg"),
    ],
)
def test_bad_descriptions_are_one_line_exit_2(tmp_path, edit, message):
    macro = FANUC / "fanuc_m20ia_support/urdf/m20ia_macro.xacro"
    pkg = tmp_path / "pkgs" / "fanuc_m20ia_support"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "package.xml").write_text((FANUC / "fanuc_m20ia_support/package.xml").read_text())
    (pkg / "meshes").symlink_to(FANUC / "fanuc_m20ia_support/meshes")
    (pkg / "urdf" / "m20ia_macro.xacro").write_text(edit(macro.read_text()))
    top = (FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro").read_text()
    (pkg / "urdf" / "m20ia.xacro").write_text(top)
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "robots",
            "import",
            str(pkg / "urdf/m20ia.xacro"),
            "--name",
            "bad",
            "--package-path",
            str(tmp_path / "pkgs"),
            "--package-path",
            str(FANUC),
            "--out",
            str(tmp_path / "out"),
            "--samples",
            "10",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 2, run.stdout + run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and message in run.stderr, run.stderr
    assert not (tmp_path / "out" / "bad").exists()


def test_unknown_package_in_library_call_names_the_file(tmp_path):
    with pytest.raises(InputError, match="fanuc_m20ia_support"):
        import_robot(
            FANUC / "fanuc_m20ia_support/urdf/m20ia.xacro",
            name="x",
            out=tmp_path,
            package_paths=[tmp_path],
        )


def test_preview_draws_the_imported_meshes(robots, tmp_path):
    """The preview's scene holds each link's converted visual mesh, every triangle."""
    import trimesh
    import umsgpack

    from offline_prog.config.cell import load_cell
    from offline_prog.scene.drake_cell import build_cell_model
    from offline_prog.viz.preview import draw_cell
    from offline_prog.viz.static_scene import StaticScene

    out, _ = robots
    text = (REPO / "cells" / "seal_plate_kr16.yaml").read_text()
    text = text.replace("model: kuka_kr16_2\n", f"model: fanuc_m20ia\n  robots_dir: {out}\n")
    (tmp_path / "cell.yaml").write_text(text)
    robot = load_robot("fanuc_m20ia", out)
    drake = build_cell_model(load_cell(tmp_path / "cell.yaml"), tmp_path / "cell.yaml", robot)
    scene = StaticScene()
    draw_cell(scene, drake)
    drawn = {}
    for message in scene.messages:
        command = umsgpack.unpackb(message) if isinstance(message, bytes) else {}
        path = command.get("path", "")
        if command.get("type") == "set_object" and path.startswith("/drake/fanuc_m20ia/"):
            index = command["object"]["geometries"][0]["data"]["index"]["array"].data
            drawn[path.split("/")[3]] = len(index) // 4 // 3
    for link in ("base_link", "link_1", "link_2", "link_3", "link_4", "link_5", "link_6"):
        obj = out / "fanuc_m20ia" / "meshes" / "visual" / f"{link}.obj"
        assert drawn[link] == len(trimesh.load(obj, force="mesh").faces), link


@pytest.mark.slow  # plans a whole cell (CI runs the slow tests too)
def test_m10ia_on_the_search_path_plans_the_seal_demo(robots, tmp_path):
    """The M-10iA found through OFFLINE_PROG_ROBOTS (no robots_dir in the cell) plans the
    seal demo collision-free and exports a FANUC program that reads back as planned;
    `robots list` names the folder it comes from."""
    out, _ = robots
    env = {**os.environ, "OFFLINE_PROG_ROBOTS": str(out)}
    listing = subprocess.run(
        [sys.executable, "-m", "offline_prog", "robots", "list"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    rows = {line.split()[0]: line for line in listing.stdout.splitlines()}
    assert f"OFFLINE_PROG_ROBOTS: {out}" in rows["fanuc_m10ia"] and "bundled" in rows["ur10e"]
    cell = (REPO / "cells" / "seal_plate_kr16.yaml").read_text()
    (tmp_path / "seal_m10ia.yaml").write_text(cell.replace("kuka_kr16_2", "fanuc_m10ia"))
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "offline_prog",
            "plan",
            str(tmp_path / "seal_m10ia.yaml"),
            "--out",
            str(tmp_path / "plan"),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=900,
        env=env,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "collision-free" in run.stdout
    program = tmp_path / "plan" / "programs" / "OFFLINE_PROG.ls"
    _check_program(program, tmp_path / "plan", load_robot("fanuc_m10ia", out))


def test_default_package_path_is_the_folder_holding_the_package(tmp_path):
    """Without --package-path, the packages beside the description's own are found
    (fanuc_resources next to fanuc_m10ia_support)."""
    result = import_robot(
        FANUC / "fanuc_m10ia_support/urdf/m10ia.xacro",
        name="m10ia",
        out=tmp_path,
        vendor="fanuc",
        samples=20,
    )
    assert result.params.c3 == pytest.approx(0.64) and result.fk.ok
