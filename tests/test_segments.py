"""Segments from IC curves, least squares on segments, validation on held-out data."""

import dataclasses
import json

import numpy as np
import pytest

from dynia import verdicts
from dynia.errors import ModelError, NothingSelected
from dynia.fit import fit_segments, validation_error
from dynia.models import FOPDT, FirstOrder
from dynia.result import DyniaResult
from dynia.segments import (
    check_segments,
    holdout_split,
    intersect_segments,
    mask_to_segments,
    random_segments,
    segments_from_ic,
    segments_to_mask,
    segments_to_times,
)

FIRST_ORDER_BOUNDS = {"K": (0.0, 7.0), "T": (0.0, 7.0)}
FOPDT_BOUNDS = {"K": (0.0, 5.0), "T": (0.0, 10.0), "theta": (0.0, 8.0)}


def hand_built(ic, names=("K", "T"), **settings):
    """A DyniaResult holding only the IC curves that matter here."""
    ic = np.asarray(ic, dtype=float)
    n_params, n_steps = ic.shape
    return DyniaResult(
        names=tuple(names),
        samples=np.zeros((1, n_params)),
        bounds=np.tile([0.0, 1.0], (n_params, 1)),
        time=np.arange(n_steps) * 2.0,
        ic=ic,
        ci=np.zeros((n_params, n_steps, 2)),
        gradient=np.zeros((n_params, 1, n_steps)),
        bin_centres=np.zeros((n_params, 1)),
        settings=settings,
    )


def reference_clean(mask, merge_gap, min_length):
    """The selection rule step by step: fill short inner gaps, then drop short runs."""
    mask = list(mask)
    filled = mask[:]
    true_steps = [i for i, value in enumerate(mask) if value]
    for i, value in enumerate(mask):
        if not value and true_steps and true_steps[0] < i < true_steps[-1]:
            left = max(j for j in true_steps if j < i)
            right = min(j for j in true_steps if j > i)
            if right - left - 1 < merge_gap:
                filled[i] = True
    kept = [False] * len(mask)
    i = 0
    while i < len(filled):
        if filled[i]:
            j = i
            while j < len(filled) and filled[j]:
                j += 1
            if j - i >= min_length:
                kept[i:j] = [True] * (j - i)
            i = j
        else:
            i += 1
    return kept


# ------------------------------------------------------------ selection


def test_joint_any_and_per_parameter_with_a_missing_window():
    ic = [[0.9, 0.9, 0.2, 0.9, 0.9, np.nan, 0.6, 0.6], [0.1, 0.8, 0.8, 0.8, 0.1, 0.7, 0.7, 0.2]]
    result = hand_built(ic)
    assert segments_from_ic(result, mode="joint") == [(1, 2), (3, 4), (6, 7)]
    assert segments_from_ic(result, mode="any") == [(0, 8)]
    assert segments_from_ic(result, mode="per_parameter") == {"K": [(0, 2), (3, 5), (6, 8)], "T": [(1, 4), (5, 7)]}
    # NaN is never informative, whatever the threshold
    assert segments_from_ic(result, parameters=["K"], ic_threshold=0.0) == [(0, 5), (6, 8)]
    assert segments_from_ic(result, ic_threshold=0.85, mode="any") == [(0, 2), (3, 5)]
    assert segments_from_ic(result, ic_threshold={"K": 0.95, "T": 0.75}, mode="any") == [(1, 4)]


def test_merging_comes_before_the_minimum_length():
    ic = [[1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 1, 0]]
    result = hand_built(ic, names=("K",))
    assert segments_from_ic(result, merge_gap=0, min_length=1) == [(0, 2), (4, 5), (8, 11)]
    assert segments_from_ic(result, merge_gap=2, min_length=1) == [(0, 2), (4, 5), (8, 11)]
    assert segments_from_ic(result, merge_gap=3, min_length=1) == [(0, 5), (8, 11)]
    assert segments_from_ic(result, merge_gap=3, min_length=4) == [(0, 5)]
    assert segments_from_ic(result, merge_gap=0, min_length=3) == [(8, 11)]
    with pytest.raises(NothingSelected):
        segments_from_ic(result, merge_gap=4, min_length=12)


