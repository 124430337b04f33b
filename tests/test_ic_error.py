"""The Monte Carlo error of IC and limits (ic_error, target_se): exact, honest, and bounded in cost."""

import warnings

import numpy as np
import pytest
from conftest import compiled_window_costs

import dynia
import dynia.distributed
from benchmarks.honesty import ic_error_honesty
from dynia.engine.flavours import monte_carlo_errors
from dynia.engine.windows import moving_window, window_costs
from dynia.errors import SettingsError
from dynia.pipeline import TargetNotReachedWarning, ic_se_that_matters
from dynia.settings import ic_batches

# The bar: over 20 seeds, the median predicted error and the median
# seed-to-seed spread agree within this factor, either way.
HONEST_FACTOR = 1.5


@pytest.mark.parametrize(
    "number, percentage, n_samples",
    # 0.1 % needs 50 000 samples for 10 batches of 5 behavioural sets each.
    [(1, 10, 2000), (1, 0.1, 50_000), (2, 10, 2000), (2, 0.1, 50_000)],
)
def test_predicted_error_matches_the_spread_over_twenty_seeds(number, percentage, n_samples):
    check = ic_error_honesty(number, percentage, n_samples, seeds=20)
    for name, ratio in zip(check.names, check.ratio):
        assert 1 / HONEST_FACTOR <= ratio <= HONEST_FACTOR, (name, ratio)


@pytest.mark.parametrize("flavour", ["thesis", "weighted"])
def test_both_engines_give_the_same_errors_and_leave_the_estimates_alone(example1, flavour):
    y, sims, params, bounds = example1["y"], example1["sims"], example1["params"], example1["bounds"]
    results = {}
    for engine in ("numba", "numpy"):
        plain = moving_window(y, sims, params, bounds, flavour=flavour, engine=engine)
        results[engine] = moving_window(y, sims, params, bounds, flavour=flavour, engine=engine, ic_error=True)
        for name in ("ic", "ci", "median", "gradient"):  # the same engine with and without: exact
            np.testing.assert_array_equal(getattr(results[engine], name), getattr(plain, name))
    compiled, numpy_path = results["numba"], results["numpy"]
    # Across engines, the contract of tests/test_fast.py: the batches' estimates are identical wherever every
    # batch keeps its behavioural set (98 % of example 1's windows; the rest lie among its tail's near-ties).
    batches = compiled.run.ic_batches
    costs, reference = compiled_window_costs(y, sims, 10), window_costs(y, sims, 10, 0, y.size)
    kept = np.ones(y.size, dtype=bool)
    for b in range(batches):
        count = int(len(range(b, params.shape[0], batches)) * 0.1)
        for t in range(y.size):
            ours = np.sort(np.argsort(costs[t, b::batches], kind="stable")[:count])
            theirs = np.sort(np.argsort(reference[t, b::batches], kind="stable")[:count])
            kept[t] &= np.array_equal(ours, theirs)
    assert kept.mean() >= 0.97
    np.testing.assert_array_equal(compiled.ic_se[:, kept], numpy_path.ic_se[:, kept])
    np.testing.assert_array_equal(compiled.ci_se[:, kept], numpy_path.ci_se[:, kept])
    assert compiled.run.ic_batches == 10
    assert np.isfinite(compiled.ic_se).all() and (compiled.ic_se >= 0).all()


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_every_batch_is_its_samples_analysed_alone(example1, engine):
    """The standard error is computed from exactly these batch estimates (tolerance 0)."""
    y, sims, params, bounds = example1["y"], example1["sims"], example1["params"], example1["bounds"]
    result = moving_window(y, sims, params, bounds, engine=engine, ic_error=True)
    batches = result.run.ic_batches
    alone = [moving_window(y, sims[b::batches], params[b::batches], bounds, engine=engine) for b in range(batches)]
    ic_se, ci_se = monte_carlo_errors(np.stack([r.ic for r in alone]), np.stack([r.ci for r in alone]))
    np.testing.assert_array_equal(result.ic_se, ic_se)
    np.testing.assert_array_equal(result.ci_se, ci_se)


