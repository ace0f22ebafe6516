"""Universal Robots URScript: a job as one ``.script``.

Plain URScript has no remote TCP, so the program runs the planned joints; it names no
frame and holds no frame value (no TCP or feature of the installation moves a joint
target: the header says to re-plan after a calibration). Links:
``movej`` through the link's joint waypoints (the planned, collision-checked straight
joint moves; the controller's own timing at the joints' common limits). Each seam with
its approach and retract: the planned joint trajectory resampled to the controller
period (0.002 s on e-Series) on the plan's straight joint steps and streamed with one
``servoj`` per period. URScript units: metres, radians, seconds.

Process I/O from the plan's I/O events: an output is set (``set_standard_digital_out``,
``set_standard_analog_out``) just before the first ``servoj`` whose sample has reached
the event's time, so the tool is at most v_TCP · period past its position (0.2 mm at
100 mm/s and 2 ms). The flow, ``set_standard_analog_out(n, value / 10 V)`` (URScript
takes the output as a fraction of its 0–10 V range), follows the plan's ``ao`` column
while it is live, interpolated between live samples only (an edge is a step, not a
ramp), written at each event and whenever it has changed by ``ANALOG_STEP_V`` or by
``ANALOG_STEP_SHARE`` of its value, and holds the idle value otherwise.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from offline_prog.atomic import write_atomic
from offline_prog.export.post import ControllerPost
from offline_prog.export.record import JointMove, ProgramRecord, SeamRun, Switch
from offline_prog.export.text import urscript_comment
from offline_prog.io_events import Signal

E_SERIES_PERIOD_S = 0.002
SERVOJ_LOOKAHEAD_S = 0.1
SERVOJ_GAIN = 300
ANALOG_RANGE_V = 10.0  # standard analog outputs: 0..10 V as 0..1
ANALOG_STEP_V = 0.02  # write the flow when it changed by this much
# ... or by this share of its value (a process model's quality follows the output's
# value relative to the speed: a bead or a tape at a slow ramp needs fine steps)
ANALOG_STEP_SHARE = 0.002


@dataclasses.dataclass(frozen=True)
class UrScriptOptions:
    """name: the program's function (≤ 63 characters, our bound); period_s: the servoj
    period [s] (the controller's)."""

    name: str = "offline_prog"
    period_s: float = E_SERIES_PERIOD_S


class UrScriptPost(ControllerPost):
    """The URScript program of a job (see the module docstring)."""

    FORMAT = "urscript"
    Options = UrScriptOptions
    NAME_MAX = 63
    OPW_ONLY = False

    def __init__(self, job, options: UrScriptOptions, **flags):
        super().__init__(job, options, **flags)
        if not options.period_s > 0:
            raise ValueError(f"period_s={options.period_s}: need a period > 0 s")
        # movej: the joints' common limits, at the plan's motion.link_speed_percent
        share = self.job.job.link_speed_percent / 100.0
        self.v_link = float(self.robot.qd_max.min()) * share
        self.a_link = float(self.robot.qdd_max.min())
        self.lines: list[str] = []

    def conventions(self, record: ProgramRecord) -> list[str]:
        io, rows, names = record.job.process_io, record.job.job, record.job.seam_names
        lines = [
            "Units: m, rad, s. Joint order: " + ", ".join(rows.joint_names) + ".",
            f"Job: {len(names)} seams in this order: {', '.join(names)}.",
            "Frames: none. This program streams joint positions, which no installation TCP "
            "or feature moves: after calibrating the tool or the grasp, plan again with the "
            "calibrated cell (offline-prog calibrate) and export again.",
            f"Links: movej through joint waypoints (a={self.a_link:.3f}, v={self.v_link:.3f}); "
            f"seams with approach and retract: servoj every {self.options.period_s} s "
            "(resampled from the plan).",
        ]
        if io is not None and io.digital_output is not None:
            lines.append(
                f"Process output: standard digital out {io.digital_output}, on "
                f"{io.on_lead_m * 1e3:g} mm before each seam's start, off "
                f"{io.off_lead_m * 1e3:g} mm before its end (at the servoj sample that "
                "reaches it)."
            )
        if io is not None and io.analog_output is not None:
            lines.append(
                f"Flow: standard analog out {io.analog_output} = ({io.offset:g} V + "
                f"{io.per_mps:g} V per m/s x v_TCP) / 10 V, within [{io.min:g}, {io.max:g}] V."
            )
        return lines

    def header(self, lines: list[str]) -> None:
        self.lines += [f"# {urscript_comment(line)}" for line in lines]
        self.lines.append(f"def {self.options.name}():")

    def frames(self) -> None:
        """The payload (gripper + part, centre of mass in the flange) when the cell
        gives it; the program moves the flange's joints, so it sets no TCP."""
        rows = self.job.job
        if (load := self.load) is not None:
            mass, p_EC = load.total(rows.X_EP)
            self.lines.append(f"  set_payload({mass:.3f}, {_list(p_EC, 4)})")

    def move_joint(self, move: JointMove) -> None:
        for q in move.targets:
            self.lines.append(f"  movej({_list(q)}, a={self.a_link:.3f}, v={self.v_link:.3f})")

    def seam(self, run: SeamRun) -> None:
        """The seam with its approach and retract, streamed (see the module docstring)."""
        rows, period = self.job.job, self.options.period_s
        t = rows.t[run.rows]
        grid = np.arange(0.0, t[-1] - t[0], period)
        grid = np.append(grid, t[-1] - t[0]) if t[-1] - t[0] - grid[-1] > 1e-9 else grid
        grid = grid + t[0]  # the job's clock
        q = joints_on_steps(t, rows.q[run.rows], grid)
        # An event is set before the first command whose sample is at or past its time.
        sets: dict[int, list] = {}
        for event in run.events:
            i = int(np.searchsorted(grid, event.t_s - 1e-12))
            sets.setdefault(min(max(i, 1), len(grid) - 1), []).append(event)
        flow, last = self._flow(run, grid), None
        for i in range(1, len(grid)):
            events = sets.get(i, [])
            self.lines += [
                self.set_output(Switch(0, 0.0, e)) for e in events if e.signal is Signal.DIGITAL
            ]
            analog = [e for e in events if e.signal is Signal.ANALOG]
            if flow is not None and (
                last is None
                or abs(flow[i] - last) >= min(ANALOG_STEP_V, ANALOG_STEP_SHARE * abs(last))
                or analog
            ):
                last = flow[i]
                if analog:  # the event, at the value the plan's flow has at this sample
                    event = dataclasses.replace(analog[0], value=float(flow[i]))
                    self.lines.append(self.follow_speed(Switch(0, 0.0, event)))
                else:
                    self.lines.append(self._analog_out(flow[i]))
            self.lines.append(
                f"  servoj({_list(q[i])}, t={period}, lookahead_time={SERVOJ_LOOKAHEAD_S}, "
                f"gain={SERVOJ_GAIN})"
            )

    def set_output(self, switch: Switch) -> str:
        state = "True" if switch.event.state else "False"
        return f"  set_standard_digital_out({switch.event.output}, {state})"

    def follow_speed(self, switch: Switch) -> str:
        """The flow output at the event's value: the plan's flow, which follows the TCP
        speed while live (the stream writes its further values)."""
        return self._analog_out(switch.event.value)

    def footer(self, out_dir: Path) -> list[Path]:
        name = self.options.name
        file = out_dir / f"{name}.script"
        write_atomic(file, "\n".join([*self.lines, "  stopj(2.0)", "end", f"{name}()"]) + "\n")
        return [file]

    def _analog_out(self, value_v: float) -> str:
        output = self.job.process_io.analog_output
        fraction = np.clip(value_v / ANALOG_RANGE_V, 0.0, 1.0)
        return f"  set_standard_analog_out({output}, {fraction:.4f})"

    def _flow(self, run: SeamRun, grid: np.ndarray) -> np.ndarray | None:
        """(len(grid),) the flow command at the grid times [V]: the plan's ``ao`` column
        between its live samples while the flow is live (its analog events), else idle."""
        io = self.job.process_io
        if io is None or io.analog_output is None or self.job.analog is None:
            return None
        t, value = self.job.job.t[run.rows], self.job.analog[run.rows]
        events = [e for e in run.events if e.signal is Signal.ANALOG]
        out = np.full(len(grid), io.idle)
        for on, off in zip(events[::2], events[1::2], strict=True):
            live = (t >= on.t_s) & (t < off.t_s)
            here = (grid >= on.t_s) & (grid < off.t_s)
            if live.any():
                out[here] = np.interp(grid[here], t[live], value[live])
            else:  # a window shorter than a sample: the event's own value
                out[here] = on.value
        return out


def joints_on_steps(t: np.ndarray, q: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """(M, 6) the joints at times ``grid`` (M,) [s], linear between the plan's samples
    t (N,), q (N, 6) [rad]: the straight joint step between two samples is what the
    collision check certified (collision.check), so a servoj target never leaves it."""
    return np.column_stack([np.interp(grid, t, q[:, j]) for j in range(q.shape[1])])


def _list(values: np.ndarray, digits: int = 7) -> str:
    return "[" + ", ".join(f"{v:.{digits}f}" for v in values) + "]"
