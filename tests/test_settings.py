"""AnalysisSettings: checked once, strictly typed, and honoured (or refused) by every front-end."""

from pathlib import Path

import numpy as np
import pytest

import dynia
import dynia.distributed
from dynia.adaptive import AdaptiveOptions, adaptive_run
from dynia.errors import DataError, DyniaError, ModelError, OutputError, SettingsError
from dynia.models import FirstOrder
from dynia.online import OnlineDynia
from dynia.settings import MAX_BINS, AnalysisSettings, merged_settings

U = np.r_[np.zeros(20), np.full(60, 1.0)]
Y = FirstOrder().simulate([[2.0, 3.0]], U)[0]
BOUNDS = {"K": (0, 7), "T": (0, 7)}


@pytest.mark.parametrize("error", [DataError, SettingsError, ModelError, OutputError])
def test_every_error_is_a_dynia_error_and_a_value_error(error):
    assert issubclass(error, DyniaError) and issubclass(error, ValueError)


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("percentage", "10", r"percentage must be a finite number; got '10' \(str\)"),
        ("n", 2.5, r"n must be a whole number; got 2.5 \(float\)"),
        ("n_samples", True, r"n_samples must be a whole number; got True \(bool\)"),
        ("conf_level", 0.9, r"conf_level is a percentage in \(50, 100\); got 0.9 \(did you mean 90\?\)"),
        ("conf_level", 50, r"conf_level is a percentage in \(50, 100\); got 50$"),
        ("conf_level", 100, r"conf_level is a percentage in \(50, 100\)"),
        ("bins", MAX_BINS + 1, "bins must be at most 1000"),
        ("min_points", 22, r"min_points 22 is more than a window holds \(2n\+1 = 21"),
        ("workers", 0, "workers must be at least 1"),
        ("flavour", "glue", "flavour must be one of 'thesis', 'mcat', 'weighted'"),
        ("dt", "1", "dt must be a finite number > 0"),
    ],
)
def test_a_bad_setting_is_one_clear_error_naming_it(field, value, message):
    with pytest.raises(SettingsError, match=message) as caught:
        AnalysisSettings(**{field: value})
    assert caught.value.setting == field


@pytest.mark.parametrize(
    "changes, message",
    [
        (dict(sampler="iis", engine="numba"), "which the compiled engine does not take"),
        (dict(sampler="de", flavour="mcat"), "which the mcat flavour cannot use"),
        (dict(engine="numba", flavour="mcat"), "engine 'numba' covers the 'thesis' and 'weighted'"),
        (dict(flavour="mcat", percentage=30), "does not divide 100"),
        (dict(n_samples=15, percentage=10), "keeps 1 parameter sets per window"),
    ],
)
def test_settings_that_cannot_go_together_are_refused(changes, message):
    with pytest.raises(SettingsError, match=message):
        AnalysisSettings(**changes)


def test_build_puts_given_keywords_over_the_object_and_checks_again():
    base = AnalysisSettings(n=5, percentage=5)
    assert AnalysisSettings.build(base, n=None, percentage=20) == AnalysisSettings(n=5, percentage=20)
    assert AnalysisSettings.build(None) == AnalysisSettings()
    with pytest.raises(SettingsError, match="unknown setting"):
        base.replace(window_size=3)
    with pytest.raises(SettingsError, match="settings must be a dynia.settings.AnalysisSettings"):
        AnalysisSettings.build({"n": 5})


def test_the_old_silently_dropped_keywords_now_reach_the_adaptive_run_or_are_refused():
    # dynia.run(sampler="iis", min_points=11, engine="numba", workers=0) used to drop three of them.
    with pytest.raises(SettingsError, match="workers must be at least 1"):
        dynia.run(U, Y, FirstOrder(), BOUNDS, sampler="iis", min_points=11, engine="numba", workers=0)
    with pytest.raises(SettingsError, match="compiled engine"):
        dynia.run(U, Y, FirstOrder(), BOUNDS, sampler="iis", min_points=11, engine="numba")
    res = dynia.run(U, Y, FirstOrder(), BOUNDS, sampler="iis", n_samples=400, n=5, min_points=11, rng=1)
    assert res.settings.min_points == 11 and res.settings.sampler == "iis"
    # min_points 11 of a window of 11: the truncated windows at both ends report nothing.
    assert np.isnan(res.ic[:, :5]).all() and np.isnan(res.ic[:, -5:]).all() and not np.isnan(res.ic[:, 5:-5]).any()


