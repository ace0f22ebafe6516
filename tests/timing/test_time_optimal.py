"""The time-optimal process law: TOPP-RA agrees with toppra's own use, the jerk
stage keeps every joint limit (velocity, acceleration, jerk), a binding velocity
limit is reported with the right joint and σ band, and a tight jerk limit holds;
for cycle_time the averaged profile (filtered_stage) holds every limit too and is
faster than the staircase, and on the tape demo within 5 % of TOPP-RA."""

import io
import json
import re

import numpy as np
import pytest

from offline_prog.timing.filtered_law import FilteredTimeLaw
from offline_prog.timing.filtered_stage import filtered_timing
from offline_prog.timing.jerk_stage import jerk_limited_law, steady_jerk_limit
from offline_prog.timing.joint_timing import JointRates
from offline_prog.timing.time_optimal import topp_profile

QD_MAX = np.full(6, 2.0)  # rad/s
QDD_MAX = np.full(6, 8.0)  # rad/s²
QDDD_MAX = np.full(6, 80.0)  # rad/s³
LENGTH = 1.0  # m


def bump_rates(gain: float = 3.0, joint: int = 2, sigma=None) -> JointRates:
    """A smooth joint path on σ ∈ [0, 1] m, exact at any σ: slow sines on every joint
    plus a steep stretch of ``joint`` around σ = 0.5 (q′ up to 1 + gain rad/m there)."""
    from scipy.special import erf

    sigma = np.linspace(0.0, LENGTH, 2001) if sigma is None else sigma
    k = np.arange(6)[None, :] + 1.0
    q = 0.3 * np.sin(k * sigma[:, None])
    dq = 0.3 * k * np.cos(k * sigma[:, None])
    ddq = -0.3 * k**2 * np.sin(k * sigma[:, None])
    x = (sigma - 0.5) / 0.05
    q[:, joint] += gain * 0.05 * np.sqrt(np.pi) / 2 * erf(x)  # ∫ gain · exp(−x²) dσ
    dq[:, joint] += gain * np.exp(-(x**2))
    ddq[:, joint] += gain * np.exp(-(x**2)) * (-2 * x / 0.05)
    return JointRates(sigma, q, dq, ddq)


def bump_rates_at(**kwargs):
    """bump_rates as a function of σ (exact at every sample, no interpolation)."""
    return lambda sigma: bump_rates(sigma=sigma, **kwargs)


def sampled_use(rates, law, limits=(QD_MAX, QDD_MAX, QDDD_MAX), rate_hz=1000.0):
    """Largest |q̇|/q̇max, |q̈|/q̈max, |q⃛|/q⃛max on samples of the law: q̇ = q′σ̇ at
    each sample, q̈ and q⃛ by finite differences of it (the check a user would do on
    trajectory.csv's qd columns)."""
    t = np.arange(0.0, law.duration, 1.0 / rate_hz)
    sigma, sd, _, _ = law(t)
    qd = rates(sigma).dq * sd[:, None]
    qdd = np.diff(qd, axis=0) * rate_hz
    qddd = np.diff(qdd, axis=0) * rate_hz
    return tuple(
        float((np.abs(x) / limit).max()) for x, limit in zip((qd, qdd, qddd), limits, strict=True)
    )