@pytest.mark.parametrize("seed", range(30))
def test_the_selection_matches_a_step_by_step_reference(seed):
    rng = np.random.default_rng(seed)
    ic = rng.uniform(0, 1, (3, 60))
    ic[rng.uniform(size=ic.shape) < 0.1] = np.nan
    merge_gap, min_length = int(rng.integers(0, 6)), int(rng.integers(1, 8))
    result = hand_built(ic, names=("a", "b", "c"))
    informative = ic >= 0.4
    for mode, combined in (("joint", informative.all(0)), ("any", informative.any(0))):
        expected = mask_to_segments(np.array(reference_clean(combined, merge_gap, min_length)))
        options = dict(ic_threshold=0.4, merge_gap=merge_gap, min_length=min_length, mode=mode)
        if expected:
            assert segments_from_ic(result, **options) == expected
        else:
            with pytest.raises(NothingSelected):
                segments_from_ic(result, **options)


def floored(ic, informative, behavioural_spread=None, **settings):
    """``hand_built`` with a noise floor: ``informative`` per step, the behavioural floor 1 at every step."""
    result = hand_built(ic, **settings)
    steps = result.time.size
    spread = np.full(steps, 2.0) if behavioural_spread is None else np.asarray(behavioural_spread, dtype=float)
    return dataclasses.replace(
        result,
        informative=np.asarray(informative, dtype=bool),
        discrimination=np.ones(steps),
        noise_floor=np.full(steps, 0.5),
        behavioural_spread=spread,
        behavioural_floor=np.ones(steps),
    )


def test_the_same_ic_gives_the_same_windows_and_segments_through_every_path():
    # The review's case: windows 40-59 informative, n = 5. One rule, one map: the windows' centres.
    ic = np.full((1, 100), 0.2)
    ic[0, 40:60] = 0.9
    result = hand_built(ic, names=("K",), n=5)
    mask = result.informative_windows()[0]
    assert mask_to_segments(mask) == [(40, 60)]
    assert segments_from_ic(result) == [(40, 60)] == segments_from_ic(result, parameters="K", mode="per_parameter")["K"]
    assert segments_from_ic(result, mode="joint") == [(40, 60)]
    assert (verdicts.high_ic_windows(result, 0) == mask).all()
    assert (verdicts.evidence_windows(result, 0) == (mask & result.full_windows)).all()
    # The threshold is the one default everywhere: IC 0.5 is informative, 0.49 is not.
    ic[0, 40:60] = 0.5
    assert segments_from_ic(hand_built(ic, names=("K",), n=5)) == [(40, 60)]
    ic[0, 40:60] = 0.49
    with pytest.raises(NothingSelected):
        segments_from_ic(hand_built(ic, names=("K",), n=5))


def test_a_window_below_the_noise_floor_or_tied_is_never_informative():
    informative = np.ones(60, dtype=bool)
    informative[20:30] = False  # below the floor
    spread = np.full(60, 2.0)
    spread[40:45] = 0.5  # behavioural set tied within noise (floor 1)
    result = floored(np.full((2, 60), 0.9), informative, spread)
    expected = np.ones(60, dtype=bool)
    expected[20:30] = expected[40:45] = False
    assert (result.informative_windows() == expected).all()
    assert (result.informative_windows(0.0) == expected).all()  # whatever the threshold
    assert segments_from_ic(result, min_length=1, merge_gap=0) == [(0, 20), (30, 40), (45, 60)]
    assert segments_from_ic(result, min_length=1, merge_gap=0, mode="per_parameter")["T"] == [
        (0, 20),
        (30, 40),
        (45, 60),
    ]
    for p in range(2):
        assert not verdicts.high_ic_windows(result, p)[20:30].any()
        assert not verdicts.high_ic_windows(result, p)[40:45].any()
    # Without the floor (reference ports, old files) the IC test is all there is.
    bare = hand_built(np.full((2, 60), 0.9))
    assert bare.informative_windows().all() and segments_from_ic(bare) == [(0, 60)]


def test_the_plots_veil_the_windows_whose_ic_ranks_noise():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    informative = np.ones(60, dtype=bool)
    informative[20:30] = False
    spread = np.full(60, 2.0)
    spread[40:45] = 0.5
    result = floored(np.full((2, 60), 0.9), informative, spread)
    ax = result.plot_information_content("K")
    veil = [c for c in ax.collections if "noise" in str(c.get_label())]
    assert len(veil) == 1
    # steps are 2 s apart: a step reaches 1 s to either side
    starts = sorted(round(float(path.vertices[:, 0].min()), 6) for path in veil[0].get_paths())
    assert starts == [39.0, 79.0]


