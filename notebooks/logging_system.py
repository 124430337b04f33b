# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # DYNIA inside the plant's logging system: `dynia follow` on a database (thesis section 4.3)
#
# Section 4.3 of the thesis proposes "to run an instance of the DYNIA method
# that analyze the process data while these data are obtained by the logging
# system": the Monte Carlo sampling is done once, the moving-window
# calculations are done "semi-online" as new data are logged, and the values
# are stored, so that "a database with the time-varying information content is
# readily available when a decision is made to reevaluate the model
# parameters". The notebook `online_replay` shows the calculation
# (`dynia.online.OnlineDynia`, one trailing window per logged sample); this
# one shows the proposal as a plant would run it: the command `dynia follow`
# watching a table of a real database that a logger keeps writing, and
# keeping a results table of IC, band and estimate per step and parameter
# next to it (`dynia.follow.Follower`, `dynia.io.database`).
#
# The plant is the DaISy heating-system record shipped in `data/` (a halogen
# lamp heating a steel plate, one sample every 2 s; see
# `data/heating_system/SOURCE.md`), with the model and settings of the
# README's command-line example and of `online_replay`: a first-order
# deviation model around the operating point (input offset 6 V, output offset
# the first logged temperature, zero initial state), K in [0, 40] degC/V and
# T in [0, 200] s. It is the record whose verdicts change as it grows: its
# lamp voltage moves between levels, and the plate's gain moves with the
# operating point (`online_replay`, and the README's offline analysis), which
# a follower can only see once the log holds operating points that
# contradict each other. The notebook asserts that a verdict changes.
#
# The notebook
#
# 1. makes an SQLite database with a wide table `plant (time REAL, u REAL,
#    y REAL)`, written by a "logger" that knows nothing of dynia (Python's
#    `sqlite3`, one committed row per sample, many times faster than real
#    time);
# 2. after each round of logged rows runs `dynia follow ... --once` as a
#    separate process, as cron would, and reads the results table back;
# 3. in the middle round, runs a follower that does not stop (`--poll`)
#    alongside the logger, kills it with SIGKILL half-way, and starts it
#    again;
# 4. shows the events table (the verdict changes) and the follower's log;
# 5. checks that the results table equals the batch analysis of the same rows.

# %% tags=["parameters"]
data_file: str = "../data/heating_system/heating_system.csv"  # the DaISy record, relative to the working directory
database: str = "plant.db"  # the logger's SQLite file, made afresh in the working directory
rows_per_round: int = 100  # rows the logger writes between two runs of the follower
speedup: float = 200.0  # how many times faster than real time the logger writes (one row every dt / speedup s)
n_samples: int = 2000  # Monte Carlo parameter sets, drawn once by the follower (dynia follow's default)
n: int = 10  # half window: each trailing window holds the 2n+1 newest steps (README example: 10)
gain_high: float = 40.0  # upper bound of the gain K in degC/V (README example: 40)
time_constant_high: float = 200.0  # upper bound of the time constant T in s (README example: 200)
input_offset: float = 6.0  # steady-state input before the experiment, in V (SOURCE.md)
poll_seconds: float = 0.1  # --poll of the follower that runs alongside the logger
batch_rows: int = 5  # --batch of that follower: rows per transaction, the most a kill can make it redo
seed: int = 1  # seed of the follower's Monte Carlo sample (--seed)
figure_dir: str = "figures"  # where the PNGs go

# %%
import json
import os
import re
import signal
import sqlite3
import subprocess
import sys
import time

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import sqlalchemy as sa

import dynia
from dynia.claims import say

os.makedirs(figure_dir, exist_ok=True)

data = dynia.io.csv.load_csv(data_file, time="time", input="u", output="y")
total_rows = data.time.size
for suffix in ("", "-journal", "-wal", "-shm"):
    if os.path.exists(database + suffix):
        os.remove(database + suffix)

# The logger: a plain SQLite program, nothing of dynia or SQLAlchemy; one transaction per logged row. In
# write-ahead-log mode (kept by the file) the follower's reads and the logger's writes do not block each other,
# and a commit waits for no flush to disk (with one, a row per commit would be as slow as the disk).
logger = sqlite3.connect(database, timeout=30)
logger.execute("PRAGMA journal_mode=WAL")
logger.execute("PRAGMA synchronous=NORMAL")
logger.execute("CREATE TABLE plant (time REAL, u REAL, y REAL)")
logged = 0  # rows written so far


