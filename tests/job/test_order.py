"""Seam order: the synchronised PTP time estimate against hand-worked cases and ruckig;
exact order equals brute force over orders and options; the heuristic within 5 % of it,
within its budget, stopping below its improvement threshold, every seam run once; the
given order kept."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from order_oracle import brute_force_order

from offline_prog.job.link_costs import LinkCosts, ptp_time
from offline_prog.job.order import EXACT_MAX_SEAMS, order_job
from offline_prog.job.order_search import SearchResult as Counters
from offline_prog.job.order_search import (
    _costed,
    _moves,
    _neighbours,
    _source,
    _tables,
    _window,
    local_search,
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


@pytest.mark.parametrize("seed", range(7))
def test_exact_order_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = 8 if seed == 6 else int(rng.integers(3, 8))
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
    found = local_search(LinkCosts(options, home, V, A))
    time, chosen = found.air_time_s, found.sequence
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
    costs = LinkCosts(options, np.zeros(6), V, A)
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


@pytest.mark.parametrize("seed", range(4))
def test_a_move_costed_on_its_window_equals_the_whole_order_costed(seed):
    """The search costs a move only where the order changes, from the current order's
    prefix and suffix tables: the same air time as the whole moved order's best
    options (LinkCosts.layered), for every move it generates."""
    rng = np.random.default_rng(200 + seed)
    n = int(rng.integers(3, 16))
    costs = LinkCosts(instance(rng, n), rng.uniform(-1, 1, 6), V, A)
    tour = costs.tour(rng.permutation(n))
    moves = _moves(n, _neighbours(costs), tour)
    lo, length = _window(moves)
    times = _costed(costs, moves, lo, length, _tables(costs, tour), Counters(0.0, [], 0.0))
    moved = tour[_source(moves, np.broadcast_to(np.arange(n + 2), (len(lo), n + 2)))]
    for t, order, first, size in zip(times, moved, lo, length, strict=True):
        assert sorted(order[1:-1]) == list(range(n)) and not np.array_equal(order, tour)
        outside = np.ones(n + 2, dtype=bool)
        outside[first : first + size] = False
        assert np.array_equal(order[outside], tour[outside])  # changed only on its window
        assert t == pytest.approx(costs.layered(list(order[1:-1]))[0], abs=1e-9)


def large_job(seed: int, n: int = 25):
    rng = np.random.default_rng(seed)
    return instance(rng, n, options=(1, 4)), rng.uniform(-1, 1, 6), n


@pytest.mark.parametrize("budget", [100_000, 400_000, 1_600_000])
def test_the_search_stops_within_its_budget(budget):
    """Its own counter of link estimates never passes the budget; a larger budget
    goes on from where a smaller one stopped (never a longer air time)."""
    options, home, n = large_job(11)
    kwargs = {"qd_max": V, "qdd_max": A, "n_seams": n, "min_improvement_s": 0.0}
    result = order_job(options, home, budget=budget, **kwargs).search
    assert result.method == "heuristic" and result.budget == budget
    assert 0 < result.used <= budget
    assert result.stopped == "budget"
    more = order_job(options, home, budget=4 * budget, **kwargs)
    assert more.search.used > result.used
    assert more.air_time_s <= order_job(options, home, budget=budget, **kwargs).air_time_s
    assert more.search.lower_bound_s <= more.air_time_s <= more.search.start_air_time_s


def test_the_search_stops_when_a_round_gains_less_than_the_threshold():
    """Each descent ends at the first round that gains less than min_improvement_s (or
    at one with no gain at all): at most one small gain per descent; a threshold no
    round reaches stops every descent after its first round."""
    options, home, n = large_job(12)
    kwargs = {"qd_max": V, "qdd_max": A, "n_seams": n, "budget": 10**9}
    threshold = 0.05
    search = order_job(options, home, min_improvement_s=threshold, **kwargs).search
    small = [g for g in search.improvements_s if g < threshold]
    assert search.stopped in ("improvement below threshold", "no improving move")
    assert len(small) <= search.descents
    assert all(g > 0 for g in search.improvements_s)
    assert search.used < 10**9  # not stopped by the budget
    never = order_job(options, home, min_improvement_s=1e9, **kwargs).search
    assert never.rounds <= never.descents and never.stopped == "improvement below threshold"
    exhaustive = order_job(options, home, min_improvement_s=0.0, **kwargs).search
    assert exhaustive.stopped == "no improving move"
    assert exhaustive.rounds > search.rounds > never.rounds


@settings(max_examples=15, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(EXACT_MAX_SEAMS + 1, 30),
    most=st.integers(1, 6),
    budget=st.sampled_from([50_000, 500_000, 3_000_000]),
)
def test_every_seam_runs_once_with_one_of_its_own_options(seed, n, most, budget):
    """Whatever the job and budget: the heuristic's order is a permutation of the seams,
    each run by one of its own options (direction, branch), the links add up to the
    air time, never worse than the given order nor below the lower bound."""
    rng = np.random.default_rng(seed)
    options = instance(rng, n, options=(1, most + 1))
    home = rng.uniform(-1, 1, 6)
    result = order_job(options, home, qd_max=V, qdd_max=A, n_seams=n, budget=budget)
    seams = [options[i][0] for i in result.sequence]
    assert sorted(seams) == list(range(n))
    assert all(0 <= i < len(options) for i in result.sequence)
    assert len(result.links_s) == n + 1
    assert sum(result.links_s) == pytest.approx(result.air_time_s)
    assert result.search.lower_bound_s <= result.air_time_s + 1e-9
    assert result.air_time_s <= result.given_air_time_s + 1e-12


def test_report_says_how_the_order_was_found(planned_job):
    """report.json job.order_search: method, budget, what it used, rounds, why it
    stopped, its time, and the air time against the start and the lower bound."""
    import json

    plan, folder = planned_job("seal_job_kr16")
    search = json.loads((folder / "report.json").read_text())["job"]["order_search"]
    assert search["method"] == "exact" and search["stopped"] == "exact"
    assert search["air_time_s"] == pytest.approx(plan.order.air_time_s)
    assert search["lower_bound_s"] <= search["air_time_s"] <= search["start_air_time_s"]
    assert search["time_s"] >= 0.0 and search["rounds"] == 0
