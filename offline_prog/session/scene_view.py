"""The session's MeshCat scene: the cell, the planned path coloured by state, the
closest pair, and the robot at any time of the plan.

The cell is drawn once by a MeshcatVisualizer (``/drake/visualizer/<model>/<body>``);
after that the session poses the bodies itself: the robot's links from the plan's
joints, the gripper at X_IE (its frame is the flange's), the part at
X_IP = X_IE · X_PE⁻¹ of the plan shown, the tool at the edited X_IT
(at once: it is what the engineer moved). The processing path hangs under the part's
node in P, one line set per sample state; an outdated plan's path turns grey. The
closest pair of the plan is a red (below the clearance) or amber segment between its
witness points, measured at the pose shown. A calibration (touches loaded) adds the
nominal and the calibrated flange paths side by side in I, blue and orange, with both
tool tips.

Every call must come from the thread that created the Meshcat (Drake's rule).
"""

from __future__ import annotations

import numpy as np
from pydrake.geometry import Meshcat, Rgba, Sphere
from pydrake.math import RigidTransform

from offline_prog.calibration.path_shift import moved_flange
from offline_prog.session.sample_states import sample_states
from offline_prog.viz.preview import camera

STATE_COLORS = (  # ok, slowed by a joint limit, near a singularity, colliding
    (0.1, 0.75, 0.2, 1.0),
    (1.0, 0.65, 0.0, 1.0),
    (0.7, 0.2, 0.9, 1.0),
    (0.95, 0.1, 0.1, 1.0),
)
OUTDATED_COLOR = (0.55, 0.55, 0.55, 1.0)
PAIR_COLORS = {"below": (0.95, 0.1, 0.1, 1.0), "above": (1.0, 0.75, 0.0, 1.0)}
MAX_PATH_SEGMENTS = 1500
LINE_WIDTH = 4.0
WITNESS_RADIUS_M = 0.004
ROOT = "/drake/visualizer"
CALIBRATION = "/session/calibration"
CALIBRATION_COLORS = {"nominal": (0.15, 0.45, 0.95, 1.0), "calibrated": (1.0, 0.5, 0.0, 1.0)}
TIP_RADIUS_M = 0.003


