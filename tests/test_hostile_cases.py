"""Issue 20's hostile cases on the command line, the data loader, the output directory, the settings and pandas.

Each test is one case of the review and failed before the fix: a data loss, a crash, a silent wrong result or a
poor message. An error must be exactly one ``dynia: error:`` line naming the option or column at fault, with no
traceback and no user file touched. Model and engine cases are in ``test_hostile_engine.py``.
"""

import json
import subprocess
import sys

import numpy as np
import pytest
from cli_cases import (
    BASE,
    GOOD,
    cli_analyse,
    cli_one_error,
    cli_succeeded,
    tree_state,
    write_text_file,
)

import dynia
import dynia.cli
from dynia.errors import DataError, SettingsError
from dynia.io.csv import load_csv
from dynia.io.frames import unpack
from dynia.io.outdir import MARKER
from dynia.models import FirstOrder
from dynia.settings import AnalysisSettings

# The data and model options of BASE, without the method options that dynia suggest does not take.
DATA_AND_MODEL = "--time time --input u --output y --model first-order --param K=0:5 --param T=0:5".split()


@pytest.fixture
def good(tmp_path):
    return write_text_file(tmp_path / "data.csv", GOOD)


@pytest.fixture
def never_analysed(monkeypatch):
    """Fail the test if the data loading or the analysis starts: errors must come first."""

    def refuse(*args, **kwargs):
        raise AssertionError("the command went on although it should have stopped before")

    # Reading the data is every command's first work: the analysis cannot start without it.
    monkeypatch.setattr("dynia.cli.common.load_csv", refuse)


def _model_file(path, side_effect=None):
    """A --model FILE.py returning FirstOrder; on import it writes ``side_effect`` if given."""
    effect = f"pathlib.Path({str(side_effect)!r}).write_text('ran')\n" if side_effect else ""
    return write_text_file(
        path,
        f"import pathlib\n{effect}from dynia.models import FirstOrder\n\n\ndef model():\n    return FirstOrder()\n",
    )


# ------------------------------------------------------------------ data loss


def test_overwrite_never_deletes_the_model_file_the_run_imports(tmp_path, capsys, good):
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--out", out))
    # The model kept with the results it made: the run reads it, so --out may not replace it.
    model = _model_file(out / "mymodel.py")
    options = [option if option != "first-order" else f"{model}:model" for option in BASE]
    before = tree_state(tmp_path)
    cli_one_error(*cli_analyse(capsys, good, *options, "--out", out, "--overwrite"), "--out", "mymodel.py")
    assert tree_state(tmp_path) == before


def test_a_model_module_is_a_protected_input_too(tmp_path, capsys, good, monkeypatch):
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--out", out))
    _model_file(out / "plantmodel.py")
    monkeypatch.chdir(out.parent)
    monkeypatch.syspath_prepend(str(out))  # the module is found on the path, MODULE:NAME
    options = [option if option != "first-order" else "plantmodel:model" for option in BASE]
    before = tree_state(out)
    cli_one_error(*cli_analyse(capsys, good, *options, "--out", out, "--overwrite"), "--out", "plantmodel.py")
    assert tree_state(out) == before


@pytest.mark.parametrize(
    "marker",
    [
        json.dumps({"created_by": "dynia"}),  # one echoed line
        json.dumps({"created_by": "dynia", "files": {"ic.csv": 10}, "directories": []}),  # lists other files only
    ],
)
def test_overwrite_refuses_files_dynia_did_not_write_and_names_them(tmp_path, capsys, good, never_analysed, marker):
    mine = tmp_path / "mine"
    mine.mkdir()
    write_text_file(mine / "thesis.tex", "\\chapter{Results}\n")
    write_text_file(mine / MARKER, marker)
    before = tree_state(tmp_path)
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", mine, "--overwrite"), "--out", "thesis.tex")
    assert tree_state(tmp_path) == before


def test_overwrite_refuses_a_result_file_changed_since(tmp_path, capsys, good):
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--out", out))
    with open(out / "summary.json", "a") as summary:
        summary.write("\n% my notes on this run\n")
    before = tree_state(out)
    cli_one_error(*cli_analyse(capsys, good, *BASE, "--out", out, "--overwrite"), "summary.json")
    assert tree_state(out) == before


def test_the_marker_records_what_dynia_wrote_and_overwrite_replaces_it(tmp_path, capsys, good):
    out = tmp_path / "results"
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--out", out))
    record = json.loads((out / MARKER).read_text())
    written = {str(path.relative_to(out)) for path in out.rglob("*") if path.is_file() and path.name != MARKER}
    assert set(record["files"]) == written and "ic.csv" in written
    assert all(record["files"][name] == (out / name).stat().st_size for name in written)
    cli_succeeded(*cli_analyse(capsys, good, *BASE, "--seed", "7", "--out", out, "--overwrite"))
    assert json.loads((out / "summary.json").read_text())["settings"]["seed"] == 7


