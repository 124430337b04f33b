"""The one-to-one port of the thesis's MATLAB, checked on hand-worked cases."""

import numpy as np
import pytest

import dynia
from dynia import thesis
from dynia.engine.windows import window_costs


def test_conf_limits_use_floor_of_c_times_count_minus_one():
    values = np.arange(200.0)
    # c1 = (1 - 0.9)/2 = 0.04999..., floor(0.04999*199) = 9; c2 = 0.95, floor(189.05) = 189
    np.testing.assert_array_equal(thesis.conf_limits(values, 200, 90), [9.0, 189.0])
    np.testing.assert_array_equal(thesis.conf_limits(np.arange(10.0), 10, 50), [2.0, 6.0])


def test_select_best_parameters_is_a_stable_ascending_rank():
    cost = np.array([3.0, 1.0, 2.0, 1.0, 0.5])
    par = np.array([10.0, 11.0, 12.0, 13.0, 14.0])
    best_mat, best_indices = thesis.select_best_parameters(cost, par, 3)
    np.testing.assert_array_equal(best_indices, [4, 1, 3])  # the tie 1.0 keeps sample order
    np.testing.assert_array_equal(best_mat, [[0.5, 14.0], [1.0, 11.0], [1.0, 13.0]])


def test_calc_likelihood_shifts_only_when_negative_and_normalises():
    lhood = thesis.calc_likelihood(np.array([[0.2, 0], [0.6, 0]]))
    np.testing.assert_allclose(lhood, [0.8 / 1.2, 0.4 / 1.2])
    lhood = thesis.calc_likelihood(np.array([[0.5, 0], [3.0, 0], [1.0, 0]]))
    # 1 - cost = [0.5, -2, 0] -> shifted by 2 -> [2.5, 0, 2] -> / 4.5
    np.testing.assert_allclose(lhood, [2.5 / 4.5, 0, 2 / 4.5])


def test_calc_likelihood_of_equal_costs_above_one_is_nan_as_in_matlab():
    assert np.isnan(thesis.calc_likelihood(np.array([[2.0, 0], [2.0, 0]]))).all()


def test_calc_likelihood_with_one_row_fails_where_matlab_does():
    with pytest.raises(ValueError, match="at least 2 behavioural sets"):
        thesis.calc_likelihood(np.array([[0.1, 1.0]]))


def test_cumul_likelihood_accumulates_in_parameter_order():
    lhood = np.array([0.5, 0.3, 0.2])
    par_sorted = np.array([1.0, 2.0, 3.0])
    cumulated, c_all = thesis.cumul_likelihood(
        5, np.array([0.5, 1.0, 2.0, 3.0, 4.0]), par_sorted, np.array([2, 0, 1]), lhood
    )
    np.testing.assert_allclose(cumulated, [0.2, 0.7, 1.0])
    # MATLAB: 0 below the set, the loop skips values in [min, max), then the CLD, then ones
    assert c_all[0] == 0


