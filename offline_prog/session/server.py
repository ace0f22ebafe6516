"""The session loop: the panel's requests, the planner thread and the MeshCat scene.

Three kinds of thread, each with its own job:

- the panel's HTTP threads only read a snapshot and post requests (under ``lock``);
- one planner thread runs the cached pipeline, Save and Export, newest request first;
- the main thread owns the MeshCat (Drake's rule): it hands requests to the planner,
  draws the answers and animates the robot.

Every change of the parameters gets a new generation number. A plan is drawn and
reported as current only if its generation is still the newest; an older one that
finishes late is dropped, and a plan still running when a newer request arrives stops
at its next stage. While the shown plan is older than the controls, the status says so
and the path is grey.
"""

from __future__ import annotations

import dataclasses
import logging
import queue
import threading
import time
from pathlib import Path

from offline_prog.config import cell_text
from offline_prog.config.cell import transform
from offline_prog.errors import InputError
from offline_prog.scene.drake_cell import build_cell_model
from offline_prog.session import calibration, outputs, request
from offline_prog.session.replan import Replanner, SupersededError
from offline_prog.session.scene_view import SceneView
from offline_prog.session.state import controls, values, with_value
from offline_prog.session.status import plan_status

log = logging.getLogger(__name__)

SETTLE_S = 0.3  # a control untouched this long has settled: re-plan
FRAME_S = 1.0 / 30.0  # main-loop period (animation frames)
ACTIONS = ("plan", "save", "export", "play", "pause", "seek", "auto", "calibrated")