def test_nothing_selected_is_its_own_error():
    result = floored(np.full((1, 30), 0.9), np.zeros(30, dtype=bool), names=("K",))
    with pytest.raises(NothingSelected) as caught:
        segments_from_ic(result)
    assert isinstance(caught.value, ValueError)  # a DyniaError, as every error of the package
    with pytest.raises(NothingSelected):
        segments_from_ic(hand_built([[0.9, 0.2, 0.9]], names=("K",)), ic_threshold=0.95)
    with pytest.raises(NothingSelected):
        segments_from_ic(hand_built([[0.9, 0.2], [0.1, 0.9]]), mode="joint")


def test_defaults_follow_the_window_of_the_run():
    # n = 2: runs shorter than a window (5 steps) go, gaps shorter than 2 close
    ic = [[1, 1, 1, 0, 1, 1, 0, 0, 1, 1, 1, 1, 0, 1]]
    assert segments_from_ic(hand_built(ic, names=("K",), n=2)) == [(0, 6), (8, 14)]
    # without n in the settings nothing is merged or dropped
    assert segments_from_ic(hand_built(ic, names=("K",))) == [(0, 3), (4, 6), (8, 12), (13, 14)]
    # a trailing window's IC at t belongs to step t - n
    assert segments_from_ic(hand_built(ic, names=("K",), n=2, window="trailing"), min_length=1, merge_gap=0) == [
        (0, 1),
        (2, 4),
        (6, 10),
        (11, 12),
    ]


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        (dict(parameters=["K", "gain"]), ValueError, r"unknown: \['gain'\]"),
        (dict(ic_threshold=1.5), ValueError, r"ic_threshold of K must be a number in \[0, 1\]"),
        (dict(ic_threshold={"K": 0.5}), ValueError, r"missing: \['T'\]"),
        (dict(mode="all"), ValueError, "mode must be one of"),
        (dict(min_length=0), ValueError, "min_length must be at least 1"),
        (dict(merge_gap=1.5), ValueError, "merge_gap must be a whole number"),
    ],
)
def test_bad_selection_options(kwargs, error, message):
    with pytest.raises(error, match=message):
        segments_from_ic(hand_built(np.ones((2, 5))), **kwargs)


def test_only_a_result_is_accepted():
    with pytest.raises(TypeError, match="result must be a DyniaResult"):
        segments_from_ic(np.ones((2, 5)))


# ------------------------------------------------------------- helpers


def test_segments_to_times_ends_at_the_last_step():
    time = np.arange(10) * 2.0
    assert segments_to_times([(0, 1), (3, 10)], time) == [[0.0, 0.0], [6.0, 18.0]]


@pytest.mark.parametrize(
    "segments, message",
    [
        ([(0, 11)], r"segments\[0\] = \(0, 11\) is not a segment of a record of 10 steps"),
        ([(5, 5)], r"need 0 <= start < stop"),
        ([(-1, 3)], r"need 0 <= start < stop"),
        ([(0, 5), (4, 8)], r"segments\[1\] = \(4, 8\) overlaps segments\[0\]"),
        ([(5, 8), (0, 2)], r"starts before"),
        ([(0.5, 3)], "whole step indices"),
        ([(1, 2, 3)], r"must be a \(start, stop\) pair"),
    ],
)
def test_bad_segments(segments, message):
    with pytest.raises(ValueError, match=message):
        check_segments(segments, 10)


def test_masks_and_intersections_round_trip():
    segments = [(0, 3), (3, 5), (7, 9)]
    mask = segments_to_mask(segments, 10)
    assert mask.tolist() == [True] * 5 + [False, False, True, True, False]
    assert mask_to_segments(mask) == [(0, 5), (7, 9)]  # touching segments become one run
    assert intersect_segments(segments, [(2, 8)]) == [(2, 3), (3, 5), (7, 8)]
    assert intersect_segments(segments, []) == []


