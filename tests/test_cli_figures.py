"""The command line's figures in the user's terms: column names, units, references and dated time axes."""

import datetime
import json

import matplotlib
import numpy as np
import pytest
import xarray
from cli_cases import HEATING

matplotlib.use("Agg")
from matplotlib import dates  # noqa: E402  (after choosing the backend)
from matplotlib.figure import Figure  # noqa: E402

import dynia  # noqa: E402
from dynia.cli import main  # noqa: E402
from dynia.cli.figures import Labels, plot_data, time_axis  # noqa: E402
from dynia.io.csv import ProcessData  # noqa: E402

ARGS = (
    "--time time --input u --output y --model first-order --param K=0:40 --param T=0:200 "
    "--input-offset 6 --offset first --samples 200 --seed 1"
).split()
START = datetime.datetime(2024, 3, 1, 8, 0)


def _dated_copy(path):
    """The heating record with ISO timestamps from START instead of seconds."""
    lines = HEATING.read_text().splitlines()
    rows = [line.split(",") for line in lines[1:]]
    dated = [f"{(START + datetime.timedelta(seconds=float(t))).isoformat()},{u},{y}" for t, u, y in rows]
    path.write_text("\n".join([lines[0], *dated]) + "\n")
    return path


@pytest.fixture(scope="module")
def dated_run(tmp_path_factory):
    """One analyse and one identify of the dated record with units and references; the figures they saved."""
    folder = tmp_path_factory.mktemp("figures")
    data = _dated_copy(folder / "dated.csv")
    saved, command = {}, []

    def keep(figure, path, **_):
        # The command writes into a staging directory of its own name: the figures are told apart by command.
        saved[f"{command[-1]}/{path.name}"] = figure

    extra = ["--unit", "K=degC/V", "--unit", "y=degC", "--reference", "K=20:calibrated", "--reference", "y=150"]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Figure, "savefig", keep)
        command.append("analysed")
        assert main(["analyse", str(data), *ARGS, *extra, "--out", str(folder / "analysed")]) == 0
        command.append("fitted")
        assert main(["identify", str(data), *ARGS, "--unit", "y=degC", "--out", str(folder / "fitted")]) == 0
    return folder, saved


def test_data_figure_names_each_input_and_the_output_with_units_on_a_date_axis(dated_run):
    _, saved = dated_run
    for figure in (saved["analysed/data.png"], saved["fitted/fit.png"]):
        top, bottom = figure.axes
        # Every signal as measured, the offset the analysis removed named on its axis (the input's was not before).
        assert top.get_ylabel() == "u\nas measured (offset 6)"
        assert bottom.get_ylabel() == "y [degC]\nas measured (offset 129.32)"
        assert bottom.get_xlabel() == "time"
        assert isinstance(bottom.xaxis.get_major_formatter(), dates.ConciseDateFormatter)
        first = dates.num2date(bottom.lines[0].get_xdata()[0]).replace(tzinfo=None)
        assert first == START
        # The output as measured in both figures: the file's first value, not 0 after the offset.
        assert bottom.lines[0].get_ydata()[0] == pytest.approx(129.32)
    reference = saved["analysed/data.png"].axes[1].lines[1]
    assert set(reference.get_ydata()) == {150.0} and reference.get_label() == "reference 150"
    fitted = saved["fitted/fit.png"].axes[1]
    assert fitted.lines[1].get_label() == "fitted model + offset"
    assert np.nanmean(fitted.lines[1].get_ydata()) > 100  # drawn with the offset added back, like the measurement