class SceneView:
    """The live scene of one session (see the module docstring)."""

    def __init__(self, meshcat: Meshcat, drake, X_IT: RigidTransform):
        """Draw ``drake`` (a DrakeCell built with ``meshcat``) once and aim the camera."""
        self.meshcat, self.drake = meshcat, drake
        plant = drake.plant
        self.context = plant.CreateDefaultContext()
        model = plant.GetModelInstanceName(drake.robot)
        self.links = {
            f"{ROOT}/{model}/{plant.get_body(b).name()}": plant.get_body(b)
            for b in plant.GetBodyIndices(drake.robot)
        }
        self.part = f"{ROOT}/part/part"
        self.tool = f"{ROOT}/tool/tool"
        # The gripper's body (welded to the flange at identity), when the cell has one.
        self.gripper = f"{ROOT}/gripper/gripper" if plant.HasModelInstanceNamed("gripper") else None
        diagram_context = drake.diagram.CreateDefaultContext()
        drake.diagram.ForcedPublish(diagram_context)
        meshcat.SetCameraPose(*camera(drake.X_IB.translation(), X_IT.translation()))
        self.shown = None  # the SessionPlan drawn
        self._pair = None  # (its scene's context pieces, geometry id pairs, clearance)

    def show_tool(self, X_IT: RigidTransform) -> None:
        self.meshcat.SetTransform(self.tool, X_IT)

    def show(self, result) -> None:
        """Draw a SessionPlan: its path coloured by state (or nothing without a plan)."""
        self.shown = result
        self.meshcat.Delete(f"{self.part}/session")
        self.meshcat.Delete("/session/closest_pair")
        self._pair = None
        plan = result.plan
        if plan is None:
            return
        states = sample_states(plan)
        p_PF = plan.path(plan.trajectory.s, order=0)[0]  # (N, 3) in P [m]
        index = np.unique(np.linspace(0, len(p_PF) - 1, MAX_PATH_SEGMENTS + 1).astype(int))
        # A segment takes the worst state of the samples it covers.
        worst = np.maximum.reduceat(states, index[:-1]) if len(index) > 1 else states[:0]
        start, end = p_PF[index[:-1]], p_PF[index[1:]]
        for k, rgba in enumerate(STATE_COLORS):
            mask = worst == k
            if mask.any():
                self.meshcat.SetLineSegments(
                    f"{self.part}/session/path/{k}",
                    start[mask].T,
                    end[mask].T,
                    LINE_WIDTH,
                    Rgba(*rgba),
                )
        self.meshcat.SetLine(
            f"{self.part}/session/outdated", p_PF[index].T, LINE_WIDTH, Rgba(*OUTDATED_COLOR)
        )
        self.set_outdated(False)
        self._pair = _pair_query(result.scene, plan.collisions)

    def show_calibration(self, calibration) -> None:
        """The nominal flange path of the plan shown and the one the calibrated cell
        asks for, side by side, and both tool tips (a calibration.run.Calibration)."""
        self.meshcat.Delete(CALIBRATION)
        tips = {"calibrated": calibration.X_IT.translation()}
        plan = None if self.shown is None else self.shown.plan
        if plan is not None:
            flange = plan.trajectory.flange
            index = np.unique(np.linspace(0, len(flange.p_IE) - 1, MAX_PATH_SEGMENTS).astype(int))
            p_IE, R_IE = flange.p_IE[index], flange.R_IE[index]
            paths = {
                "nominal": p_IE,
                "calibrated": moved_flange(
                    p_IE,
                    R_IE,
                    X_IT=plan.flange.X_IT,
                    X_PE=plan.flange.X_PE,
                    X_IT_new=calibration.X_IT,
                    X_PE_new=calibration.X_PE,
                ),
            }
            for name, p in paths.items():
                rgba = Rgba(*CALIBRATION_COLORS[name])
                self.meshcat.SetLine(f"{CALIBRATION}/{name}/path", p.T, LINE_WIDTH, rgba)
            tips["nominal"] = plan.flange.X_IT.translation()
        for name, p in tips.items():
            path = f"{CALIBRATION}/{name}/tip"
            self.meshcat.SetObject(path, Sphere(TIP_RADIUS_M), Rgba(*CALIBRATION_COLORS[name]))
            self.meshcat.SetTransform(path, RigidTransform(p))

    def set_outdated(self, outdated: bool) -> None:
        """Grey path for a plan that no longer matches the controls."""
        if self.shown is None or self.shown.plan is None:
            return
        self.meshcat.SetProperty(f"{self.part}/session/path", "visible", not outdated)
        self.meshcat.SetProperty(f"{self.part}/session/outdated", "visible", outdated)

    def pose(self, t: float) -> float:
        """Pose the robot and part at time t [s] of the plan shown; returns σ there [m]."""
        if self.shown is None or self.shown.plan is None:
            return 0.0
        plan = self.shown.plan
        traj = plan.trajectory
        q = np.array([np.interp(t, traj.t, plan.joints.q[:, j]) for j in range(6)])
        plant = self.drake.plant
        plant.SetPositions(self.context, self.drake.robot, q)
        for path, body in self.links.items():
            self.meshcat.SetTransform(path, plant.EvalBodyPoseInWorld(self.context, body))
        X_IE = self.drake.frame_E.CalcPoseInWorld(self.context)
        self.meshcat.SetTransform(self.part, X_IE @ plan.flange.X_PE.inverse())
        if self.gripper is not None:
            self.meshcat.SetTransform(self.gripper, X_IE)
        if self._pair is not None:
            self._show_pair(q)
        return float(np.interp(t, traj.t, traj.s))

    def _show_pair(self, q: np.ndarray) -> None:
        scene, context, plant_context, port, ids, clearance = self._pair
        scene.plant.SetPositions(plant_context, scene.robot, q)
        query = port.Eval(context)
        best = None
        for a, b in ids:
            try:
                r = query.ComputeSignedDistancePairClosestPoints(a, b)
            except RuntimeError:  # a filtered pair (allowed contact)
                continue
            if best is None or r.distance < best.distance:
                best = r
        if best is None:
            return
        p_A = query.GetPoseInWorld(best.id_A) @ best.p_ACa
        p_B = query.GetPoseInWorld(best.id_B) @ best.p_BCb
        rgba = Rgba(*PAIR_COLORS["below" if best.distance < clearance else "above"])
        self.meshcat.SetLine("/session/closest_pair/line", np.column_stack([p_A, p_B]), 6.0, rgba)
        for name, p in (("a", p_A), ("b", p_B)):
            self.meshcat.SetObject(f"/session/closest_pair/{name}", Sphere(WITNESS_RADIUS_M), rgba)
            self.meshcat.SetTransform(f"/session/closest_pair/{name}", RigidTransform(p))


def _pair_query(scene, collisions):
    """What measuring the plan's closest pair at any q needs, or None."""
    closest = collisions.closest
    if scene is None or closest is None:
        return None
    names = {closest.a: [], closest.b: []}
    for g, label in scene.labels.items():
        if label.name in names:
            names[label.name].append(g)
    ids = [(a, b) for a in names[closest.a] for b in names[closest.b]]
    context = scene.diagram.CreateDefaultContext()
    plant_context = scene.plant.GetMyMutableContextFromRoot(context)
    scene_graph = scene.diagram.scene_graph()
    sg_context = scene_graph.GetMyContextFromRoot(context)
    port = scene_graph.get_query_output_port()
    return scene, sg_context, plant_context, port, ids, collisions.clearance_m