def test_random_segments_keep_the_lengths_avoid_the_excluded_part_and_repeat_with_the_seed():
    lengths = [30, 5, 12, 1]
    exclude = [(0, 10), (140, 200)]
    for seed in range(20):
        segments = random_segments(lengths, 200, seed, exclude=exclude)
        check_segments(segments, 200)
        assert sorted(stop - start for start, stop in segments) == sorted(lengths)
        assert not (segments_to_mask(segments, 200) & segments_to_mask(exclude, 200)).any()
    draw = random_segments(lengths, 200, 3, exclude=exclude)
    assert draw == random_segments(lengths, 200, 3, exclude=exclude)
    assert draw != random_segments(lengths, 200, 4, exclude=exclude)


def test_one_random_segment_starts_uniformly():
    rng = np.random.default_rng(0)
    starts = [random_segments([6], 10, rng)[0][0] for _ in range(2500)]
    counts = np.bincount(starts, minlength=5)
    assert counts.size == 5  # starts 0 .. 4 only
    assert np.all(np.abs(counts - 500) < 5 * np.sqrt(400))  # binomial sd ~ 20


def test_random_segments_that_cannot_fit():
    with pytest.raises(ValueError, match="total 30 steps but only 20"):
        random_segments([20, 10], 40, 0, exclude=[(0, 20)])
    with pytest.raises(ValueError, match="too fragmented"):
        random_segments([6], 20, 0, exclude=[(5, 6), (10, 11), (15, 16)])


def test_holdout_split():
    assert holdout_split(10) == ([(0, 7)], [(7, 10)])
    assert holdout_split(1000, 0.25) == ([(0, 750)], [(750, 1000)])
    assert holdout_split(10, [(0, 2), (5, 6)]) == ([(2, 5), (6, 10)], [(0, 2), (5, 6)])
    with pytest.raises(ValueError, match="held_out must lie strictly between 0 and 1"):
        holdout_split(10, 1.0)
    with pytest.raises(ValueError, match="covers the whole record"):
        holdout_split(10, [(0, 10)])


# ----------------------------------------------------------------- fit


def steps_input():
    return np.r_[np.zeros(20), np.ones(40), np.zeros(40), 2 * np.ones(50), np.zeros(50)]


def test_noise_free_first_order_is_recovered_exactly_from_two_segments():
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    fit = fit_segments(u, y, FirstOrder(), [(15, 60), (130, 170)], bounds=FIRST_ORDER_BOUNDS)
    assert fit.success
    assert fit.parameters["K"] == pytest.approx(2.0, abs=1e-6)
    assert fit.parameters["T"] == pytest.approx(3.0, abs=1e-6)
    assert fit.rmse < 1e-9 and fit.n_points == 85 and fit.dof == 83
    assert fit.identifiable == {"K": True, "T": True}
    assert np.allclose(fit.fitted[15:60], y[15:60]) and np.isnan(fit.fitted[:15]).all()


@pytest.mark.parametrize("theta", [2.4, 3.0])  # a fraction of a step, and a kink of the residual
def test_noise_free_fopdt_is_recovered_exactly(theta):
    u = steps_input()
    y = FOPDT().simulate([[1.5, 4.0, theta]], u)[0]
    y[[30, 31, 140]] = np.nan  # missing points are skipped
    fit = fit_segments(u, y, FOPDT(), [(10, 80), (95, 200)], bounds=FOPDT_BOUNDS)
    for name, true in zip(("K", "T", "theta"), (1.5, 4.0, theta)):
        assert fit.parameters[name] == pytest.approx(true, abs=1e-6)
    assert fit.n_points == 70 + 105 - 3


def test_noisy_fopdt_lies_within_a_few_standard_errors():
    u = steps_input()
    rng = np.random.default_rng(11)
    y = FOPDT().simulate([[1.5, 4.0, 2.4]], u)[0] + rng.normal(0, 0.05, u.size)
    fit = fit_segments(u, y, FOPDT(), [(10, 80), (95, 200)], bounds=FOPDT_BOUNDS)
    for name, true in zip(("K", "T", "theta"), (1.5, 4.0, 2.4)):
        assert abs(fit.parameters[name] - true) < 3 * fit.std_errors[name]
        assert 0 < fit.std_errors[name] < 0.05 * true
    assert fit.sigma == pytest.approx(0.05, rel=0.15)
    assert np.allclose(np.sqrt(np.diag(fit.covariance)), list(fit.std_errors.values()))


