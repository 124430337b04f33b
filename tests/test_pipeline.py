"""dynia.run end to end: the thesis's example 1, result objects, bad input."""

import re
import warnings

import matplotlib
import numpy as np
import pytest
from conftest import example_firstorder_input

import dynia
from dynia.models import FirstOrder

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def example1_run():
    u = example_firstorder_input()
    rng = np.random.default_rng(7)
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + rng.normal(0, 0.5, u.size)
    return dynia.run(
        u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=2000, n=10, percentage=10, bins=40, rng=rng
    )


def test_example1_gain_is_identified_while_the_input_is_steady_and_non_zero(example1_run):
    ic = example1_run.ic[example1_run.index("K")]
    steady = np.r_[40:130, 180:320, 350:390]  # 0-based steps away from the input changes
    assert ic[steady].mean() > 0.8
    assert ic[440:490].mean() < 0.5  # the system has settled at zero: nothing tells K apart


def test_example1_time_constant_is_identified_after_the_final_step_to_zero(example1_run):
    ic = example1_run.ic[example1_run.index("T")]
    steady = np.r_[40:130, 180:320, 350:390]
    assert ic[405:440].mean() > 0.6
    assert ic[steady].mean() < 0.3
    lower, upper = example1_run.ci[example1_run.index("T"), 420]
    assert lower <= 3.0 <= upper


def test_result_axes_follow_the_bounds_order():
    u = np.r_[np.zeros(10), np.ones(30)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    forward = dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=200, n=3, rng=4)
    backward = dynia.run(u, y, FirstOrder(), {"T": (0, 7), "K": (0, 7)}, n_samples=200, n=3, rng=4)
    assert forward.names == ("K", "T") and backward.names == ("T", "K")
    # the same draws land in the bounds order, so both runs see the same samples
    np.testing.assert_array_equal(forward.samples, backward.samples)
    assert forward.bounds.tolist() == backward.bounds.tolist() == [[0.0, 7.0], [0.0, 7.0]]
    assert forward.run.model == "FirstOrder" and forward.run.n_sampled == 200


def test_same_seed_same_result_bit_for_bit():
    u = np.r_[np.zeros(10), np.ones(30)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + 0.01
    runs = [
        dynia.run(
            u,
            y,
            FirstOrder(),
            {"K": (0, 7), "T": (0, 7)},
            n_samples=300,
            n=3,
            sampler="lhs",
            rng=np.random.default_rng(11),
        )
        for _ in range(2)
    ]
    np.testing.assert_array_equal(runs[0].ic, runs[1].ic)
    np.testing.assert_array_equal(runs[0].gradient, runs[1].gradient)


@pytest.mark.parametrize("window", ["centred", "trailing"])
def test_run_equals_moving_window_on_the_same_samples(window):
    u = np.r_[np.zeros(10), np.ones(50)]
    y = FirstOrder().simulate([[2.0, 3.0]], u, dt=0.5)[0] + 0.05
    res = dynia.run(u, y, FirstOrder(), {"T": (0, 7), "K": (0, 7)}, dt=0.5, n_samples=400, n=4, rng=2, window=window)
    sims = FirstOrder().simulate(res.samples[:, [1, 0]], u, dt=0.5)
    direct = dynia.moving_window(y, sims, res.samples, res.bounds, n=4, window=window)
    np.testing.assert_array_equal(res.ic, direct.ic)
    np.testing.assert_array_equal(res.gradient, direct.gradient)
    np.testing.assert_array_equal(res.time, np.arange(60) * 0.5)


def test_to_dataframe_and_plots(example1_run):
    table = example1_run.to_dataframe()
    assert list(table.columns) == ["time", "parameter", "ic", "lower", "upper", "median", "informative"]
    assert len(table) == 2 * 500
    row = table[(table.parameter == "T") & (table.time == 420)].iloc[0]
    assert row.ic == example1_run.ic[1, 420]
    ax = example1_run.plot_information_content("K")
    assert ax.get_ylim() == (0, 1)
    ax = example1_run.plot_identifiability("T", true_value=3.0)
    assert ax.get_ylabel() == "T"
    with pytest.raises(ValueError, match="unknown parameter 'tau'"):
        example1_run.plot_identifiability("tau")


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(bounds={"K": (0, 7)}), r"missing: \['T'\]"),
        (dict(bounds={"K": (0, 7), "T": (0, 7), "theta": (0, 1)}), r"unknown: \['theta'\]"),
        (dict(bounds=[(0, 7), (0, 7)]), "bounds must map each parameter name"),
        (dict(bounds={"K": (7, 0), "T": (0, 7)}), r"bounds\['K'\]: need finite low < high"),
        (dict(bounds={"K": "07", "T": (0, 7)}), r"bounds\['K'\] must be a \(low, high\) pair"),
        (dict(u=np.ones(5)), "u has 5 samples but y has 40"),
        (dict(sampler="grid"), "sampler must be one of"),
        (dict(x0="warm"), "x0 must be one of"),
        (dict(n_samples=0), "n_samples must be at least 1"),
    ],
)
def test_bad_input_gets_a_clear_error(change, message):
    args = dict(u=np.ones(40), y=np.ones(40), bounds={"K": (0, 7), "T": (0, 7)})
    args.update(change)
    options = {key: value for key, value in args.items() if key not in ("u", "y", "bounds")}
    with pytest.raises(ValueError, match=message):
        dynia.run(args["u"], args["y"], FirstOrder(), args["bounds"], n=2, **options)