def log_rows(stop):
    """Write the record's rows up to ``stop`` (exclusive), one commit each, at ``speedup`` times real time."""
    global logged
    started, first = time.perf_counter(), logged
    while logged < stop:
        with logger:
            logger.execute(
                "INSERT INTO plant (time, u, y) VALUES (?, ?, ?)",
                (float(data.time[logged]), float(data.u[logged]), float(data.y[logged])),
            )
        logged += 1
        time.sleep(max(0.0, started + (logged - first) * data.dt / speedup - time.perf_counter()))
        yield logged


follow_command = [
    sys.executable, "-m", "dynia.cli", "follow", f"sqlite:///{database}",
    "--table", "plant", "--time", "time", "--input", "u", "--output", "y",
    "--model", "first-order", "--param", f"K=0:{gain_high:g}", "--param", f"T=0:{time_constant_high:g}",
    "--input-offset", f"{input_offset:g}", "--offset", "first", "--x0", "zero",
    "--samples", str(n_samples), "--n", str(n), "--seed", str(seed),
]  # fmt: skip
names = ["K", "T"]
results_db = sa.create_engine(f"sqlite:///{database}", connect_args={"timeout": 30})


def read_table(query):
    return pd.read_sql(query, results_db)


def steps_committed():
    """Steps the follower has committed: rows of its steps table (0 before it made it)."""
    with results_db.connect() as connection:
        if not sa.inspect(connection).has_table("dynia_results_steps"):
            return 0
        return connection.execute(sa.text("SELECT count(*) FROM dynia_results_steps")).scalar_one()


def current_verdicts():
    """The newest verdict of each parameter in the events table."""
    events = read_table("SELECT parameter, verdict, reasons FROM dynia_events ORDER BY id")
    newest = events.groupby("parameter").last()
    return {name: (row.verdict, row.reasons) for name, row in newest.iterrows()}


rounds = [(start, min(start + rows_per_round, total_rows)) for start in range(0, total_rows, rows_per_round)]
live_round = len(rounds) // 2  # the middle round: a follower runs alongside the logger there, and is killed
print(f"{total_rows} rows at dt = {data.dt:g} s to log in {len(rounds)} rounds; round {live_round + 1} is the live one")

# %% [markdown]
# ## Rounds of logging, each followed by `dynia follow --once`
#
# Before every round but the middle one, the logger writes its rows; then
# `dynia follow ... --once` starts as a process of its own, reads the rows
# the table gained since its last commit, analyses one trailing window per
# new step, judges the record so far (noise floor and verdicts), commits and
# exits. Every start after the first resumes from the checkpoint the follower
# keeps in its own tables (`dynia_results_state`, `dynia_results_steps`): the
# Monte Carlo sample is drawn once, at the first start, and each later run
# only simulates the new steps. After each round the notebook reads the
# results table back, as a control-room display would.
#
# The middle round is different, and is the subject of the next section.

# %%
snapshots = []  # per round: the results table as read back, and the verdicts
once_logs = []  # the stderr of every `--once` run
round_seconds = []  # wall time of each round's follower run (not checked: machines differ)
trace = []  # the live round: (seconds since the follower started, rows logged, steps committed)