def test_result_figures_are_dated_and_marked(dated_run):
    folder, saved = dated_run
    summary = json.loads((folder / "analysed" / "summary.json").read_text())
    assert summary["settings"]["units"] == {"K": "degC/V", "y": "degC"}
    assert summary["settings"]["references"]["K"] == {"value": 20.0, "label": "calibrated"}
    # result.nc carries them too (it did not): JSON attributes beside the result, which dynia.load leaves alone.
    attributes = xarray.open_dataset(folder / "analysed" / "result.nc").attrs
    assert json.loads(attributes["units"]) == summary["settings"]["units"]
    assert json.loads(attributes["references"]) == summary["settings"]["references"]
    assert dynia.load(folder / "analysed" / "result.nc").names == ("K", "T")
    entry = summary["parameters"]["K"]
    when = dates.date2num(datetime.datetime.fromisoformat(entry["time_of_max_ic"]))
    ic = saved["analysed/ic_K.png"].axes[0]
    assert isinstance(ic.xaxis.get_major_formatter(), dates.ConciseDateFormatter)
    (marker,) = [line for line in ic.lines if line.get_marker() == "o"]
    assert marker.get_xdata()[0] == pytest.approx(when, abs=1e-9)
    assert [text.get_text() for text in ic.texts] == [entry["verdict"]]
    figure = saved["analysed/identifiability_K.png"]
    ax, colour_bar = figure.axes
    assert ax.get_ylabel() == "K [degC/V]" and colour_bar.get_ylabel() == "CLD gradient"
    (estimate,) = [line for line in ax.lines if line.get_marker() == "D"]
    assert estimate.get_ydata()[0] == pytest.approx(entry["estimate"])
    (reference,) = [line for line in ax.lines if line.get_linestyle() == "--"]
    assert set(reference.get_ydata()) == {20.0} and reference.get_label() == "calibrated 20"
    assert all(line.get_linestyle() != "--" for line in saved["analysed/identifiability_T.png"].axes[0].lines)


def test_a_numeric_record_keeps_seconds_from_the_first_grid_point():
    data = ProcessData(time=np.array([5.0, 7.0, 9.0]), u=np.ones(3), y=np.zeros(3), dt=2.0, start=100.0, notes=())
    x, dated, label = time_axis(data)
    np.testing.assert_array_equal(x, [0.0, 2.0, 4.0])
    assert not dated and label == "time (s from the first grid point)"
    zoned = ProcessData(
        time=np.array([0.0, 60.0]),
        u=np.ones(2),
        y=np.zeros(2),
        dt=60.0,
        start=START.replace(tzinfo=datetime.timezone(datetime.timedelta(hours=-3, minutes=-30))),
        notes=(),
    )
    x, dated, label = time_axis(zoned)
    assert dated and label == "time (UTC-03:30)"
    assert dates.num2date(x[1]).replace(tzinfo=None) == START + datetime.timedelta(minutes=1)  # the file's clock


def test_two_inputs_get_a_panel_each():
    time = np.arange(100.0)
    u = np.column_stack([np.ones(100), 2 * np.ones(100)])
    labels = Labels(inputs=("rain", "PET"), output="q", units={"rain": "mm/d", "q": "mm/d"})
    figure = plot_data(time, u, np.arange(100.0), labels=labels)
    assert [ax.get_ylabel() for ax in figure.axes] == ["rain [mm/d]", "PET", "q [mm/d]"]
    assert [set(ax.lines[0].get_ydata()) for ax in figure.axes[:2]] == [{1.0}, {2.0}]
    matplotlib.pyplot.close(figure)


@pytest.mark.parametrize(
    "extra, message",
    [
        (
            ["--unit", "Q=m"],
            "dynia: error: --unit Q: not a parameter or column of this run; expected one of K, T, u, y",
        ),
        (["--unit", "K"], "dynia: error: --unit 'K': expected NAME=UNIT"),
        (["--unit", "K=s", "--unit", "K=h"], "dynia: error: --unit K is given twice"),
        (["--reference", "x=1"], "dynia: error: --reference x: not a parameter or column of this run"),
        (["--reference", "K=abc:old"], "dynia: error: --reference 'K=abc:old': expected NAME=VALUE[:LABEL]"),
    ],
)
def test_unknown_or_malformed_units_and_references_are_one_line_errors(tmp_path, capsys, extra, message):
    status = main(["analyse", str(HEATING), *ARGS, *extra, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2 and err.startswith(message) and err.count("\n") == 1
    assert not (tmp_path / "out").exists()