def test_parameter_sets_that_overflow_are_dropped_and_counted():
    import control

    from dynia.models import TransferFunction

    lag = TransferFunction(lambda p: control.tf([p[0]], [1.0, -p[1]]), names=("K", "a"))
    u = np.r_[np.zeros(5), np.ones(60)]
    y = lag.simulate([[1.0, -0.5]], u)[0]
    # a > ~12 overflows within 60 steps; about a third of [-1, 30] does
    with pytest.warns(dynia.pipeline.DroppedSamplesWarning, match=r"were dropped .* not finite"):
        res = dynia.run(u, y, lag, {"K": (0, 2), "a": (-1, 30)}, n_samples=300, n=3, rng=3)
    assert 0 < res.run.n_dropped < 300
    assert res.samples.shape[0] == 300 - res.run.n_dropped
    assert np.isfinite(res.ic).all()
    assert (res.samples[:, 1] < 15).all()


def test_too_few_sets_left_after_overflow_are_refused_saying_how_many_were_asked_and_why():
    """Issue 32: one input value of 1.797e308 left 6 of 500 sets, refused as if 'n_samples 6' had been asked."""
    u = np.r_[np.zeros(5), np.ones(60)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    u[30:] = 1.797e308  # every set with K > 1 overflows: about 70 of 500 are left, too few for 1 %
    with pytest.raises(dynia.ModelError) as refused:
        dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0.1, 7)}, n_samples=500, n=3, percentage=1, rng=1)
    message = str(refused.value)
    assert re.search(r"^\d+ of the 500 parameter sets were dropped because their simulation is not finite", message)
    assert "the input reaches 1.8e+308 in magnitude" in message and "are too few to keep 2 behavioural" in message


def test_summary_reports_the_band_and_estimate_at_the_highest_ic(example1_run):
    summary = example1_run.summary()
    k = example1_run.index("K")
    best = int(np.nanargmax(example1_run.ic[k]))
    assert summary["K"]["max_ic"] == example1_run.ic[k, best]
    assert summary["K"]["time_of_max_ic"] == example1_run.time[best]
    assert summary["K"]["band"] == list(example1_run.ci[k, best])
    assert summary["K"]["band"][0] <= summary["K"]["estimate"] <= summary["K"]["band"][1]
    assert abs(summary["K"]["estimate"] - 2.0) < 0.3