def test_a_settings_object_and_keywords_give_the_same_run():
    settings = AnalysisSettings(n_samples=300, n=4, percentage=20, conf_level=80)
    by_object = dynia.run(U, Y, FirstOrder(), BOUNDS, settings=settings, rng=3)
    by_keywords = dynia.run(U, Y, FirstOrder(), BOUNDS, n_samples=300, n=4, percentage=20, conf_level=80, rng=3)
    assert np.array_equal(by_object.ic, by_keywords.ic) and np.array_equal(by_object.ci, by_keywords.ci)
    assert by_object.settings == by_keywords.settings
    assert by_object.settings.conf_level == 80 and by_object.run.n_sampled == 300


@pytest.mark.parametrize(
    "changes, message",
    [
        (dict(window="centred"), "OnlineDynia does not support window='centred'"),
        (dict(workers=2), "OnlineDynia does not support workers=2"),
        (dict(engine="numba"), "OnlineDynia does not support engine='numba'"),
    ],
)
def test_online_refuses_what_it_cannot_honour(changes, message):
    settings = AnalysisSettings(n_samples=100, window="trailing").replace(**changes)
    with pytest.raises(SettingsError, match=message):
        OnlineDynia(FirstOrder(), BOUNDS, settings=settings)


def test_online_takes_a_settings_object_and_equals_the_batch_run():
    settings = AnalysisSettings(n_samples=300, n=4, window="trailing")
    online = OnlineDynia(FirstOrder(), BOUNDS, settings=settings, rng=2).replay(U, Y)
    batch = dynia.run(U, Y, FirstOrder(), BOUNDS, settings=settings, rng=2)
    assert np.array_equal(online.ic, batch.ic)


def test_a_lag_model_whose_pole_underflows_runs_on_both_engines():
    # T far below dt: exp(-dt/T) is 0 for every sample, so the model has no state term.
    compiled = dynia.run(U, Y, FirstOrder(), {"K": (0, 7), "T": (0, 0.001)}, n_samples=200, n=3, rng=1, engine="numba")
    plain = dynia.run(U, Y, FirstOrder(), {"K": (0, 7), "T": (0, 0.001)}, n_samples=200, n=3, rng=1, engine="numpy")
    assert compiled.settings.engine == "numba"
    assert np.array_equal(compiled.ic, plain.ic, equal_nan=True)
    assert np.array_equal(compiled.ci, plain.ci, equal_nan=True)


@pytest.mark.parametrize(
    "call, needle",
    [
        (lambda: dynia.sampling.sample("uniform", 10**10, [[0.0, 1.0]], 1), "n_samples must be at most 100 000 000"),
        (lambda: dynia.sampling.sample("sobol", 2.5, [[0.0, 1.0]], 1), "n_samples must be a whole number"),
        (
            lambda: dynia.fit.fit_segments(
                [0.0] * 20, [0.0] * 20, dynia.models.FirstOrder(), [(0, 20)], n_starts=10**10
            ),
            "n_starts must be at most 10 000",
        ),
        (
            lambda: dynia.suggest(
                [0.0] * 50, [0.0] * 50, dynia.models.FirstOrder(), {"K": (0, 1), "T": (0, 1)}, max_samples=10**12
            ),
            "max_samples must be at most 100 000 000",
        ),
    ],
)
def test_every_count_has_a_bound_and_a_reason(call, needle):
    """Issue 32: a count typed 1e10 for 1e4 is one line naming it, not an allocation that fails or runs for hours."""
    with pytest.raises(SettingsError, match=needle) as refused:
        call()
    assert refused.value.setting == needle.split()[0]


# The front-ends that take their settings as settings= and **overrides, each called on U, Y with FirstOrder.
FRONT_ENDS = {
    "identify": lambda **keywords: dynia.identify(U, Y, FirstOrder(), BOUNDS, **keywords),
    "adaptive_run": lambda **keywords: adaptive_run(U, Y, FirstOrder(), BOUNDS, **keywords),
    "distributed.run": lambda **keywords: dynia.distributed.run(U, Y, FirstOrder(), BOUNDS, **keywords),
    "OnlineDynia": lambda **keywords: OnlineDynia(FirstOrder(), BOUNDS, **keywords),
}