def test_standard_errors_match_a_monte_carlo_of_noise_realisations():
    u = np.r_[np.zeros(10), np.ones(30), np.zeros(30), 2 * np.ones(30)]
    clean = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    rng = np.random.default_rng(5)
    estimates, errors = [], []
    for _ in range(150):
        fit = fit_segments(
            u, clean + rng.normal(0, 0.1, u.size), FirstOrder(), [(5, 45), (65, 90)], bounds=FIRST_ORDER_BOUNDS
        )
        estimates.append([fit.parameters["K"], fit.parameters["T"]])
        errors.append([fit.std_errors["K"], fit.std_errors["T"]])
    estimates, errors = np.array(estimates), np.array(errors)
    spread = estimates.std(axis=0, ddof=1)
    # 150 realisations know the spread to about 6 %
    assert np.allclose(errors.mean(axis=0), spread, rtol=0.2)
    coverage = (np.abs(estimates - [2.0, 3.0]) < 2 * errors).mean(axis=0)
    assert np.all((coverage > 0.88) & (coverage < 0.995))


def test_with_the_time_constant_fixed_the_gain_is_a_linear_regression():
    u = steps_input()
    regressor = FirstOrder().simulate([[1.0, 3.0]], u)[0]  # y is K times this
    y = 2.0 * regressor + np.random.default_rng(9).normal(0, 0.1, u.size)
    segments = [(15, 60), (95, 170)]
    inside = segments_to_mask(segments, u.size)
    x, observed = regressor[inside], y[inside]
    gain = x @ observed / (x @ x)
    residual = observed - gain * x
    fit = fit_segments(u, y, FirstOrder(), segments, bounds={"K": (0, 7)}, fixed={"T": 3.0})
    assert fit.parameters["K"] == pytest.approx(gain, rel=1e-10)
    assert fit.sigma == pytest.approx(np.sqrt(residual @ residual / (x.size - 1)), rel=1e-8)
    assert fit.std_errors["K"] == pytest.approx(fit.sigma / np.sqrt(x @ x), rel=1e-6)


def test_a_flat_input_leaves_the_time_constant_unidentifiable():
    u = np.ones(150)
    rng = np.random.default_rng(2)
    y = FirstOrder().simulate([[2.0, 3.0]], u, x0="steady")[0] + rng.normal(0, 0.1, u.size)
    fit = fit_segments(u, y, FirstOrder(), [(50, 100)], bounds=FIRST_ORDER_BOUNDS)
    assert fit.identifiable == {"K": True, "T": False}
    assert fit.std_errors["T"] == np.inf and np.isnan(fit.covariance[1]).all()
    # the gain alone is the mean level, known to s/sqrt(n) with one degree of freedom used
    segment = y[50:100]
    assert fit.parameters["K"] == pytest.approx(segment.mean(), abs=1e-9)
    assert fit.dof == 49
    assert fit.std_errors["K"] == pytest.approx(segment.std(ddof=1) / np.sqrt(50), rel=1e-6)
    record = json.loads(json.dumps(fit.to_dict(), allow_nan=False))
    assert record["std_errors"]["T"] is None and record["identifiable"]["T"] is False
    assert record["segments"] == [[50, 100]]


def test_with_an_offset_per_segment_a_plateau_says_nothing_about_the_gain():
    u = np.ones(150)
    y = FirstOrder().simulate([[2.0, 3.0]], u, x0="steady")[0]
    level = fit_segments(u, y, FirstOrder(), [(50, 100)], bounds=FIRST_ORDER_BOUNDS)
    assert level.identifiable == {"K": True, "T": False}
    free_level = fit_segments(u, y, FirstOrder(), [(50, 100)], bounds=FIRST_ORDER_BOUNDS, offset="segment")
    assert free_level.identifiable == {"K": False, "T": False}


def test_an_offset_per_segment_absorbs_level_shifts():
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    y[:100] += 0.7
    y[100:] -= 0.4
    segments = [(15, 60), (100, 170)]
    fit = fit_segments(u, y, FirstOrder(), segments, bounds=FIRST_ORDER_BOUNDS, offset="segment")
    assert fit.parameters["K"] == pytest.approx(2.0, abs=1e-6)
    assert fit.parameters["T"] == pytest.approx(3.0, abs=1e-6)
    assert fit.offsets == pytest.approx((0.7, -0.4), abs=1e-6)
    assert fit.dof == 45 + 70 - 2 - 2
    assert fit.validation_error(u, y, [(170, 200)]) == pytest.approx(0.0, abs=1e-6)
    without = fit_segments(u, y, FirstOrder(), segments, bounds=FIRST_ORDER_BOUNDS)
    assert abs(without.parameters["K"] - 2.0) > 0.05 and without.rmse > 0.1