@pytest.mark.parametrize(
    "scale, model_scale, warned",
    [(1.0, 1.0, False), (1e100, 1.0, True), (1.0, 1e-200, True), (1e4, 1.0, True), (20.0, 1.0, False)],
)
def test_a_model_that_cannot_reach_the_outputs_scale_is_named(scale, model_scale, warned):
    """Issue 32: data 1e100 above the model or a model 1e-200 below the data ended in ties without a word why.

    Three decades apart are named; 20 times (l/s against mm/d) is not, since a weak response under noise looks alike.
    """
    u = np.r_[np.zeros(20), np.ones(80), np.zeros(100)]
    y = (FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(0).normal(0, 0.05, u.size)) * scale
    model = dynia.models.FunctionModel(lambda p, u, dt: FirstOrder().simulate(p, u, dt=dt) * model_scale, ["K", "T"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dynia.run(u, y, model, {"K": (0, 7), "T": (0.1, 7)}, n_samples=500, n=5, rng=1)
    named = [item for item in caught if item.category is dynia.pipeline.UnreachedOutputWarning]
    assert bool(named) is warned
    if warned:
        assert "no parameter set in the box reaches the output's size" in str(named[0].message)


def test_a_long_rest_at_zero_is_no_output_out_of_reach():
    """The thesis's example 1, then a rest at zero for 99 % of the record: the corners' 99th percentile was their
    decay in the rest, 1e-98 against the noise's 1.3, and the box that holds the truth was named as out of reach."""
    u = example_firstorder_input(100_000)
    assert np.count_nonzero(u) < 0.01 * u.size
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(1).normal(0, 0.5, u.size)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n_samples=300, rng=1)
    assert not [item for item in caught if item.category is dynia.pipeline.UnreachedOutputWarning]
    assert {name: verdict["verdict"] for name, verdict in result.verdicts.items()} == {
        "K": "identified",
        "T": "identified",
    }


@pytest.mark.parametrize("engine", ["numba", "numpy", "twin"])
@pytest.mark.parametrize("scale, warned", [(1.0, False), (1e4, True)])
def test_the_box_reach_is_judged_alike_on_every_engine(engine, scale, warned):
    """After a run on the kernels the corners are simulated by the kernel (the recursion loops in Python: 4 s for
    200 000 steps); after one on numpy or the twin by the recursion. The verdict on the reach is the same."""
    u = np.r_[np.zeros(20), np.ones(80), np.zeros(100)]
    y = (FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(0).normal(0, 0.05, u.size)) * scale
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0.1, 7)}, n_samples=300, n=5, rng=1, engine=engine)
    assert result.settings.engine == engine
    assert bool([item for item in caught if item.category is dynia.pipeline.UnreachedOutputWarning]) is warned


@pytest.mark.parametrize("scale", [1e-280, 1e-300, 3e-308])
def test_a_record_below_what_the_simulation_resolves_is_refused(scale):
    """Issue 32: at 1e-290 every set tied (K 0.279, T 0.112, weak) without a word; at 1e-280 it still held."""
    u = np.r_[np.zeros(20), np.ones(80)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    with pytest.raises(dynia.DataError, match=r"^u's largest magnitude is .* below 1.2e-271: the simulation sets"):
        dynia.run(u * scale, y * scale, FirstOrder(), {"K": (0, 7), "T": (0.1, 7)}, n_samples=300, rng=1)


def test_a_range_the_model_refuses_is_named_by_its_parameter_before_any_set_is_drawn():
    """Issue 32: the API said 'sample 4 has T = -0.78' where the command line names the range."""
    u = np.r_[np.zeros(20), np.ones(80)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    with pytest.raises(
        dynia.SettingsError, match=r"^T ranges over \(-1, 7\), which reaches T = -1, where FirstOrder"
    ) as refused:
        dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (-1, 7)}, n_samples=300, rng=1)
    assert refused.value.setting == "T" and "sample" not in str(refused.value)


def test_the_reach_of_the_box_follows_the_bounds_order_not_the_models():
    """Bounds given T first: the corners must still put K's range in K's column (a gain up to 1e5 reaches 1e4)."""
    u = np.r_[np.zeros(20), np.ones(80), np.zeros(100)]
    y = FirstOrder().simulate([[1e4, 3.0]], u)[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dynia.run(u, y, FirstOrder(), {"T": (0.1, 7), "K": (0, 1e5)}, n_samples=300, n=5, rng=1)
    assert not [item for item in caught if item.category is dynia.pipeline.UnreachedOutputWarning]
