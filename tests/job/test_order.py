"""Seam order: the synchronised PTP time estimate against hand-worked cases and ruckig;
exact order equals brute force over orders and options; the heuristic within 5 % of it;
the given order kept."""

import numpy as np
import pytest

from offline_prog.job.order import (
    EXACT_MAX_SEAMS,
    _Costs,
    _local_search,
    brute_force_order,
    order_job,
    ptp_time,
)

V = np.deg2rad([156, 156, 156, 330, 330, 615])
A = 2.0 * V


def instance(rng, n, options=(1, 4)):
    out = []
    for k in range(n):
        for o in range(rng.integers(*options)):
            out.append((k, f"{k}.{o}", rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)))
    return out


def test_ptp_time_triangle_and_trapezoid_by_hand():
    v, a = np.ones(6), np.ones(6)
    q_b = np.zeros(6)
    q_b[0] = 0.25  # d < v²/a: triangle, T = 2 √(d/a) = 1
    assert ptp_time(np.zeros(6), q_b, v, a) == pytest.approx(1.0)
    q_b[0] = 3.0  # trapezoid: T = d/v + v/a = 4
    assert ptp_time(np.zeros(6), q_b, v, a) == pytest.approx(4.0)
    q_b[3] = 10.0  # the slowest joint decides
    assert ptp_time(np.zeros(6), q_b, v, a) == pytest.approx(11.0)


def test_ptp_time_matches_ruckig_without_a_jerk_limit():
    """ruckig's rest-to-rest time with a jerk limit too high to matter."""
    from ruckig import InputParameter, Ruckig, Trajectory

    rng = np.random.default_rng(0)
    for _ in range(20):
        q_a, q_b = rng.uniform(-2, 2, (2, 6))
        otg, inp, trajectory = Ruckig(6), InputParameter(6), Trajectory(6)
        inp.current_position, inp.target_position = q_a.tolist(), q_b.tolist()
        inp.max_velocity, inp.max_acceleration = V.tolist(), A.tolist()
        inp.max_jerk = (A * 1e6).tolist()
        otg.calculate(inp, trajectory)
        assert ptp_time(q_a, q_b, V, A) == pytest.approx(trajectory.duration, rel=1e-4)


def test_ptp_time_grows_with_the_move():
    rng = np.random.default_rng(1)
    q = rng.uniform(-2, 2, (50, 6))
    t = [ptp_time(np.zeros(6), s * q, V, A) for s in (0.2, 0.5, 1.0)]
    assert np.all(np.diff(np.stack(t), axis=0) > 0)


@pytest.mark.parametrize("seed", range(6))
def test_exact_order_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 8))
    options = instance(rng, n)
    home = rng.uniform(-1, 1, 6)
    result = order_job(options, home, qd_max=V, qdd_max=A, n_seams=n, mode="auto")
    best, _ = brute_force_order(options, home, qd_max=V, qdd_max=A, n_seams=n)
    assert result.method == "exact"
    assert result.air_time_s == pytest.approx(best, abs=1e-9)
    assert sorted(options[i][0] for i in result.sequence) == list(range(n))
    assert sum(result.links_s) == pytest.approx(result.air_time_s)
    assert result.saved_s >= -1e-12


@pytest.mark.parametrize("seed", range(4))
def test_heuristic_within_5_percent_of_the_optimum(seed):
    """Against Held–Karp (which equals brute force, test above) on 8–11 seams."""
    rng = np.random.default_rng(100 + seed)
    n = 8 + seed
    options = instance(rng, n, options=(2, 3))
    home = np.zeros(6)
    time, chosen = _local_search(_Costs(options, home, V, A, None), n)
    best = order_job(options, home, qd_max=V, qdd_max=A, n_seams=n, mode="auto")
    assert best.method == "exact"
    assert time <= 1.05 * best.air_time_s
    assert sorted(options[i][0] for i in chosen) == list(range(n))


def test_given_order_keeps_the_seams_in_order_and_picks_their_best_options():
    rng = np.random.default_rng(7)
    options = instance(rng, 5, options=(2, 4))
    result = order_job(options, np.zeros(6), qd_max=V, qdd_max=A, n_seams=5, mode="given")
    assert [options[i][0] for i in result.sequence] == [0, 1, 2, 3, 4]
    assert result.method == "given" and result.saved_s == 0.0
    # No other choice of options in this order is faster.
    by_seam = [[i for i, o in enumerate(options) if o[0] == k] for k in range(5)]
    costs = _Costs(options, np.zeros(6), V, A, None)
    import itertools

    fastest = min(sum(costs.links(list(c))) for c in itertools.product(*by_seam))
    assert result.air_time_s == pytest.approx(fastest)


def test_beyond_the_exact_size_the_heuristic_runs_and_visits_every_seam():
    rng = np.random.default_rng(3)
    n = EXACT_MAX_SEAMS + 2
    options = instance(rng, n, options=(1, 3))
    result = order_job(options, np.zeros(6), qd_max=V, qdd_max=A, n_seams=n, mode="auto")
    assert result.method == "heuristic"
    assert sorted(options[i][0] for i in result.sequence) == list(range(n))
    assert result.air_time_s <= result.given_air_time_s