@pytest.mark.parametrize("front_end", FRONT_ENDS)
def test_an_unknown_keyword_is_a_settings_error_naming_it_with_the_closest_names_and_the_list(front_end):
    # distributed.run checks its keywords before it looks for a cluster.
    with pytest.raises(SettingsError, match=r"takes no keyword 'windw' \(did you mean 'window'\?\); ") as caught:
        FRONT_ENDS[front_end](windw="trailing", n=3)
    assert caught.value.setting == "windw"
    assert "bins, conf_level, dt, dtype, engine, flavour, ic_error, max_samples, min_points, n, n_samples" in str(
        caught.value
    )


def test_an_unknown_keyword_is_matched_against_the_front_ends_own_arguments_and_options_too():
    with pytest.raises(SettingsError, match=r"'n_start' \(did you mean 'n_starts'"):
        dynia.identify(U, Y, FirstOrder(), BOUNDS, n_start=3)
    with pytest.raises(SettingsError, match=r"'hold_out' \(did you mean 'held_out'"):
        dynia.identify(U, Y, FirstOrder(), BOUNDS, hold_out=0.2)
    with pytest.raises(SettingsError, match=r"takes no keyword 'stage' \(did you mean 'stages'"):
        adaptive_run(U, Y, FirstOrder(), BOUNDS, stage=2)
    with pytest.raises(SettingsError, match="options must be a dynia.adaptive.AdaptiveOptions; got dict"):
        adaptive_run(U, Y, FirstOrder(), BOUNDS, options={"stages": 2})


def test_no_local_variable_of_a_front_end_becomes_a_setting():
    """Issue 33: the front-ends merged locals(), so any local named like a setting (n, window, engine) became one."""
    package = Path(dynia.__file__).parent
    assert not [str(path) for path in package.rglob("*.py") if "locals()" in path.read_text()]

    def front_end(u, *, settings=None, **overrides):
        window = "centred"  # a local named like a setting, as the front-ends have (n, engine, quality...)
        return merged_settings(settings, overrides, front_end=front_end), window

    assert front_end([1.0], n=3)[0] == AnalysisSettings(n=3, dt=1.0)
    # The merge takes settings by name, never a namespace to pick setting-named variables from: locals() holds the
    # arguments (u, model, ...), which are no settings.
    with pytest.raises(SettingsError, match="takes no keyword 'u'"):
        merged_settings(None, dict(u=[1.0], window="trailing"), front_end=front_end)


SETTINGS = AnalysisSettings(n_samples=400, n=5, percentage=10, conf_level=80, window="trailing")


def test_dynia_run_takes_a_settings_object_and_keywords_together_and_the_keywords_win():
    both = dynia.run(U, Y, FirstOrder(), BOUNDS, settings=SETTINGS, n=3, percentage=20, rng=3)
    merged = dynia.run(U, Y, FirstOrder(), BOUNDS, settings=SETTINGS.replace(n=3, percentage=20), rng=3)
    assert both.settings == merged.settings and np.array_equal(both.ic, merged.ic, equal_nan=True)
    assert (both.settings.n, both.settings.percentage, both.settings.conf_level) == (3, 20, 80)


def test_adaptive_run_takes_settings_options_and_their_keywords_together_and_the_keywords_win():
    settings = SETTINGS.replace(sampler="iis", percentage=5)
    options = AdaptiveOptions(blocks=4, stages=2)
    both = adaptive_run(U, Y, FirstOrder(), BOUNDS, settings=settings, options=options, n=3, blocks=2, rng=3)
    merged = adaptive_run(
        U, Y, FirstOrder(), BOUNDS, settings=settings.replace(n=3), options=AdaptiveOptions(blocks=2, stages=2), rng=3
    )
    assert both.settings == merged.settings and np.array_equal(both.ic, merged.ic, equal_nan=True)
    assert both.settings.n == 3 and both.settings.conf_level == 80 and both.run.n_blocks == 2
    # The scheme is the settings' sampler, and overrides it.
    assert adaptive_run(U, Y, FirstOrder(), BOUNDS, settings=settings, scheme="de", rng=3).settings.sampler == "de"


def test_online_takes_a_settings_object_and_keywords_together_and_the_keywords_win():
    both = OnlineDynia(FirstOrder(), BOUNDS, settings=SETTINGS, n=3, percentage=20, rng=2)
    merged = OnlineDynia(FirstOrder(), BOUNDS, settings=SETTINGS.replace(n=3, percentage=20), rng=2)
    assert both.settings == merged.settings and (both.settings.n, both.settings.conf_level) == (3, 80)
    assert np.array_equal(both.replay(U, Y).ic, merged.replay(U, Y).ic, equal_nan=True)