def test_cld_gradient_reproduces_the_matlab_quirks():
    # lb=0, ub=4, bins=5: width (4-0)/(5-1) = 1, first limit at 1.
    par_sorted = np.array([0.5, 1.5, 1.6, 2.5, 3.5])
    weights = np.array([0.1, 0.2, 0.3, 0.15, 0.25])
    cumulated = np.cumsum(weights)
    grad = thesis.cld_gradient(5, 4, 0, par_sorted, cumulated, 5)
    # bin [.., 1): samples 0 only -> C(0) - C(0) = 0 (the first sample's weight is dropped)
    # bin [1, 2): samples 1, 2 -> C(2) - C(1) = 0.3
    # bin [2, 3): sample 3 -> C(3) - C(3) = 0
    # bin [3, 4): holds the largest value -> loop ends (next limit 4 > 3.5) -> 0
    np.testing.assert_allclose(grad[:, 0], [0, 0.3, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(grad[:4, 3], [2, 3, 4, 5])  # edges built by repeated addition


def test_cld_gradient_gives_an_empty_bin_minus_the_next_weight():
    par_sorted = np.array([0.5, 2.5, 3.5])
    cumulated = np.cumsum([0.2, 0.3, 0.5])
    grad = thesis.cld_gradient(5, 4, 0, par_sorted, cumulated, 3)
    # bin [1, 2) is empty: end_index = start_index - 1 -> C(0) - C(1) = -0.3
    np.testing.assert_allclose(grad[:, 0], [0, -0.3, 0, 0, 0])


def test_cld_gradient_on_an_edge_fails_where_matlab_does():
    with pytest.raises(ValueError, match="bin edge"):
        thesis.cld_gradient(5, 4, 0, np.array([1.0, 2.5]), np.array([0.5, 1.0]), 2)


def _tiny_problem(seed=0, ns=50, steps=30):
    rng = np.random.default_rng(seed)
    par = rng.uniform(0, 1, ns)
    u = np.r_[np.zeros(steps // 2), np.ones(steps - steps // 2)]
    mct = par[:, None] * u
    y = 0.4 * u + rng.normal(0, 0.01, steps)
    return par, mct, y


def test_moving_window_calcs_identifies_a_gain_when_the_input_is_large():
    par, mct, y = _tiny_problem()
    IC, CI_t, grad = thesis.moving_window_calcs(30, par, 0, 1, 50, mct, y, 10, 20, 2)
    assert IC.shape == (30,) and CI_t.shape == (30, 2) and grad.shape == (10, 30)
    assert IC[-10:].min() > 0.8 > 0.5 > IC[:10].max()
    assert np.all(CI_t[:, 0] <= CI_t[:, 1])
    assert CI_t[-1, 0] <= 0.4 <= CI_t[-1, 1]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(ns=2000 // 3 * 3 + 1), "not a whole number"),
        (dict(percentage=2), "leaves 1 behavioural sets"),
        (dict(n=20), "TIME >= 2n"),
        (dict(lb=1, ub=1), "lb must be below ub"),
        (dict(bins=1), "bins must be at least 2"),
    ],
)
def test_moving_window_calcs_rejects_what_matlab_cannot_run(kwargs, message):
    args = dict(TIME=30, lb=0, ub=1, ns=50, bins=10, percentage=20, n=2)
    args.update(kwargs)
    par, mct, y = _tiny_problem(ns=args["ns"], steps=args["TIME"])
    if "ns" in kwargs:
        args["percentage"] = 10.1
    with pytest.raises(ValueError, match=message):
        thesis.moving_window_calcs(
            args["TIME"], par, args["lb"], args["ub"], args["ns"], mct, y, args["bins"], args["percentage"], args["n"]
        )


def test_moving_window_calcs_checks_shapes():
    par, mct, y = _tiny_problem()
    with pytest.raises(ValueError, match="mct must have shape"):
        thesis.moving_window_calcs(30, par, 0, 1, 50, mct.T, y, 10, 20, 2)
    with pytest.raises(ValueError, match="y must have shape"):
        thesis.moving_window_calcs(30, par, 0, 1, 50, mct, y[:-1], 10, 20, 2)


def script_euler(K, T, u, x=70.0):
    """``example_firstorder.m``'s loop for one sample, written out from the script.

    ``ss(tf(K, [T 1]))``: the transfer function K/T / (s + 1/T) in controllable canonical form,
    a = -1/T, b = 1, c = K/T; then ``x_d = a*x + b*u(i); x = x + x_d; mct(i) = c*x``.
    """
    numerator, denominator = np.array([0.0, K]), np.array([T, 1.0])
    numerator, denominator = numerator / denominator[0], denominator / denominator[0]
    a, b, c = -denominator[1], 1.0, numerator[1]
    out = []
    for u_i in u:
        x_d = a * x + b * u_i
        x = x + x_d
        out.append(c * x)
    return np.array(out)


def test_euler_simulation_runs_the_scripts_loop():
    u = np.r_[np.full(40, 35.0), np.full(20, 10.0), np.zeros(40)]
    params = np.array([[2.0, 3.0], [0.5, 6.5], [6.0, 0.8], [3.3, 1.0]])
    mct = thesis.euler_simulation(params, u)
    for row, (K, T) in zip(mct, params):
        np.testing.assert_allclose(row, script_euler(K, T, u), rtol=1e-13)
    np.testing.assert_allclose(thesis.euler_simulation(params, u, x=0.0)[0], script_euler(2.0, 3.0, u, x=0.0))


def test_euler_simulation_answers_the_input_one_step_early():
    u = np.r_[np.zeros(5), np.ones(10)]
    euler = thesis.euler_simulation([[2.0, 3.0]], u, x=0.0)[0]
    exact = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0]
    assert euler[4] == 0 and euler[5] > 0  # the step at 5 shows at 5
    assert exact[5] == 0 and exact[6] > 0  # in the exact (zero-order hold) output one step later
    # T = 1 puts the Euler pole 1 - 1/T at 0: the output is K u(i) itself, not K u(i-1).
    np.testing.assert_array_equal(thesis.euler_simulation([[2.0, 1.0]], u, x=0.0)[0], 2.0 * u)


def test_euler_simulation_diverges_below_half_a_step_and_settles_at_k_u_above():
    u = np.full(3000, 35.0)
    below, above = thesis.euler_simulation([[2.0, 0.49], [2.0, 0.51]], u)
    # pole 1 - 1/0.49 = -1.04: the oscillation grows by 4 % a step, without bound
    growth = np.abs(below[1:] / below[:-1])[-100:]
    np.testing.assert_allclose(growth, 1 / 0.49 - 1, rtol=1e-9)
    assert np.abs(below[-1]) > 1e40
    assert not np.isfinite(thesis.euler_simulation([[2.0, 0.1]], u)[0, -1])  # pole -9: to inf, then NaN
    np.testing.assert_allclose(above[-1], 2.0 * 35.0, rtol=1e-12)


@pytest.mark.parametrize("time_constant", [0.6, 1.0, 3.0, 7.0])
def test_euler_simulation_steady_state_is_k_times_u(time_constant):
    u = np.full(4000, 12.5)
    np.testing.assert_allclose(thesis.euler_simulation([[1.7, time_constant]], u)[0, -1], 1.7 * 12.5, rtol=1e-12)


def test_moving_window_from_costs_equals_moving_window_calcs():
    par, mct, y = _tiny_problem(seed=4, ns=60, steps=40)
    costs = window_costs(y, mct, 3, 0, 40)
    fast = thesis.moving_window_from_costs(costs, par, 0, 1, 60, 8, 10)
    slow = thesis.moving_window_calcs(40, par, 0, 1, 60, mct, y, 8, 10, 3)
    for got, expected in zip(fast, slow):
        np.testing.assert_array_equal(got, expected)


def _window_by_window(costs, par, lb, ub, bins, percentage, conf_level):
    """The oracle for moving_window_from_costs: movingWindowCalcs's loop body over given costs, window by window.

    Returns IC, CI_t and gradient_data of the windows the MATLAB gets through, and the error of the first it
    stops at (None if none).
    """
    ns = par.size
    count_max = int(ns * (percentage / 100))
    rows = []
    for costs_of_window in costs:
        best_mat, _ = thesis.select_best_parameters(costs_of_window, par, count_max)
        try:
            _, CI, _, gradient_vec = thesis.run_dynia(ns, par, best_mat, lb, ub, bins, conf_level=conf_level)
        except dynia.errors.SettingsError as error:
            return None, error
        rows.append((1 - (CI[1] - CI[0]) / (ub - lb), CI, gradient_vec[:, 0]))
    IC, CI_t, gradient = (np.array(column) for column in zip(*rows))
    return (IC, CI_t, gradient.T), None


def _bin_limits(lb, ub, bins):
    """cld_gradient's limits, by its repeated addition."""
    limits = [lb + (ub - lb) / (bins - 1)]
    while len(limits) < bins + 1:
        limits.append(limits[-1] + (ub - lb) / (bins - 1))
    return limits


def _awkward_window_problem(rng, ns, n_windows, bins, lb, ub):
    """Costs with ties, inf and NaN; parameter values with ties, on bin edges and off the sampling range."""
    width = ub - lb
    values = np.r_[
        rng.uniform(lb - 0.1 * width, ub + 0.1 * width, 6),
        _bin_limits(lb, ub, bins)[1:],  # edges of the second bin on (on the first one the MATLAB stops)
        lb + width / (bins - 1) * np.arange(2, bins + 1),  # the edges as lb + k w, a rounding away
        [ub, lb],
    ]
    par = rng.choice(values, ns) if rng.random() < 0.7 else rng.uniform(lb, ub, ns)
    levels = [np.arange(4.0) / 3, rng.uniform(0, 2, 20), np.array([0.0, -0.0, 0.5])][rng.integers(3)]
    costs = rng.choice(levels, (n_windows, ns))
    for value, share in ((np.inf, rng.uniform(0, 0.3)), (np.nan, rng.uniform(0, 0.3))):
        costs[rng.random(costs.shape) < share] = value
    costs[rng.random(n_windows) < 0.1] = np.nan  # all NaN: every likelihood NaN
    costs[rng.random(n_windows) < 0.1] = np.inf
    mostly_nan = rng.random(n_windows) < 0.1  # fewer numbers than behavioural sets
    costs[mostly_nan, : ns - 1] = np.nan
    continuous = rng.random(n_windows) < 0.3
    costs[continuous] = rng.random((continuous.sum(), ns))
    return costs, par


def _assert_fast_path_equals_oracle(costs, par, lb, ub, bins, percentage, conf_level=90):
    expected, error = _window_by_window(costs, par, lb, ub, bins, percentage, conf_level)
    if error is not None:
        with pytest.raises(dynia.errors.SettingsError) as raised:
            thesis.moving_window_from_costs(costs, par, lb, ub, par.size, bins, percentage, conf_level=conf_level)
        assert str(raised.value) == str(error)
        return False
    got = thesis.moving_window_from_costs(costs, par, lb, ub, par.size, bins, percentage, conf_level=conf_level)
    for got_array, expected_array in zip(got, expected, strict=True):
        np.testing.assert_array_equal(got_array, expected_array)
    return True


# Where a window keeps an inf cost the oracle's calc_likelihood subtracts -inf from -inf: NaN, as in MATLAB.
_ORACLE_ON_INF_COSTS = pytest.mark.filterwarnings("ignore:invalid value encountered in subtract:RuntimeWarning")


@pytest.mark.parametrize("seed", range(40))
@_ORACLE_ON_INF_COSTS
def test_moving_window_from_costs_equals_the_oracle_window_by_window(seed):
    rng = np.random.default_rng(seed)
    ns, percentage = [(40, 5), (100, 2), (60, 5), (50, 10), (80, 25), (30, 100), (200, 1), (120, 50)][seed % 8]
    bins = int(rng.choice([2, 3, 4, 7, 40]))
    lb = float(rng.choice([0.0, 0.1, -3.0, 1.0]))
    ub = lb + float(rng.choice([1.0, 0.7, 6.0, 2.0]))
    conf_level = float(rng.choice([90, 50, 99.9]))
    costs, par = _awkward_window_problem(rng, ns, 120, bins, lb, ub)
    if not _assert_fast_path_equals_oracle(costs, par, lb, ub, bins, percentage, conf_level):
        # The oracle stopped at a window: the windows that it gets through, without that one, compare too.
        keep = np.ones(len(costs), dtype=bool)
        for t in range(len(costs)):
            keep[t] = _window_by_window(costs[t : t + 1], par, lb, ub, bins, percentage, conf_level)[1] is None
        assert not keep.all()
        assert _assert_fast_path_equals_oracle(costs[keep], par, lb, ub, bins, percentage, conf_level)


@_ORACLE_ON_INF_COSTS
def test_moving_window_from_costs_equals_the_oracle_across_chunks_of_windows():
    # 10 000 samples: 230 windows span two of the fast path's chunks, and the 500 behavioural sets'
    # likelihoods are summed over several of numpy's pairwise blocks.
    rng = np.random.default_rng(11)
    costs, par = _awkward_window_problem(rng, 10_000, 230, 40, 1.0, 3.0)
    assert _assert_fast_path_equals_oracle(costs, par, 1.0, 3.0, 40, 5)


def test_moving_window_from_costs_stops_where_the_matlab_does():
    # Bins 3 on [0, 1]: the first edge is 0.5. The third window's behavioural values are 0.5 and 0.9, the
    # smallest on that edge, where cld_gradient stops; the first window's 0.1 and 0.5 pass.
    par = np.array([0.1, 0.5, 0.9, 0.25, 0.75, 0.6, 0.3, 0.2, 0.8, 0.4])
    costs = np.ones((4, 10))
    costs[0, [0, 1]] = costs[1, [4, 5]] = costs[2, [1, 2]] = costs[3, [0, 3]] = 0
    assert not _assert_fast_path_equals_oracle(costs, par, 0.0, 1.0, 3, 20)
    with pytest.raises(ValueError, match=r"np.float64\(0.5\) lies exactly on a bin edge"):
        thesis.moving_window_from_costs(costs, par, 0.0, 1.0, 10, 3, 20)
    assert _assert_fast_path_equals_oracle(costs[[0, 1, 3]], par, 0.0, 1.0, 3, 20)


def test_moving_window_from_costs_needs_two_behavioural_sets_as_calc_likelihood_does():
    with pytest.raises(ValueError, match="leaves 1 behavioural sets"):
        thesis.moving_window_from_costs(np.zeros((3, 50)), np.arange(50.0), 0, 50, 50, 5, 2)


def test_thesis_code_result_ranks_diverged_simulations_last_as_matlab_does():
    example = dynia.synthetic.thesis_example(1, np.random.default_rng(5))
    samples = np.random.default_rng(6).uniform(0, 7, (100, 2))
    samples[:4, 1] = [0.05, 0.1, 0.2, 0.3]  # poles -19 to -2.3: inf, then NaN, within the record
    sims = thesis.euler_simulation(samples, example.u)
    assert np.isinf(sims).any() and np.isnan(sims).any()
    result = thesis.thesis_code_result(
        example.y, sims, samples, [[0, 7], [0, 7]], ["K", "T"], n=10, percentage=10, bins=40
    )
    for p in range(2):
        with np.errstate(over="ignore"):
            IC, CI_t, grad = thesis.moving_window_calcs(500, samples[:, p], 0, 7, 100, sims, example.y, 40, 10, 10)
        np.testing.assert_array_equal(result.ic[p], IC)
        np.testing.assert_array_equal(result.ci[p], CI_t)
        np.testing.assert_array_equal(result.gradient[p], grad)