def test_local_resolve_equals_a_whole_new_solve():
    """Lowering the speed limit curve on a stretch and re-solving only around it gives
    TOPP-RA's whole-path answer (time_optimal.resolve_locally)."""
    from offline_prog.timing.time_optimal import resolve_locally

    rates = bump_rates(gain=1.0)
    curve = np.full(len(rates.sigma), 0.8)
    common = dict(qd_max=QD_MAX, qdd_max=QDD_MAX, v_cap=0.8, a_path=2.0)

    def solve(span=None, ends=(0.0, 0.0)):
        return topp_profile(rates, v_steady=curve, span=span, ends=ends, **common)

    before = solve()
    lowered = [(0.2, 0.25), (0.8, 0.85)]
    for a, b in lowered:  # a stretch the old profile is over, near each end
        curve[(rates.sigma >= a) & (rates.sigma <= b)] = 0.3
    local = resolve_locally(before, lowered, solve, reach=0.8**2 / (2 * 2.0))
    whole = solve()
    assert local.ok and whole.ok
    np.testing.assert_allclose(local.sigma, whole.sigma)
    np.testing.assert_allclose(local.speed, whole.speed, atol=1e-6)
    assert local.duration > before.duration + 0.1  # the lowered stretches cost time
    # A reach too short to hold the new slowdown widens until it does.
    curve[(rates.sigma >= 0.5) & (rates.sigma <= 0.52)] = 0.05
    tight = resolve_locally(whole, [(0.5, 0.52)], solve, reach=1e-3)
    np.testing.assert_allclose(tight.speed, solve().speed, atol=1e-6)


def test_topp_ra_agrees_with_toppra_used_directly():
    import toppra
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    rates = bump_rates()
    profile = topp_profile(rates, qd_max=QD_MAX, qdd_max=QDD_MAX, v_cap=1e3, a_path=1e3)
    waypoints = rates.q[::20]
    spline = toppra.SplineInterpolator(rates.sigma[::20], waypoints)
    instance = algo.TOPPRA(
        [
            constraint.JointVelocityConstraint(np.column_stack([-QD_MAX, QD_MAX])),
            constraint.JointAccelerationConstraint(np.column_stack([-QDD_MAX, QDD_MAX])),
        ],
        spline,
        gridpoints=np.linspace(0.0, LENGTH, 1000),
    )
    reference = instance.compute_trajectory(0, 0).duration
    assert profile.ok
    assert profile.duration == pytest.approx(reference, rel=5e-3)


def test_jerk_stage_holds_every_joint_limit_and_stays_near_topp_ra():
    rates = bump_rates()
    limits = (QD_MAX, QDD_MAX, QDDD_MAX)
    profile = topp_profile(
        rates,
        qd_max=QD_MAX,
        qdd_max=QDD_MAX,
        v_cap=0.5,
        a_path=2.0,
        v_steady=steady_jerk_limit(rates, limits),
    )
    for process in ("constant_speed", "cycle_time"):
        timing = jerk_limited_law(
            rates, profile, v_process=0.5, a_max=2.0, j_max=20.0, limits=limits, process=process
        )
        assert timing.feasible
        assert max(sampled_use(bump_rates_at(), timing.law)) <= 1.01
        assert timing.law.duration <= 1.25 * profile.duration


def test_a_binding_velocity_limit_names_the_joint_and_the_band():
    rates = bump_rates(gain=8.0, joint=2)  # joint 3 needs σ̇ ≤ 2 / 8.06 m/s at σ = 0.5
    limits = (QD_MAX, QDD_MAX, QDDD_MAX * 100)
    profile = topp_profile(rates, qd_max=QD_MAX, qdd_max=QDD_MAX, v_cap=0.5, a_path=2.0)
    timing = jerk_limited_law(rates, profile, v_process=0.5, a_max=2.0, j_max=20.0, limits=limits)
    inner = [s for s in timing.slowdowns if s.constraint not in ("start/stop",)]
    assert len(inner) == 1
    slow = inner[0]
    assert (slow.joint, slow.constraint) == (3, "velocity")
    assert slow.sigma_m[0] < 0.5 < slow.sigma_m[1]
    assert slow.sigma_m[1] - slow.sigma_m[0] < 0.45  # the band ±0.05 m and the ramps
    assert slow.speed_min_m_s <= QD_MAX[2] / np.abs(rates.dq[:, 2]).max()
    assert 0.85 <= slow.use <= 1.0  # plateaus are planned to 90 % of the limit
    assert slow.t_s[0] < slow.t_s[1]