# ------------------------------------------------------------------ crashes: unchecked integers


@pytest.mark.parametrize("where", ["command line", "config"])
def test_a_negative_seed_is_one_line_before_the_data_are_read(tmp_path, capsys, good, never_analysed, where):
    if where == "config":
        config = write_text_file(tmp_path / "run.toml", "seed = -5\n")
        options = [option for option in BASE if option not in ("--seed", "2")] + ["--config", config]
    else:
        options = [*BASE, "--seed", "-5"]
    cli_one_error(*cli_analyse(capsys, good, *options, "--out", tmp_path / "out"), "--seed", "-5")


@pytest.mark.parametrize(
    "key, value, option",
    [
        ("samples", 9223372036854775807, "--samples"),
        ("n", 9223372036854775807, "--n"),
        ("max_samples", 9223372036854775807, "--max-samples"),
    ],
)
def test_a_huge_whole_number_in_a_config_is_one_line(tmp_path, capsys, good, never_analysed, key, value, option):
    text = f"{key} = {value}\n" + ("target_se = 0.05\n" if key == "max_samples" else "")
    config = write_text_file(tmp_path / "run.toml", text)
    options = [word for word in BASE if word not in ("--samples", "100", "--n", "3")]
    cli_one_error(*cli_analyse(capsys, good, *options, "--config", config, "--out", tmp_path / "out"), option)


@pytest.mark.parametrize(
    "setting, value",
    [
        # One past dynia.settings.MAX_SAMPLES, MAX_HALF_WINDOW, MAX_WORKERS.
        ("n_samples", 100_000_001),
        ("n", 100_000_001),
        ("workers", 1025),
        ("max_samples", 100_000_001),
        ("n_samples", 2**63 - 1),
    ],
)
def test_every_whole_number_setting_has_an_upper_end(setting, value):
    extra = {"target_se": 0.05} if setting == "max_samples" else {}
    with pytest.raises(SettingsError, match=rf"^{setting} must be at most") as caught:
        AnalysisSettings(**{setting: value}, **extra)
    assert caught.value.setting == setting