def follow_once():
    started = time.perf_counter()
    done = subprocess.run([*follow_command, "--once"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    once_logs.append(done.stderr)
    return time.perf_counter() - started


def live_round_with_a_kill(start, stop):
    """A follower without --once alongside the logger, killed with SIGKILL once it has committed half the round."""
    before = steps_committed()
    live = subprocess.Popen(
        [*follow_command, "--poll", str(poll_seconds), "--batch", str(batch_rows), "--judge-every", "3600"],
        stderr=subprocess.PIPE,
        text=True,
    )
    first_line = live.stderr.readline()  # "following plant into ...": it has started and is polling
    began = time.perf_counter()
    target = before + (stop - start) // 2
    committed = before
    for rows in log_rows(stop):
        committed = steps_committed()
        trace.append((time.perf_counter() - began, rows, committed))
        if committed >= target:
            break
    while committed < target:  # the logger is done with the round; the follower is still catching up
        assert live.poll() is None, first_line + live.stderr.read()
        time.sleep(0.01)
        committed = steps_committed()
        trace.append((time.perf_counter() - began, logged, committed))
    live.send_signal(signal.SIGKILL)
    live.wait()
    at_kill = dict(
        returncode=live.returncode,
        steps=steps_committed(),
        result_rows=len(read_table("SELECT time FROM dynia_results")),
        rows_logged=logged,
        seconds=time.perf_counter() - began,
        stderr=first_line + live.stderr.read(),
        began=began,
    )
    trace.append((at_kill["seconds"], logged, at_kill["steps"]))
    for rows in log_rows(stop):  # the logger does not care: it goes on writing
        trace.append((time.perf_counter() - began, rows, steps_committed()))
    return at_kill


for number, (start, stop) in enumerate(rounds):
    if number == live_round:
        killed = live_round_with_a_kill(start, stop)
        after_kill = read_table("SELECT time, parameter FROM dynia_results")
    else:
        for _ in log_rows(stop):
            pass
    round_seconds.append(follow_once())
    if number == live_round:
        restarted = time.perf_counter() - killed["began"] - round_seconds[-1]
        trace.append((restarted + round_seconds[-1], logged, steps_committed()))
    snapshots.append(
        dict(
            rows=logged,
            results=read_table("SELECT * FROM dynia_results ORDER BY time, parameter"),
            verdicts=current_verdicts(),
        )
    )

# %% [markdown]
# Every round, the results table held one row per logged sample and
# parameter, and the verdicts after each round were (the live round's count
# is after the restart):

# %%
# NBVAL_CHECK_OUTPUT
for number, snapshot in enumerate(snapshots):
    steps = snapshot["results"].time.nunique()
    verdicts = ", ".join(f"{name} {verdict}" + (f" ({reasons})" if reasons else "") for name, (verdict, reasons)
                         in snapshot["verdicts"].items())
    print(f"round {number + 1}: {snapshot['rows']} rows logged, {steps} steps in the results table; {verdicts}")
assert all(len(s["results"]) == len(names) * s["rows"] for s in snapshots), "a row per logged sample and parameter"

# %% [markdown]
# Time of each `--once` run on this machine (2 cores shared with other
# jobs). Each run starts a Python process and imports dynia before it reads
# a row; a follower that keeps running (next section) pays that once. Not
# checked: timings vary.

# %%
print(f"follower runs: {', '.join(f'{seconds:.1f}' for seconds in round_seconds)} s "
      f"(median {np.median(round_seconds):.1f} s per round of up to {rows_per_round} rows)")

# %% [markdown]
# ## How IC(t) builds up as the data arrive
#
# Each panel is the results table as the notebook read it back after a round
# in which a verdict changed (and after the last round): the information
# content of both parameters over the steps logged so far, and in its title
# the verdicts the follower had written to the events table by then. A
# trailing window holds only steps already logged, so a step's row never
# changes once written (only its `informative` flag may, when a later
# judgement of the record moves the noise floor): each panel extends the one
# before it.

# %%
changed_rounds = [k for k in range(len(snapshots)) if k == 0 or snapshots[k]["verdicts"] != snapshots[k - 1]["verdicts"]]
shown_rounds = sorted(set(changed_rounds) | {len(snapshots) - 1})
colours = {"K": "tab:blue", "T": "tab:red"}
fig, axes = plt.subplots(len(shown_rounds), 1, figsize=(10, 2.2 * len(shown_rounds)), sharex=True, sharey=True,
                         layout="constrained")
for ax, number in zip(np.atleast_1d(axes), shown_rounds):
    snapshot = snapshots[number]
    for name in names:
        rows = snapshot["results"][snapshot["results"].parameter == name]
        ax.plot(rows.time, rows.ic, color=colours[name], linewidth=1, label=f"IC of {name}")
    ax.axvline(data.time[snapshot["rows"] - 1], color="k", linestyle=":", linewidth=1, label="newest logged row")
    verdicts = "; ".join(f"{name}: {verdict}" + (f" ({reasons})" if reasons else "")
                         for name, (verdict, reasons) in snapshot["verdicts"].items())
    ax.set_title(f"after round {number + 1} ({snapshot['rows']} rows logged): {verdicts}", fontsize="medium")
    ax.set_ylabel("IC")
    ax.set_ylim(0, 1.05)
np.atleast_1d(axes)[0].legend(loc="lower right", fontsize="small", ncol=3)
np.atleast_1d(axes)[-1].set_xlabel("time (s)")
np.atleast_1d(axes)[-1].set_xlim(data.time[0], data.time[-1])
fig.suptitle(f"The results table of dynia follow as the log grows (trailing window of {2 * n + 1} samples)")
fig.savefig(f"{figure_dir}/logging_system_rounds.png", dpi=120, bbox_inches="tight")

# %% [markdown]
# ## Killed half-way, started again: no step lost, none doubled
#
# In the middle round the follower runs as it would on a plant: started
# without `--once`, it looks at the table every `--poll` seconds and commits
# a transaction per `--batch` rows, each holding the steps it analysed
# together with the checkpoint that covers them. The logger writes the
# round's rows meanwhile. Once the follower has committed half of them, the
# notebook kills it with SIGKILL, which no program can catch: whatever
# transaction was open is lost. (`--judge-every` is set longer than it
# lives, so that the record is judged only at the ends of rounds, and the
# events below do not depend on how fast this machine is.) The logger goes
# on writing the round's rows, and the next `dynia follow --once` resumes
# from the last commit.

# %%
say(
    f"The live follower was killed after {killed['seconds']:.1f} s with {killed['steps']} steps committed "
    f"({killed['steps'] - rounds[live_round][0]} of the round's {rounds[live_round][1] - rounds[live_round][0]}), "
    f"while the logger had written {killed['rows_logged']} rows. These numbers depend on the machine's speed, "
    "and are not checked. Its log up to the kill:"
)

# %%
print(killed["stderr"])

# %% [markdown]
# The figure traces the live round as the notebook saw it: the rows in the
# plant table, the steps the follower had committed (it commits a
# transaction per `--batch` rows), the kill, after which the logger goes
# on alone, and the restart (`--once`, shaded), at whose end the steps reach
# the round's last row. The times are this run's wall clock.

# %%
fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
seconds, rows_logged, committed = np.array(trace).T
ax.step(seconds, rows_logged, where="post", color="k", label="rows in the plant table (the logger)")
ax.step(seconds, committed, where="post", color="tab:blue", label="steps committed by the follower")
ax.axvline(killed["seconds"], color="tab:red", linestyle="--", label="SIGKILL")
ax.axvspan(restarted, trace[-1][0], color="tab:green", alpha=0.15, label="dynia follow --once, the restart")
ax.axhline(rounds[live_round][1], color="0.6", linestyle=":", label="the round's last row")
ax.set_xlabel("seconds since the live follower started polling (wall time of this run)")
ax.set_ylabel("rows / steps")
ax.set_title(f"Round {live_round + 1}: a follower (--poll {poll_seconds:g} s, --batch {batch_rows}) "
             f"alongside the logger ({speedup:g} x real time)", fontsize="medium")
ax.legend(loc="lower right", fontsize="small")
fig.savefig(f"{figure_dir}/logging_system_kill.png", dpi=120, bbox_inches="tight")

# %% [markdown]
# What the kill left, and what the restart made of it: the steps table and
# the results table agree (the killed transaction left no part of itself),
# the committed steps are the first rows of the log, and after the restart
# every logged row is in the results table exactly once per parameter, the
# times those of the log, in order.

# %%
# NBVAL_CHECK_OUTPUT
final = snapshots[-1]["results"]
per_time = final.groupby("time").parameter.count()
steps_table = read_table("SELECT step, time FROM dynia_results_steps ORDER BY step")
print("killed by SIGKILL:", killed["returncode"] == -signal.SIGKILL)
print("killed half-way through the round:",
      rounds[live_round][0] + (rounds[live_round][1] - rounds[live_round][0]) // 2 <= killed["steps"]
      < rounds[live_round][1])
print("results rows at the kill = parameters x committed steps:", killed["result_rows"] == len(names) * killed["steps"])
print("committed steps are the first logged rows:",
      np.array_equal(np.sort(after_kill.time.unique()), data.time[: killed["steps"]]))
print("after the restart, rows per time:", sorted(set(per_time.tolist())), "for", len(names), "parameters")
print("times are the logged ones, none missing:", np.array_equal(per_time.index.to_numpy(), data.time))
print("steps numbered 0 ..", len(steps_table) - 1, "without a gap:",
      np.array_equal(steps_table.step.to_numpy(), np.arange(total_rows)))

# %% [markdown]
# ## The events table and the follower's log
#
# The follower judges the whole record at the end of every `--once` run (the
# noise floor and the verdicts need the record, not one window), and writes
# a row to `dynia_events` for every parameter whose verdict or reasons
# changed, with the time of the newest step it judged; the same goes to its
# log on stderr as a line of level VERDICT. The events table, without the
# `logged_at` column (the wall-clock time of the run) and the reasons'
# long texts:

# %%
# NBVAL_CHECK_OUTPUT
events = read_table("SELECT * FROM dynia_events ORDER BY id")
print(events[["time", "parameter", "previous", "verdict", "reasons"]].to_string(index=False))
assert (events.previous.notna()).any(), "the record changes a verdict as it grows"

# %% [markdown]
# The verdict lines of the follower's log, over all its `--once` runs (the
# log's UTC timestamps left out):

# %%
# NBVAL_CHECK_OUTPUT
log_lines = [re.sub(r"^\S+Z dynia follow: ", "", line) for text in once_logs for line in text.splitlines()]
verdict_lines = [line for line in log_lines if re.match(r"^(K|T): ", line)]
print("\n".join(verdict_lines))

# %% [markdown]
# The whole log of the first `--once` runs and of the restart after the kill:
# a line as it starts (with the steps it finds committed), one per poll that
# wrote steps, and the verdict changes:

# %%
print("".join(once_logs[: 2]) + "...\n" + once_logs[live_round])

# %%
changes = events[events.previous.notna()]
lines = []
for change in changes.itertuples():
    rows = int(np.searchsorted(data.time, change.time)) + 1
    details = [reason["text"] for reason in json.loads(change.details)]
    because = f": {'; '.join(details)}" if details else ""
    lines.append(f"- **{change.parameter}** went from `{change.previous}` to `{change.verdict}` when the follower "
                 f"judged the log at {change.time:g} s ({rows} rows){because}.")
first = events[events.previous.isna()]
say(
    "The first judgement (after round 1) gave "
    + ", ".join(f"{row.parameter} `{row.verdict}`" + (f" ({row.reasons})" if row.reasons else "")
                for row in first.itertuples())
    + ". Then:\n\n" + "\n".join(lines)
)

# %%
gain_turned = changes[(changes.parameter == "K") & (changes.previous == "identified") & (changes.verdict == "suspect")]
first_gain_verdict = events[events.parameter == "K"].verdict.iloc[0]
assert first_gain_verdict == "identified" and len(gain_turned) >= 1, "the gain: identified, then suspect"

# %% [markdown]
# The gain was `identified` at first and turned `suspect` as the log grew
# (asserted above). The heating plate shows what the thesis warns of in
# section 4.4, and what the README's offline analysis of this record and
# `online_replay` find: the gain of a linear model of this plate moves with
# the operating point, so stretches of the record where the gain is well
# identified give bands that rule each other out, or that the whole
# record's fit rules out (the reason above says which). A follower can only
# say so once the log holds an operating point that contradicts the first
# ones; until then the gain looks `identified`. A verdict that turns
# `identified` in a later round (the time constant's, where it happens above)
# is the opposite case: the evidence grows as more transients are logged.
# The events table is where whoever decides to re-identify the model reads
# this, without running anything.
#
# ## The final IC(t), with the rounds and the verdict changes
#
# The results table at the end, with the logged data above it: the
# information content of both parameters and each one's 90 % band (the
# `lower` and `upper` columns), the rounds' boundaries as thin lines, the
# live round shaded, and each verdict change marked at the time of the
# judgement that made it.

# %%
fig, axes = plt.subplots(4, 1, figsize=(10, 10), sharex=True, layout="constrained")
axes[0].plot(data.time, data.y, color="k", linewidth=1, label="plate temperature y (degC)")
axes[0].set_ylabel("temperature (degC)")
lamp = axes[0].twinx()
lamp.step(data.time, data.u, where="post", color="tab:orange", linewidth=1, label="lamp voltage u (V)")
lamp.set_ylabel("lamp voltage (V)")
axes[0].legend(loc="upper left", fontsize="small")
lamp.legend(loc="upper right", fontsize="small")
axes[0].set_title("The plant table, as logged (DaISy heating system)")
for name in names:
    rows = final[final.parameter == name]
    axes[1].plot(rows.time, rows.ic, color=colours[name], linewidth=1, label=f"IC of {name}")
axes[1].set_ylim(0, 1.2)
axes[1].set_ylabel("information content")
axes[1].set_title(f"Information content in the results table, trailing window of {2 * n + 1} samples")
for ax, name, unit, (low, high) in zip(axes[2:], names, ("degC/V", "s"), ((0, gain_high), (0, time_constant_high))):
    rows = final[final.parameter == name]
    ax.fill_between(rows.time, rows.lower, rows.upper, color="0.75", label="90 % band (lower .. upper)")
    ax.plot(rows.time, rows.estimate, color=colours[name], linewidth=0.8, label="estimate (CLD median)")
    ax.set_ylim(low, high)
    ax.set_ylabel(f"{name} ({unit})")
    ax.set_title(f"Band and estimate of {name} in the results table")
for ax in axes:
    for start, _ in rounds[1:]:
        ax.axvline(data.time[start], color="0.7", linewidth=0.6, zorder=0)
    live_start, live_stop = rounds[live_round]
    ax.axvspan(data.time[live_start], data.time[live_stop - 1], color="tab:red", alpha=0.08, zorder=0)
for change in changes.itertuples():
    ax = axes[2 + names.index(change.parameter)]
    ax.axvline(change.time, color=colours[change.parameter], linestyle="--", linewidth=1.2)
    ax.annotate(f"{change.previous} -> {change.verdict}", (change.time, 0.97), xycoords=("data", "axes fraction"),
                ha="right", va="top", fontsize="small", color=colours[change.parameter])
axes[1].legend(loc="upper center", fontsize="small", ncol=2)
for ax in axes[2:]:
    ax.legend(loc="lower right", fontsize="small")
axes[-1].set_xlabel("time (s); thin lines: rounds of logging; shaded: the live round with the kill")
axes[-1].set_xlim(data.time[0], data.time[-1])
fig.savefig(f"{figure_dir}/logging_system.png", dpi=120, bbox_inches="tight")

# %% [markdown]
# ## Check: the results table equals the batch analysis
#
# The same rows, with the same offsets (input minus the input offset, output
# minus the first logged output), through `dynia.run(..., window="trailing")`
# with the follower's sample size, half window and seed. However the rows
# arrived, in rounds, through a follower killed mid-way and a restart, the
# table must hold the batch analysis's numbers: `ic`, `lower`, `upper` and
# `estimate` to rounding (the per-step updates sum in numpy, the batch engine
# in compiled running sums), `informative` and the verdicts exactly.

# %%
u = data.u - input_offset
y = data.y - data.y[~np.isnan(data.y)][0]
batch = dynia.run(u, y, dynia.models.FirstOrder(), {"K": (0.0, gain_high), "T": (0.0, time_constant_high)},
                  n_samples=n_samples, n=n, rng=seed, window="trailing", dt=data.dt)
table = {column: np.vstack([final[final.parameter == name][column].to_numpy(dtype=float) for name in batch.names])
         for column in ("ic", "lower", "upper", "estimate")}
for column, expected in (("ic", batch.ic), ("lower", batch.ci[..., 0]), ("upper", batch.ci[..., 1]),
                         ("estimate", batch.median)):
    np.testing.assert_allclose(table[column], expected, rtol=1e-9, equal_nan=True, err_msg=column)
compared = True  # reached only if every assert_allclose above passed
informative = final[final.parameter == batch.names[0]].informative
assert informative.notna().all(), "every step judged"
informative = informative.to_numpy(dtype=bool)
assert np.array_equal(informative, batch.informative)
batch_verdicts = {name: (v["verdict"], ", ".join(r["code"] for r in v["reasons"])) for name, v in batch.verdicts.items()}
assert batch_verdicts == snapshots[-1]["verdicts"]

# %%
# NBVAL_CHECK_OUTPUT
print("ic, lower, upper, estimate equal to dynia.run(window='trailing') to rtol 1e-9:", compared)
print("informative equal:", np.array_equal(informative, batch.informative),
      f"({informative.sum()} of {informative.size} steps informative)")
print("verdicts equal:", batch_verdicts == snapshots[-1]["verdicts"], batch_verdicts)