def test_a_tight_jerk_limit_holds_and_costs_time():
    rates = bump_rates()
    loose = (QD_MAX, QDD_MAX, QDDD_MAX)
    tight = (QD_MAX, QDD_MAX, QDDD_MAX / 10)
    durations = []
    for limits in (loose, tight):
        profile = topp_profile(
            rates,
            qd_max=QD_MAX,
            qdd_max=QDD_MAX,
            v_cap=0.5,
            a_path=2.0,
            v_steady=steady_jerk_limit(rates, limits),
        )
        timing = jerk_limited_law(
            rates, profile, v_process=0.5, a_max=2.0, j_max=20.0, limits=limits
        )
        assert timing.feasible
        assert max(sampled_use(bump_rates_at(), timing.law, limits)) <= 1.01
        durations.append(timing.law.duration)
    assert durations[1] > durations[0]


@pytest.mark.parametrize(("gain", "jerk_share"), [(3.0, 1.0), (3.0, 0.1), (8.0, 1.0)])
def test_averaged_profile_holds_every_limit_and_beats_the_staircase(gain, jerk_share):
    rates = bump_rates(gain=gain)
    limits = (QD_MAX, QDD_MAX, QDDD_MAX * jerk_share)
    profile = topp_profile(
        rates,
        qd_max=QD_MAX,
        qdd_max=QDD_MAX,
        v_cap=0.5,
        a_path=2.0,
        v_steady=steady_jerk_limit(rates, limits),
    )
    path = dict(v_process=0.5, a_max=2.0, j_max=20.0, limits=limits)
    staircase = jerk_limited_law(rates, profile, process="cycle_time", **path)
    averaged = filtered_timing(rates, profile, **path)
    assert averaged.feasible
    assert max(sampled_use(bump_rates_at(gain=gain), averaged.law, limits)) <= 1.01
    t = np.arange(0.0, averaged.law.duration, 1e-3)
    _, sd, sdd, sddd = averaged.law(t)
    assert sd.max() <= 0.5 * (1 + 1e-12)
    assert np.abs(sdd).max() <= 2.0 * (1 + 1e-9)
    assert np.abs(sddd).max() <= 20.0 * (1 + 1e-9)
    assert averaged.law.duration < staircase.law.duration


@pytest.mark.slow
def test_tape_demo_cycle_time_within_5_percent_of_topp_ra():
    """The tape demo's cycle_time plan: within 5 % of TOPP-RA without jerk limits,
    with every joint's velocity, acceleration and jerk held on trajectory.csv."""
    from offline_prog.plan import plan_cell

    from conftest import CELLS

    text = (CELLS / "tape_cylinder_ur10e.yaml").read_text()
    text = text.replace(
        "  max_jerk: 10.0\n", "  max_jerk: 10.0\n  time_law: time_optimal\n  process: cycle_time\n"
    )
    cell = CELLS / "_test_time_optimal_tape.yaml"
    cell.write_text(text)
    try:
        plan = plan_cell(cell)
    finally:
        cell.unlink()
    assert isinstance(plan.trajectory.law, FilteredTimeLaw)
    assert plan.trajectory.duration <= 1.05 * plan.joints.retiming.topp_plain_s
    assert max(csv_limit_use(plan)) <= 1.01


def csv_limit_use(plan) -> tuple[float, float, float]:
    """Largest joint velocity, acceleration and jerk use on trajectory.csv, from its
    qd columns by finite differences (controller axes)."""
    from offline_prog.results.plan_folder import trajectory_csv

    table = np.genfromtxt(io.StringIO(trajectory_csv(plan)), delimiter=",", names=True)
    robot = plan.robot
    t = table["t"]
    qd = robot.controller_joints(np.column_stack([table[f"qd{k + 1}"] for k in range(6)]))
    qdd = np.diff(qd, axis=0) / np.diff(t)[:, None]
    qddd = np.diff(qdd, axis=0) / np.diff(0.5 * (t[1:] + t[:-1]))[:, None]
    return (
        float((np.abs(qd) / robot.qd_max).max()),
        float((np.abs(qdd) / robot.qdd_max).max()),
        float((np.abs(qddd) / robot.jerk_limits).max()),
    )