def test_a_warm_up_from_steady_input_matches_the_whole_history():
    u = np.r_[np.zeros(20), np.ones(100), np.zeros(60)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    # the simulation starts at step 70, after 50 steps (17 time constants) at input 1
    fit = fit_segments(u, y, FirstOrder(), [(110, 160)], bounds=FIRST_ORDER_BOUNDS, warmup=40)
    assert fit.parameters["K"] == pytest.approx(2.0, abs=1e-6)
    assert fit.parameters["T"] == pytest.approx(3.0, abs=1e-6)
    # without a warm-up a segment starting mid-decay is simulated from rest at
    # input 0: the output stays 0 whatever the parameters, and nothing is learnt
    short = fit_segments(u, y, FirstOrder(), [(121, 160)], bounds=FIRST_ORDER_BOUNDS, warmup=0)
    assert short.identifiable == {"K": False, "T": False}
    assert short.rmse == pytest.approx(np.sqrt(np.mean(y[121:160] ** 2)))


def test_fixed_parameters_are_not_fitted():
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    fit = fit_segments(u, y, FirstOrder(), [(15, 60)], bounds={"T": (0, 7)}, fixed={"K": 2.0})
    assert fit.fitted_names == ("T",) and fit.parameters == pytest.approx({"K": 2.0, "T": 3.0}, abs=1e-6)
    assert list(fit.std_errors) == ["T"] and fit.covariance.shape == (1, 1)


def test_multistart_escapes_a_local_minimum_of_the_dead_time():
    rng = np.random.default_rng(5)
    u = np.repeat(rng.choice([-1.0, 1.0], 40), 8)
    y = FOPDT().simulate([[1.0, 2.0, 13.0]], u)[0]
    bounds = {"K": (0.1, 3), "T": (0.1, 5), "theta": (0, 50)}
    one = fit_segments(u, y, FOPDT(), [(50, 320)], bounds=bounds, initial={"theta": 35})
    assert one.parameters["theta"] > 20  # stuck
    several = fit_segments(u, y, FOPDT(), [(50, 320)], bounds=bounds, initial={"theta": 35}, n_starts=8, rng=3)
    assert several.parameters["theta"] == pytest.approx(13.0, abs=1e-6)
    again = fit_segments(u, y, FOPDT(), [(50, 320)], bounds=bounds, initial={"theta": 35}, n_starts=8, rng=3)
    assert again.parameters == several.parameters


def test_to_dict_is_json_ready():
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(0).normal(0, 0.1, u.size)
    fit = fit_segments(u, y, FirstOrder(), [(15, 60)], bounds={"K": (0, np.inf), "T": (0, 7)}, initial={"K": 1.0})
    record = json.loads(json.dumps(fit.to_dict(), allow_nan=False))
    assert record["parameters"] == pytest.approx(fit.parameters)
    assert record["settings"]["bounds"]["K"] == [0.0, None]
    assert record["settings"]["initial"] == {"K": 1.0, "T": 3.5}
    assert record["settings"]["warmup"] is None and record["settings"]["x0"] == "steady"


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(segments=[(0, 400)]), r"is not a segment of a record of 200 steps"),
        (dict(segments=[(0, 50), (40, 60)]), "overlaps"),
        (dict(segments=[]), "segments is empty"),
        (dict(bounds={"K": (0, 7), "tau": (0, 7)}), r"bounds names unknown parameters \['tau'\]"),
        (dict(bounds={"K": (0, 7)}), r"parameter 'T' needs finite bounds .* or an initial value"),
        (dict(bounds={"K": (7, 0), "T": (0, 7)}), r"bounds\['K'\]: need low < high"),
        (dict(initial={"K": 9.0}), r"initial\['K'\] = 9.0 lies outside its bounds"),
        (dict(initial={"gain": 1.0}), r"initial names unknown parameters \['gain'\]"),
        (dict(fixed={"K": 2.0, "T": 3.0}), "nothing is left to fit"),
        (dict(fixed={"K": 2.0}, initial={"K": 2.0}), "either fitted or fixed"),
        (dict(segments=[(185, 195)]), r"segments\[0\] = \(185, 195\) has no measured output"),
        (dict(offset="mean"), "offset must be one of"),
        (dict(x0="rest"), "x0 must be one of"),
        (dict(dt=0), "dt must be a finite number > 0"),
        (dict(warmup=-1), "warmup must be at least 0"),
        (dict(bounds={"K": (0, np.inf), "T": (0, 7)}, initial={"K": 1.0}, n_starts=3), "must then be finite"),
    ],
)
def test_bad_fit_arguments(kwargs, message):
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    y[180:] = np.nan
    arguments = dict(segments=[(15, 60)], bounds=FIRST_ORDER_BOUNDS) | kwargs
    segments = arguments.pop("segments")
    with pytest.raises(ValueError, match=message):
        fit_segments(u, y, FirstOrder(), segments, **arguments)