def test_batches_of_a_record_resting_at_zero_are_their_samples_analysed_alone():
    """Windows where every sample ties (each batch's set is then its first members, nothing selected): exact."""
    u = np.r_[np.full(150, 1.0), np.zeros(650)]
    y = dynia.models.FirstOrder().simulate([[2.0, 3.0]], u)[0] + np.random.default_rng(3).normal(0, 0.5, u.size)
    params = np.random.default_rng(4).uniform([0.1, 0.5], [4, 7], (2000, 2))
    sims = dynia.models.FirstOrder().simulate(params, u)
    bounds = [[0, 4], [0, 7]]
    costs = compiled_window_costs(y, sims, 10)
    tied = (costs == costs[:, :1]).all(axis=1)
    assert tied.sum() >= 200  # the shortcut is taken, and not everywhere
    result = moving_window(y, sims, params, bounds, engine="numba", ic_error=True)
    batches = result.run.ic_batches
    alone = [moving_window(y, sims[b::batches], params[b::batches], bounds, engine="numba") for b in range(batches)]
    ic_se, ci_se = monte_carlo_errors(np.stack([r.ic for r in alone]), np.stack([r.ci for r in alone]))
    np.testing.assert_array_equal(result.ic_se, ic_se)
    np.testing.assert_array_equal(result.ci_se, ci_se)


def test_batches_shrink_to_keep_five_behavioural_sets_and_refuse_fewer():
    assert ic_batches(2000, 10) == 10
    assert ic_batches(300, 10) == 6  # 300 // 6 = 50 samples, 5 behavioural
    with pytest.raises(SettingsError, match="raise n_samples or percentage") as error:
        ic_batches(50, 10)
    assert error.value.setting == "ic_error"


def test_mcat_refuses_ic_error(example1):
    with pytest.raises(SettingsError, match="mcat"):
        dynia.run(
            example1["u"],
            example1["y"],
            dynia.models.FirstOrder(),
            {"K": (0, 7), "T": (0, 7)},
            flavour="mcat",
            ic_error=True,
            rng=1,
        )


def test_adaptive_samplers_report_the_error_from_their_weights(example1):
    bounds = {"K": (0.0, 7.0), "T": (0.0, 7.0)}
    options = dict(sampler="iis", n_samples=5000, percentage=2, rng=3)
    plain = dynia.run(example1["u"], example1["y"], dynia.models.FirstOrder(), bounds, **options)
    with_error = dynia.run(example1["u"], example1["y"], dynia.models.FirstOrder(), bounds, ic_error=True, **options)
    np.testing.assert_array_equal(with_error.ic, plain.ic)
    assert with_error.ic_se.shape == plain.ic.shape and np.isfinite(with_error.ic_se).all()
    # The weights matter: the same samples analysed unweighted give other errors.
    unweighted = moving_window(
        example1["y"],
        dynia.models.FirstOrder().simulate(with_error.samples, example1["u"]),
        with_error.samples,
        with_error.bounds,
        percentage=2,
        ic_error=True,
        engine="numpy",
    )
    assert not np.array_equal(unweighted.ic_se, with_error.ic_se)


def _example(rng=4):
    example = dynia.synthetic.thesis_example(1, rng)
    return example.u, example.y, example.model, example.bounds


def test_target_se_keeps_every_earlier_sample_and_stops_at_the_target():
    u, y, model, bounds = _example()
    target = 0.03
    reached = dynia.run(u, y, model, bounds, n_samples=500, target_se=target, max_samples=20_000, rng=7)
    rounds = reached.run.target_se_rounds
    assert len(rounds) >= 2 and rounds[0][0] == 500
    assert [count for count, _ in rounds] == sorted(count for count, _ in rounds)
    assert reached.run.target_se_met and reached.run.target_se_reached <= target
    assert ic_se_that_matters(reached) == reached.run.target_se_reached
    # The samples are those a single run of the final count draws: the same analysis, bit for bit.
    single = dynia.run(u, y, model, bounds, n_samples=reached.samples.shape[0], ic_error=True, rng=7)
    np.testing.assert_array_equal(single.samples, reached.samples)
    np.testing.assert_array_equal(single.ic_se, reached.ic_se)


def test_target_se_says_when_the_budget_runs_out():
    u, y, model, bounds = _example()
    with pytest.warns(TargetNotReachedWarning, match="raise max_samples"):
        result = dynia.run(u, y, model, bounds, n_samples=300, target_se=0.001, max_samples=600, rng=7)
    assert not result.run.target_se_met
    assert result.samples.shape[0] == 600
    assert result.run.target_se_reached > 0.001