def fixed_turn_seal_text(max_jerk: float | None = None) -> str:
    """The seal demo cell's text with the nozzle's turn fixed (no turn_smoothing_mm),
    without its process model (no ``process:`` block, no ``tool.process_io``), and
    with the path jerk cap ``max_jerk`` [m/s³] if given."""
    from conftest import CELLS

    text = (CELLS / "seal_plate_kr16.yaml").read_text()
    text = re.sub(r"\n  turn_smoothing_mm: .*", "", text)
    text = re.sub(r"\nprocess:.*\n  model: bead\n  bead: .*", "", text)
    text = re.sub(r"\n  process_io:\n(    .*\n)+", "\n", text)
    assert "model: bead" not in text and "process_io" not in text
    if max_jerk is not None:
        assert "  max_jerk: 10.0\n" in text
        text = text.replace("  max_jerk: 10.0\n", f"  max_jerk: {max_jerk}\n")
    return text


@pytest.mark.slow
@pytest.mark.parametrize("process", ["constant_speed", "cycle_time"])
def test_demo_cell_trajectory_csv_keeps_joint_limits(tmp_path, process):
    """trajectory.csv of the time-optimal seal demo, checked by finite differences of
    its qd columns with a 1 % margin; and it is never slower than the sin² plan."""
    from offline_prog.plan import plan_cell
    from offline_prog.results.plan_folder import trajectory_csv

    from conftest import CELLS

    # The nozzle's turn fixed (no tool.turn_smoothing_mm): the wrist's jerk binds. No
    # process model: its dispenser caps the path jerk (tests/process); this is the law's.
    text = fixed_turn_seal_text()
    # At rest: on the flying default's leads that take the 50 mm moves over, the
    # cycle_time law's whole run is 13 ms (0.09 %) slower than the sin² law's (issue 37).
    text = text.replace("  closed: true\n", "  closed: true\n  entry: rest\n")
    assert "entry: rest" in text
    fixed = CELLS / f"_test_fixed_turn_{process}.yaml"
    fixed.write_text(text)
    cell = CELLS / f"_test_time_optimal_{process}.yaml"
    cell.write_text(
        text.replace(
            "speed_reference: tcp",
            f"speed_reference: tcp\n  time_law: time_optimal\n  process: {process}",
        )
    )
    try:
        plan = plan_cell(cell)
        sin2 = plan_cell(fixed)
    finally:
        cell.unlink()
        fixed.unlink()
    assert max(csv_limit_use(plan)) <= 1.01  # velocity, acceleration and jerk
    table = np.genfromtxt(io.StringIO(trajectory_csv(plan)), delimiter=",", names=True)
    assert plan.trajectory.duration <= sin2.trajectory.duration
    kinds = {s.constraint for s in plan.joints.retiming.slowdowns}
    assert "jerk" in kinds  # the wrist's jerk limit slows the corners
    if process == "constant_speed":
        # ±0.5 % of the process speed on ≥ 90 % of the length where it is feasible;
        # trajectory.csv's TCP speed agrees (held length ≥ that share of the path).
        share, room = plan.joints.retiming.speed_held
        assert share >= 0.9 and 0.5 < room < 1.0, (share, room)
        v = plan.process_speed.v_m_s
        held = np.abs(table["tcp_speed"] - v) <= 0.005 * v
        ds = np.abs(np.diff(table["sigma"]))
        on_csv = np.sum(ds * (held[1:] & held[:-1])) / np.sum(ds)
        assert on_csv >= share * room - 0.01, (on_csv, share, room)