def test_a_window_longer_than_the_record_is_refused_by_run():
    u = np.r_[np.zeros(20), np.ones(60)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    refused = r"^the record has 80 step\(s\), fewer than one window of 2n\+1 = 161"
    with pytest.raises(SettingsError, match=refused) as caught:
        dynia.run(u, y, FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n=80, rng=1)
    assert caught.value.setting == "n"


# ------------------------------------------------------------------ silent wrong results: pandas indexes

pd = pytest.importorskip("pandas")


def _record(steps=60):
    u = np.r_[np.zeros(10), np.ones(steps - 10)]
    return u, FirstOrder().simulate([[2.0, 3.0]], u)[0]


def test_float_indexes_of_seconds_shifted_between_u_and_y_are_refused():
    u, y = _record()
    seconds = np.arange(u.size, dtype=float)
    with pytest.raises(DataError, match=r"^u and y must share one index, or their values would be paired by position"):
        dynia.run(pd.Series(u, seconds), pd.Series(y, seconds + 100), FirstOrder(), {"K": (0, 7), "T": (0, 7)})


def test_reversed_labels_are_refused():
    u, y = _record()
    labels = np.arange(u.size)
    with pytest.raises(DataError, match=r"^u and y must share one index"):
        unpack(pd.Series(u, labels), pd.Series(y, labels[::-1]))
    with pytest.raises(DataError, match=r"must strictly increase"):  # both reversed: the time runs backwards
        unpack(pd.Series(u, labels[::-1]), pd.Series(y, labels[::-1]))


@pytest.mark.parametrize(
    "index",
    [
        pd.Index(np.arange(60) * 0.5),  # a float index of seconds
        pd.timedelta_range(0, periods=60, freq="500ms"),
    ],
    ids=["seconds", "timedelta"],
)
def test_a_timedelta_or_seconds_index_gives_dt(index):
    u, y = _record()
    _, _, dt, stamps = unpack(pd.Series(u, index), pd.Series(y, index))
    assert dt == 0.5 and stamps is None
    result = dynia.run(
        pd.Series(u, index), pd.Series(y, index), FirstOrder(), {"K": (0, 7), "T": (0, 7)}, n=5, n_samples=200, rng=1
    )
    assert result.settings.dt == 0.5


def test_a_numeric_index_disagreeing_with_dt_says_how_to_give_it():
    u, y = _record()
    samples = pd.Index(np.arange(u.size) + 1000)
    with pytest.raises(SettingsError, match=r"dt = 60 s disagrees .* reset_index\(drop=True\)"):
        unpack(pd.Series(u, samples), pd.Series(y, samples), dt=60)


def test_an_irregular_numeric_index_is_refused():
    u, y = np.ones(5), np.ones(5)
    index = pd.Index([0.0, 1.0, 2.0, 5.0, 6.0])
    with pytest.raises(DataError, match=r"^the index of u and y \(read as time in seconds\) is not uniformly spaced"):
        unpack(pd.Series(u, index), pd.Series(y, index))


# ------------------------------------------------------------------ poor messages: files


@pytest.mark.parametrize(
    "content, needle",
    [
        (bytes(range(256)) * 8, "expected a CSV text file"),
        (b"\x89PNG\r\n\x1a\n" + b"\x00" * 64, "holds the control character"),
        (GOOD.encode("utf-16-le"), "UTF-16 text without a byte order mark"),
    ],
    ids=["binary", "png", "utf16-without-bom"],
)
def test_a_file_that_is_no_text_is_named_as_such(tmp_path, capsys, content, needle):
    path = tmp_path / "data.csv"
    path.write_bytes(content)
    with pytest.raises(DataError, match=needle):
        load_csv(path, time="time", input="u", output="y")
    cli_one_error(*cli_analyse(capsys, path, *BASE, "--out", tmp_path / "out"), "data.csv", needle)


def test_utf16_with_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "data.csv"
    path.write_bytes(GOOD.replace(",", "\t").encode("utf-16"))  # Excel's "Unicode text"
    data = load_csv(path, time="time", input="u", output="y")
    plain = load_csv(write_text_file(tmp_path / "plain.csv", GOOD), time="time", input="u", output="y")
    assert np.array_equal(data.u, plain.u) and np.array_equal(data.y, plain.y)
    assert any("UTF-16" in note for note in data.notes)


@pytest.mark.parametrize(
    "text, needle",
    [
        (
            "time;u;y\n0;0,5;1\n1;0,5;1\n2;1;2\n",
            r"column 'u': '0,5' is not a number \(decimals need a point, not a comma: 0\.5\); export the CSV with '\.'",
        ),
        ("time;u;y\n0,5;1;1\n1,5;1;1\n2,5;1;2\n", r"column 'time': '0,5' .* \(decimals need a point"),
        (
            "time,u,y\n0,0,5,1\n1,1,5,2\n",
            r"row 2 has 4 cells .*\(a decimal comma in a comma-separated file .*: export the CSV with '\.'",
        ),
    ],
    ids=["value", "time", "split"],
)
def test_decimal_commas_are_named(tmp_path, capsys, text, needle):
    path = write_text_file(tmp_path / "data.csv", text)
    with pytest.raises(DataError, match=needle):
        load_csv(path, time="time", input="u", output="y")


def test_a_time_column_of_other_dates_is_read_with_time_format(tmp_path, capsys):
    rows = "".join(
        f"{day:02d}.01.2012 00:00,{1.0 if day > 5 else 0.0},{2.0 if day > 6 else 0.0}\n" for day in range(1, 31)
    )
    path = write_text_file(tmp_path / "days.csv", "time,u,y\n" + rows)
    with pytest.raises(DataError, match=r"'01\.01\.2012 00:00' is neither .* --time-format"):
        load_csv(path, time="time", input="u", output="y")
    data = load_csv(path, time="time", input="u", output="y", time_format="%d.%m.%Y %H:%M")
    assert data.dt == 86400.0 and data.start.isoformat() == "2012-01-01T00:00:00"
    with pytest.raises(DataError, match=r"row 2, column 'time': '01\.01\.2012 00:00' does not match .* '%Y-%m-%d'"):
        load_csv(path, time="time", input="u", output="y", time_format="%Y-%m-%d")
    out = tmp_path / "out"
    cli_succeeded(*cli_analyse(capsys, path, *BASE, "--time-format", "%d.%m.%Y %H:%M", "--out", out))
    assert json.loads((out / "summary.json").read_text())["data"]["dt"] == 86400.0


def test_the_duplicate_timestamp_error_points_at_duplicates_mean(tmp_path):
    path = write_text_file(tmp_path / "data.csv", "time,u,y\n0,1,2\n1,1,2\n1,1,3\n2,1,2\n")
    with pytest.raises(DataError, match=r"duplicate timestamp .* --duplicates mean"):
        load_csv(path, time="time", input="u", output="y")


@pytest.mark.parametrize("argument", ["time", "input", "output"])
def test_load_csv_without_a_column_name_is_a_settings_error(tmp_path, argument):
    names = dict(time="time", input="u", output="y") | {argument: None}
    with pytest.raises(SettingsError, match=rf"^{argument} must be the name of the {argument} column \(a str\)"):
        load_csv(write_text_file(tmp_path / "data.csv", GOOD), **names)


@pytest.mark.parametrize("argument", ["input", "output"])
def test_the_time_column_is_no_signal(tmp_path, capsys, never_analysed, argument):
    names = dict(time="time", input="u", output="y") | {argument: "time"}
    path = write_text_file(tmp_path / "data.csv", GOOD)
    with pytest.raises(SettingsError, match=rf"^{argument} names the time column 'time'"):
        load_csv(path, **names)
    options = list(BASE)
    options[options.index(f"--{argument}") + 1] = "time"
    cli_one_error(*cli_analyse(capsys, path, *options, "--out", tmp_path / "out"), f"--{argument}", "time column")


# ------------------------------------------------------------------ poor messages: options


@pytest.mark.parametrize(
    "param, needle",
    [
        ("T=-5:-1", "--param T=-5:-1: T ranges over (-5, -1), which reaches T = -3, where FirstOrder refuses it"),
        ("T=-1:5", "--param T=-1:5: T ranges over (-1, 5), which reaches T = -1, where FirstOrder refuses it"),
        ("K=0:inf", "--param K=0:inf: expected finite bounds"),
        ("K=nan:1", "--param K=nan:1: expected finite bounds"),
    ],
)
def test_param_ranges_the_model_cannot_take_are_one_line(tmp_path, capsys, good, never_analysed, param, needle):
    name = param.split("=")[0]
    options = [param if word.startswith(f"{name}=") else word for word in BASE]
    cli_one_error(*cli_analyse(capsys, good, *options, "--out", tmp_path / "out"), needle)


def test_held_out_leaving_no_window_blames_held_out(tmp_path, capsys, good):
    _, _, err = _run_identify(capsys, good, *BASE, "--held-out", "0.999", "--out", tmp_path / "out")
    line = cli_one_error(2, "", err, "--held-out 0.999", "leaves 1 of the record's 40 steps")
    assert "threshold" not in line
    assert not (tmp_path / "out").exists()


def _run_identify(capsys, *args):
    status = dynia.cli.main(["identify", *map(str, args)])
    captured = capsys.readouterr()
    assert status == 2, captured.err
    return status, captured.out, captured.err


@pytest.mark.parametrize("window", ["-60s", "-1h"])
def test_a_negative_window_reaches_its_own_check(tmp_path, capsys, good, never_analysed, window):
    options = [word for word in BASE if word not in ("--n", "3")]
    cli_one_error(
        *cli_analyse(capsys, good, *options, "--window", window, "--out", tmp_path / "out"), "--window", window
    )


@pytest.mark.parametrize("option", [["--out", "d"], ["--overwrite"], ["--no-plots"]])
def test_suggest_says_it_writes_nothing(tmp_path, capsys, good, never_analysed, option):
    status = dynia.cli.main(["suggest", str(good), *DATA_AND_MODEL, *option])
    err = capsys.readouterr().err
    cli_one_error(status, "", err, "suggest writes nothing", option[0])


def test_the_model_file_runs_only_after_every_option_is_checked(tmp_path, capsys, good, never_analysed):
    ran = tmp_path / "model-ran"
    model = _model_file(tmp_path / "mymodel.py", side_effect=ran)
    options = [option if option != "first-order" else f"{model}:model" for option in BASE]
    (tmp_path / "taken").mkdir()
    for bad in (
        ["--out", tmp_path / "taken"],  # exists, no --overwrite
        ["--out", tmp_path / "out", "--bins", "5000"],
        ["--out", tmp_path / "out", "--seed", "-1"],
        ["--out", tmp_path / "out", "--window", "1h", "--n", "2"],
        ["--out", tmp_path / "out", "--param", "K=0:1"],  # given twice
    ):
        cli_one_error(*cli_analyse(capsys, good, *options, *bad))
        assert not ran.exists(), bad


def test_the_command_line_entry_point_has_no_traceback_for_a_huge_config_integer(tmp_path, good):
    config = write_text_file(tmp_path / "run.toml", "samples = 9223372036854775807\n")
    options = [word for word in BASE if word not in ("--samples", "100")]
    done = subprocess.run(
        [sys.executable, "-m", "dynia.cli", "analyse", str(good), *options, "--config", str(config), "--out", "o"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=False,
    )
    assert done.returncode == 2 and done.stderr.startswith("dynia: error: --samples must be at most"), done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "o").exists()


@pytest.mark.parametrize("rng", [-5, True, "abc", 1.5])
def test_an_rng_that_cannot_seed_a_generator_is_one_settings_error(rng):
    u = np.r_[np.zeros(20), np.ones(60)]
    y = FirstOrder().simulate([[2.0, 3.0]], u)[0]
    with pytest.raises(SettingsError, match=r"^rng must be None, a whole number >= 0") as caught:
        dynia.run(u, y, FirstOrder(), {"K": (0, 4), "T": (0.5, 6)}, n_samples=100, n=5, rng=rng)
    assert caught.value.setting == "rng"