@pytest.mark.parametrize(
    "options, setting",
    [
        (dict(target_se=0.02), "target_se"),
        (dict(max_samples=5000), "max_samples"),
        (dict(target_se=0.02, max_samples=5000, sampler="lhs"), "target_se"),
        (dict(target_se=1.5, max_samples=5000), "target_se"),
        (dict(target_se=0.02, max_samples=100), "max_samples"),
        (dict(ic_error="yes"), "ic_error"),
    ],
)
def test_target_settings_are_checked(options, setting):
    u, y, model, bounds = _example()
    with pytest.raises(SettingsError) as error:
        dynia.run(u, y, model, bounds, n_samples=2000, rng=1, **options)
    assert error.value.setting == setting


def test_errors_survive_save_and_load_and_reach_the_table(tmp_path):
    u, y, model, bounds = _example()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = dynia.run(u, y, model, bounds, ic_error=True, rng=2)
    result.save(tmp_path / "r.nc")
    back = dynia.load(tmp_path / "r.nc")
    np.testing.assert_array_equal(back.ic_se, result.ic_se)
    np.testing.assert_array_equal(back.ci_se, result.ci_se)
    table = result.to_dataframe()
    assert {"ic_se", "lower_se", "upper_se"} <= set(table.columns)
    np.testing.assert_array_equal(table["ic_se"].to_numpy(), result.ic_se.ravel())


@pytest.mark.parametrize("setting", [dict(ic_error=True), dict(target_se=0.02, max_samples=5000)])
def test_the_online_front_end_refuses_the_error_instead_of_ignoring_it(setting):
    settings = dynia.settings.AnalysisSettings(window="trailing", **setting)
    with pytest.raises(SettingsError, match="OnlineDynia does not support ic_error=True"):
        dynia.online.OnlineDynia(dynia.models.FirstOrder(), {"K": (0, 7), "T": (0, 7)}, settings=settings)


def test_the_cluster_gives_the_errors_of_dynia_run():
    distributed = pytest.importorskip("distributed")
    u, y, model, bounds = _example()
    with (
        distributed.LocalCluster(n_workers=2, processes=False, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        on_cluster = dynia.distributed.run(
            u, y, model, bounds, client=client, sample_chunks=700, time_chunks=70, ic_error=True, rng=5
        )
        with pytest.raises(SettingsError, match="does not support target_se"):
            settings = dynia.settings.AnalysisSettings(target_se=0.02, max_samples=4000)
            dynia.distributed.run(u, y, model, bounds, client=client, settings=settings, rng=5)
    alone = dynia.run(u, y, model, bounds, ic_error=True, rng=5)
    np.testing.assert_array_equal(on_cluster.ic_se, alone.ic_se)
    np.testing.assert_array_equal(on_cluster.ci_se, alone.ci_se)
    assert on_cluster.run.ic_batches == alone.run.ic_batches


def test_an_ic_within_two_standard_errors_of_the_threshold_is_not_identified():
    from dynia.result import DyniaResult
    from dynia.verdicts import assess

    def result(ic_se):
        # Two windows of evidence, as n = 0 needs (dynia.verdicts.evidence_needed).
        ic = np.array([[0.2, 0.56, 0.55, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3]])
        steps = ic.shape[1]
        return DyniaResult(
            names=("K",),
            samples=np.zeros((1, 1)),
            bounds=np.array([[0.0, 10.0]]),
            time=np.arange(float(steps)),
            ic=ic,
            ci=np.tile([4.0, 6.0], (1, steps, 1)),
            gradient=np.zeros((1, 2, steps)),
            bin_centres=np.zeros((1, 2)),
            settings=dict(n=0),
            ic_se=ic_se,
        )

    uncertain = assess(result(np.full((1, 13), 0.04)))["K"]
    assert uncertain["verdict"] == "suspect"
    assert [reason["code"] for reason in uncertain["reasons"]] == ["monte_carlo_error"]
    assert "0.56 +- 0.04" in uncertain["reasons"][0]["text"]
    assert assess(result(np.full((1, 13), 0.02)))["K"]["verdict"] == "identified"
    assert assess(result(None))["K"]["verdict"] == "identified"