@pytest.mark.parametrize(("speed", "gain"), [(0.05, 0.0), (0.5, 3.0)])
@pytest.mark.parametrize("process", ["constant_speed", "cycle_time"])
def test_skipping_the_averaged_profile_never_loses_a_better_law(speed, gain, process):
    """Where path_timing skips the averaged profile by its bounds, running it would not
    have given a shorter law (cycle_time) nor one holding the speed longer."""
    from offline_prog.timing.path_timing import HELD_TIE, SKIP_SHARE, PathLimits, _cannot_win
    from offline_prog.timing.speed_hold import SpeedHold

    rates = bump_rates(gain=gain)
    limits = (QD_MAX, QDD_MAX, QDDD_MAX)
    path = dict(v_process=speed, a_max=2.0, j_max=20.0)
    path_limits = PathLimits(LENGTH, speed, 2.0, 20.0, QD_MAX, QDD_MAX, QDDD_MAX)
    profile = topp_profile(
        rates,
        qd_max=QD_MAX,
        qdd_max=QDD_MAX,
        v_cap=speed,
        a_path=2.0,
        v_steady=steady_jerk_limit(rates, limits),
    )
    staircase = jerk_limited_law(rates, profile, limits=limits, process=process, **path)
    averaged = filtered_timing(rates, profile, limits=limits, **path)
    held = SpeedHold(rates, limits=limits, **path)
    skipped = _cannot_win(staircase, held(staircase.law), profile, path_limits, process, held)
    # A slow process on a smooth path skips it; a fast one on a steep path cannot.
    assert skipped == (gain == 0.0)
    if skipped:
        assert averaged.law.duration >= staircase.law.duration / (1 + SKIP_SHARE) - 1e-9
        assert held(averaged.law)[0] <= held(staircase.law)[0] + HELD_TIE
    else:
        assert averaged.law.duration < staircase.law.duration


def test_cycle_without_joint_limits_is_the_fastest_jerk_limited_motion(planned_folder):
    """time_optimal's cycle time without joint limits is the constant-jerk rest-to-rest
    motion under the path's v, a, j (L/v + v/a + a/j on a long path), below sin²'s;
    the demo seal's law (no joint limit binds) reaches it within 0.1 %."""
    from offline_prog.timing.path_timing import without_joint_limits
    from offline_prog.timing.time_law import sin2_time_law

    nominal = sin2_time_law(1.2, v_max=0.1, a_max=1.0, j_max=10.0)
    fastest, reached = without_joint_limits(nominal, "time_optimal")
    assert fastest == pytest.approx(1.2 / 0.1 + 0.1 / 1.0 + 1.0 / 10.0, rel=1e-9) and reached
    assert fastest < without_joint_limits(nominal, "sin2")[0] == nominal.duration
    # 5 mm cannot reach 0.1 m/s at 1 m/s², 10 m/s³ (that takes ≥ 10 mm): "reduced".
    short = sin2_time_law(0.005, v_max=0.1, a_max=1.0, j_max=10.0)
    assert not without_joint_limits(short, "time_optimal")[1]
    assert not without_joint_limits(short, "sin2")[1]
    plan, folder = planned_folder("seal_plate_kr16")
    assert plan.cell.motion.time_law == "time_optimal"  # the default
    # The law times the whole path it runs, rest to rest: a flying seam's with its
    # lead-in and lead-out (the seam's own rows cross its ends at the process speed).
    duration, fastest = plan.joints.retiming.law.duration, plan.nominal_duration_s
    if plan.joints.unbounded_s is not None:  # a process model's bound (issue 28): the
        # sin² staircase holds the bead better than the fastest ramps; the law under the
        # user's own caps is the one that reaches the fastest motion
        motion = plan.cell.motion
        user = sin2_time_law(
            plan.flange.length,
            v_max=plan.process_speed.v_m_s,
            a_max=motion.max_acceleration,
            j_max=motion.max_jerk,
        )
        duration, fastest = plan.joints.unbounded_s, without_joint_limits(user, "time_optimal")[0]
    assert fastest <= duration <= 1.001 * fastest
    report = json.loads((folder / "report.json").read_text())
    if plan.flange.flying:  # no ramp on the seam: it runs L/v from its start to its end
        v, length = plan.process_speed.v_m_s, plan.path.length
        assert plan.trajectory.duration == pytest.approx(length / v, rel=1e-6)
        # report.json puts the law's ramps where they are, on the seam's scale: on the
        # leads (σ and t < 0 before the seam's start, beyond L and its duration after)
        slowdowns = report["robot_motion"]["slowdowns"]
        ramps = [s for s in slowdowns if s["constraint"] == "start/stop"]
        assert len(ramps) == 2
        assert ramps[0]["sigma_end_m"] < 0.0 and ramps[0]["t_end_s"] < 0.0
        assert ramps[1]["sigma_start_m"] > length
        assert ramps[1]["t_start_s"] > plan.trajectory.duration
    # The seal demo reaches its speed: report.json does not call its path short.
    assert report["motion"]["top_speed_reduced"] is False