def test_bad_fit_types():
    u = steps_input()
    with pytest.raises(ModelError, match="model must be a dynia.models.Model"):
        fit_segments(u, u, "first-order", [(0, 10)], bounds=FIRST_ORDER_BOUNDS)
    with pytest.raises(ValueError, match="u has 200 samples but y has 10"):
        fit_segments(u, u[:10], FirstOrder(), [(0, 10)], bounds=FIRST_ORDER_BOUNDS)


def test_a_model_that_cannot_simulate_the_parameters_is_named():
    u = steps_input()
    y = FOPDT().simulate([[1.5, 4.0, 2.0]], u)[0]
    with pytest.raises(ValueError, match=r"FOPDT cannot simulate the parameters .*theta must be >= 0"):
        fit_segments(u, y, FOPDT(), [(10, 80)], bounds={"K": (0, 5), "T": (0, 10), "theta": (-4, 2)})


# ----------------------------------------------------------- validation


def test_validation_error_of_the_true_model_is_the_noise_on_the_held_out_part():
    u = np.tile(steps_input(), 8)
    clean = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    noise = np.random.default_rng(8).normal(0, 0.2, u.size)
    y = clean + noise
    fit_part, held_out = holdout_split(u.size)
    ((start, stop),) = held_out
    truth = validation_error(u, y, FirstOrder(), {"K": 2.0, "T": 3.0}, held_out)
    assert truth == pytest.approx(np.sqrt(np.mean(noise[start:stop] ** 2)), rel=1e-12)
    assert truth == pytest.approx(0.2, rel=0.1)  # 480 points: 3 standard deviations
    # the same with a mask, and for a fit that never saw the held-out output
    y_fit = np.where(segments_to_mask(held_out, u.size), np.nan, y)
    fit = fit_segments(u, y_fit, FirstOrder(), fit_part, bounds=FIRST_ORDER_BOUNDS)
    assert fit.n_points == start
    error = fit.validation_error(u, y, segments_to_mask(held_out, u.size))
    assert error == pytest.approx(truth, rel=0.01)


def test_simulate_reproduces_the_fitted_output():
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    fit = fit_segments(u, y, FirstOrder(), [(15, 60), (130, 170)], bounds=FIRST_ORDER_BOUNDS, warmup=25)
    on_segments = fit.simulate(u, fit.segments)
    inside = segments_to_mask(fit.segments, u.size)
    assert np.array_equal(on_segments[inside], fit.fitted[inside]) and np.isnan(on_segments[~inside]).all()
    assert np.allclose(fit.simulate(u), y, atol=1e-6)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(parameters={"K": 2.0}), r"parameters lacks \['T'\]"),
        (dict(segments=[(0, 300)]), "is not a segment"),
        (dict(segments=np.zeros(10, dtype=bool)), r"mask must have shape \(200,\)"),
        (dict(segments=[(185, 195)]), "hold no measured output"),
    ],
)
def test_bad_validation_arguments(kwargs, message):
    u = steps_input()
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    y[180:] = np.nan
    arguments = dict(parameters={"K": 2.0, "T": 3.0}, segments=[(0, 50)]) | kwargs
    with pytest.raises(ValueError, match=message):
        validation_error(u, y, FirstOrder(), arguments["parameters"], arguments["segments"])