class Session:
    """One cell file in the browser (see the module docstring)."""

    def __init__(self, cell_file: Path, meshcat, *, out_root: Path = Path("out")):
        self.replanner = Replanner(cell_file)
        self.file, self.out_root = Path(cell_file), Path(out_root)
        self.state = self.replanner.initial
        self.lock = threading.Lock()
        self.generation, self.changed_at, self.plan_now = 1, 0.0, True
        self.auto = True
        self.running = None  # (generation, stage) being planned
        self.shown_generation = self.requested_generation = 0
        self.message = ("info", "")
        self.saved: dict = {}  # state → saved file
        self.last_saved = self.last_exported = None
        self.playing, self.t, self.sigma = False, 0.0, 0.0
        self.last_step = time.monotonic()
        self.seek: float | None = None  # σ [m] asked for by the panel
        self.plan_line = {"kind": "planning", "line": "planning…"}
        self.last_calibration: calibration.SessionCalibration | None = None  # the last solved
        self.requests: queue.Queue = queue.Queue()
        self.answers: queue.Queue = queue.Queue()
        cell = self.replanner.base.cell
        drake = build_cell_model(cell, self.file, self.replanner.base.robot, meshcat=meshcat)
        self.view = SceneView(meshcat, drake, transform(cell.tool.X_IT))
        self.worker = threading.Thread(target=self._work, name="session-planner", daemon=True)
        self.worker.start()

    # --- the panel's side (HTTP threads) --------------------------------------------

    def snapshot(self) -> dict:
        """Everything the panel shows, as JSON-ready values."""
        with self.lock:
            shown = self.view.shown
            duration = length = 0.0
            if shown is not None and shown.plan is not None:
                duration = float(shown.plan.trajectory.t[-1])
                length = float(shown.plan.trajectory.s[-1])
            current = self.shown_generation == self.generation
            return {
                "cell": str(self.file),
                "generation": self.generation,
                "shown_generation": self.shown_generation,
                "current": current,
                "busy": None if self.running is None else self.running[1],
                "status": self.plan_line
                if current
                else {
                    "kind": "planning",
                    "line": "re-planning… (the plan shown is for earlier values)"
                    if self.shown_generation
                    else "planning…",
                },
                "shown": self.plan_line,
                "message": {"kind": self.message[0], "text": self.message[1]},
                "values": values(self.state),
                "controls": [
                    dataclasses.asdict(c)
                    for c in controls(self.replanner.initial, self.replanner.seam_names)
                ],
                "seams": self.replanner.seam_names,
                "auto": self.auto,
                "playing": self.playing,
                "t": self.t,
                "sigma": self.sigma,
                "duration": duration,
                "length": length,
                "saved": None if self.last_saved is None else str(self.last_saved),
                "exported": None if self.last_exported is None else str(self.last_exported),
                "calibration": self._calibration(),
            }

    def _calibration(self) -> dict | None:
        """The last touches file solved: its name, summary lines, and whether the
        controls hold its frames (call with the lock held)."""
        found = self.last_calibration
        if found is None:
            return None
        applied = calibration.calibrated(self.state, found) == self.state
        return {"file": found.file, "lines": found.lines, "applied": applied}

    def set_value(self, key: str, text) -> dict:
        """A typed or slid value (text or a number, in the control's unit): the new
        state, or ``ok: False`` with a one-line message (state kept)."""
        with self.lock:
            try:
                key = request.name(key, "key")
                state = with_value(self.state, key, request.typed(text, key))
            except ValueError as error:
                self.message = ("refused", f"refused {key} = {str(text)[:40]!r}: {error}")
                return {"ok": False, "message": self.message[1]}
            if state != self.state:
                self.state, self.changed_at = state, time.monotonic()
                self.generation += 1
                self.message = ("info", f"{key} = {values(state)[key]:g}")
            return {"ok": True}

    def load_touches(self, file, text, controller_angles=False) -> dict:
        """A touches file's text from the panel: checked now (``ok: False`` with a
        one-line message, nothing changed), solved on the planner thread against the
        cell as the controls set it, then drawn beside the plan."""
        with self.lock:
            try:
                found = calibration.read(self.replanner, self.state, file, text, controller_angles)
            except (request.RequestError, InputError) as error:
                self.message = ("refused", f"touches refused: {error}")
                return {"ok": False, "message": self.message[1]}
            self.requests.put(("calibrate", self.generation, found))
            self.message = ("info", f"calibrating from {found[1].file}…")
            return {"ok": True}

    def action(self, name: str, value=None) -> dict:
        """Buttons: plan, save, export, play, pause (no value); seek (σ [mm], a finite
        number), auto (true or false). A bad name or value: ``ok: False`` with a
        one-line message, nothing changed."""
        with self.lock:
            try:
                self._act(request.name(name, "action"), value)
            except request.RequestError as error:
                self.message = ("refused", f"refused: {error}")
                return {"ok": False, "message": str(error)}
            return {"ok": True}

    def _act(self, name: str, value) -> None:
        if name not in ACTIONS:
            raise request.RequestError(f"no action {name[:40]!r} ({', '.join(ACTIONS)})")
        if name not in ("seek", "auto") and value is not None:
            raise request.RequestError(f"{name} takes no value (got {str(value)[:40]!r})")
        if name == "seek":
            self.seek = request.finite(value, "σ") * 1e-3  # checked first: NaN aborts Drake
            self.playing = False
        elif name == "auto":
            self.auto = request.boolean(value, "auto")
        elif name == "plan":
            self.generation += 1
            self.plan_now = True
        elif name in ("save", "export"):
            self.requests.put((name, self.generation, self.state))
            self.message = ("info", f"{name}…")
        elif name == "calibrated":  # the controls to the calibrated X_IT and X_PE
            if self.last_calibration is None:
                raise request.RequestError("no calibration yet: load a touches file")
            state = calibration.calibrated(self.state, self.last_calibration)
            if state != self.state:
                self.state, self.changed_at = state, time.monotonic()
                self.generation += 1
            self.message = ("info", f"X_IT and X_PE from {self.last_calibration.file}")
        else:
            self.playing = name == "play"

    # --- the planner thread ------------------------------------------------------------

    def _work(self) -> None:
        while True:
            kind, generation, state = self.requests.get()
            if kind == "plan":  # only the newest plan request matters
                kind, generation, state = self._newest(kind, generation, state)
            try:
                self.answers.put((kind, generation, self._do(kind, generation, state)))
            except SupersededError:
                continue
            except Exception as error:  # the session never dies of one request
                log.exception("session request %s failed", kind)
                self.answers.put((kind, generation, error))
            finally:
                with self.lock:
                    self.running = None

    def _newest(self, kind, generation, state):
        try:
            while True:
                nxt = self.requests.get_nowait()
                if nxt[0] != "plan":
                    self.requests.put(nxt)  # keep Save/Export for after this plan
                    return kind, generation, state
                kind, generation, state = nxt
        except queue.Empty:
            return kind, generation, state

    def _progress(self, generation: int, *, supersede: bool):
        def progress(stage: str) -> None:
            with self.lock:
                if supersede and generation < self.generation:
                    raise SupersededError  # its answer would be dropped: stop here
                self.running = (generation, stage)

        return progress

    def _do(self, kind: str, generation: int, state):
        progress = self._progress(generation, supersede=kind == "plan")
        if kind == "plan":
            return self.replanner.plan(state, progress)
        if kind == "calibrate":  # state: the checked (inputs, touches)
            progress("calibrating")
            return calibration.solve(*state)
        saved = self.saved.get(state)
        if saved is None or not saved.exists():
            planner = self.replanner
            saved = cell_text.save_cell(planner.file, planner.initial, state, planner.cell(state))
            self.saved[state] = saved
        if kind == "save":
            return saved
        out = self.out_root / saved.stem
        return saved, *outputs.export(saved, out, progress)

    # --- the main thread: MeshCat -------------------------------------------------------

    def step(self) -> None:
        """One main-loop round: hand out a due plan, draw answers, animate."""
        now = time.monotonic()
        with self.lock:
            due = self.generation != self.shown_generation and (
                self.plan_now or (self.auto and now - self.changed_at > SETTLE_S)
            )
            if due and self.requested_generation != self.generation:
                self.requests.put(("plan", self.generation, self.state))
                self.requested_generation, self.plan_now = self.generation, False
            X_IT = transform(self.replanner.cell(self.state).tool.X_IT)
            outdated = self.generation != self.shown_generation
            seek, self.seek = self.seek, None
        elapsed, self.last_step = now - self.last_step, now
        try:
            self.view.show_tool(X_IT)
            while True:
                try:
                    kind, generation, answer = self.answers.get_nowait()
                except queue.Empty:
                    break
                self._answer(kind, generation, answer)
            if self.view.shown is not None and self.view.shown.plan is not None:
                traj = self.view.shown.plan.trajectory
                if seek is not None:
                    self.t = float(_time_at(traj, seek))
                elif self.playing:  # real time, looping
                    self.t = (self.t + min(elapsed, 0.2)) % max(traj.t[-1], FRAME_S)
                self.sigma = self.view.pose(min(self.t, traj.t[-1]))
            self.view.set_outdated(outdated)
        except Exception as error:  # a drawing error costs the picture, not the session
            log.exception("session scene update failed")
            with self.lock:
                self.message = ("refused", f"scene update failed: {error}")

    def _answer(self, kind: str, generation: int, answer) -> None:
        if isinstance(answer, Exception):
            text = f"{kind} failed: {answer}"
            if isinstance(answer, InputError | OSError):
                text = f"{kind} refused: {answer}"
            with self.lock:
                self.message = ("refused", text)
            return
        if kind == "save":
            with self.lock:
                self.last_saved = answer
                self.message = ("info", f"saved {answer}")
            return
        if kind == "export":
            saved, folder, line = answer
            with self.lock:
                self.last_saved, self.last_exported = saved, folder
                self.message = ("info", line)
            return
        if kind == "calibrate":
            self.view.show_calibration(answer.calibration)
            with self.lock:
                self.last_calibration = answer
                self.message = ("info", f"calibrated from {answer.file}: " + answer.lines[-1])
            return
        with self.lock:
            if generation != self.generation:
                return  # stale: the controls moved on while it was planned
        self.view.show(answer)
        planner = self.replanner
        line = plan_status(
            answer, planner.seam_names[answer.state.seam] if len(planner.seam_names) > 1 else ""
        )
        with self.lock:
            self.shown_generation, self.plan_line = generation, line
        plan = answer.plan
        if plan is not None and not plan.feasible and plan.collisions.closest is not None:
            self.t, self.playing = plan.collisions.closest.t_s, False  # show the worst pose
        elif plan is not None:
            self.t = min(self.t, float(plan.trajectory.t[-1]))


def _time_at(traj, sigma: float) -> float:
    import numpy as np

    return float(np.interp(sigma, traj.s, traj.t))