@pytest.mark.slow
def test_low_path_jerk_cap_keeps_the_wrist_jerk_limit():
    """With the path jerk capped low (1.5625 m/s³, as the bead's dispenser asks) the
    fixed-turn seal cell's law slows where the path's q‴ peaks between the joint-rate
    grid's points (a spline knot next to a corner): trajectory.csv's joint jerk stays
    within the limit by finite differences (it was 1.022 of the wrist's limit, the
    exact jerk 1.042, while the law's check said 0.97)."""
    from offline_prog.plan import plan_cell

    from conftest import CELLS

    cell = CELLS / "_test_low_jerk_cap.yaml"
    cell.write_text(
        fixed_turn_seal_text(max_jerk=1.5625).replace(
            "speed_reference: tcp",
            "speed_reference: tcp\n  time_law: time_optimal\n  process: cycle_time",
        )
    )
    try:
        plan = plan_cell(cell)
    finally:
        cell.unlink()
    assert max(csv_limit_use(plan)) <= 1.01
    assert plan.joints.retiming.feasible


def test_jerk_envelope_keeps_a_peak_between_grid_points():
    """q‴ that rises to a peak and jumps down between two grid points: the grid's
    σ-difference of q″ misses the peak, the envelope of the exact values does not,
    for linear interpolation anywhere on the grid step."""
    from offline_prog.joints.jerk_check import envelope
    from offline_prog.timing.joint_timing import JointRates
    from offline_prog.timing.limit_use import with_jerk

    def third(s):  # rises linearly, then drops at the knot 0.0103 m
        return np.where(s < 0.0103, 1e5 * s / 0.0103, 2e4)[:, None] * np.ones((1, 6))

    fine = np.linspace(0.0, 0.02, 200001)
    ddq = np.concatenate(
        [
            [np.zeros(6)],
            np.cumsum(0.5 * (third(fine)[1:] + third(fine)[:-1]) * np.diff(fine)[:, None], axis=0),
        ]
    )
    grid = np.linspace(0.0, 0.02, 41)  # 0.5 mm: the knot lies inside a step
    rates = JointRates(
        grid,
        np.zeros((41, 6)),
        np.zeros((41, 6)),
        np.interp(grid, fine, ddq[:, 0])[:, None] * np.ones((1, 6)),
    )
    near = np.linspace(0.0095, 0.0110, 301)
    grid_view = np.interp(near, grid, with_jerk(rates)[:, 0])
    assert grid_view.max() < 0.96e5  # the peak smoothed away
    local = (fine > 0.009) & (fine < 0.012)
    raised = envelope(with_jerk(rates), grid, fine[local], third(fine[local]))
    seen = np.interp(near, grid, raised[:, 0])
    assert np.all(seen >= third(near)[:, 0] - 1.0)
