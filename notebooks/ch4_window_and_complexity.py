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
# # Chapter 4.1 and 4.2: window size and computational complexity
#
# The thesis's chapter 4 argues in words, without figures: a large moving
# window is "likely to mix periods of noise and information, blurring the
# information", a small one gives results that "can be distorted by
# measurement errors" (4.1); the number of Monte Carlo samples needed to
# keep the sampling density grows as `S = s^n` with the number of parameters
# n (eq. 4.1-4.3), and the moving window costs `O(S^2)` in the number of
# samples S (eq. 4.4). This notebook measures all three with `dynia`, and
# the parallel speed-up that section 5.1 proposes.
#
# | figure | what it shows |
# | --- | --- |
# | `fig4_01.png` | example 1 (first order): data and the IC of K and T for every window size |
# | `fig4_02.png` | example 2 (second order with dead time): data and the IC of K, T1, T2 and theta for every window size |
# | `fig4_03.png` | the window trade-off in numbers: peak IC, width of the informative segment and sensitivity to the noise realisation against n |
# | `fig4_04.png` | measured run time of the engine and of the simulation against samples, steps and parameters (log-log, fitted slopes) |
# | `fig4_05.png` | sampling density: error of the IC curve against S for 1-4 free parameters, and the S needed for a tolerance against the thesis's `s^n` law |
# | `parallel_speedup.png` | section 5.1: wall time, speed-up and cores in use of a complete analysis with 1 and 2 workers, threads and Dask |
#
# Figures are written to `figure_dir` (relative to the working directory;
# `make figures` runs notebooks in `reports/`).

# %% tags=["parameters"]
# Window-size study (4.1)
window_sizes: list = [2, 5, 10, 20, 40]  # half windows n: the window holds 2n+1 steps
ex1_samples: int = 2000  # Monte Carlo samples of example 1 (thesis: 2000)
ex2_samples: int = 10000  # Monte Carlo samples of example 2
noise_repeats: int = 8  # output-noise realisations (same samples) for the noise sensitivity
percentage: float = 10  # behavioural share in percent (thesis: 10)
seed: int = 2009  # seed of every random draw
figure_dir: str = "figures"  # where the PNGs go

# Computational complexity (4.2); timings use one thread (workers=1)
timing_samples: list = [500, 1000, 2000, 4000, 8000, 16000, 32000]  # S, at timing_fixed_steps steps
timing_steps: list = [250, 500, 1000, 2000, 4000, 8000, 16000]  # steps, at timing_fixed_samples samples
timing_fixed_samples: int = 2000  # samples while the number of steps varies
timing_fixed_steps: int = 500  # steps while the number of samples varies
timing_repeats: int = 5  # best of this many runs
port_samples: list = [250, 500, 1000, 2000, 4000]  # the one-to-one thesis port, one parameter
port_steps: int = 100  # steps of the port's timing runs (it is slow)

# Sampling density (eq. 4.1-4.3)
density_sizes: list = [250, 500, 1000, 2000, 4000, 8000, 16000, 32000]  # doubling sequence of S
density_reference: int = 128000  # samples of the reference IC curves
density_repeats: int = 3  # independent sample draws averaged at every S
density_tolerance: float = 0.03  # RMSE of the IC curve (IC units) counted as converged

# Parallel speed-up (5.1): complete analyses of example 2 with 1 and 2 workers, threads and Dask
parallel_samples: list = [5000, 20000, 60000]  # Monte Carlo samples of the timed analyses
parallel_repeats: int = 2  # best of this many runs

# %%
import logging
import os
import time
import timeit

import matplotlib.pyplot as plt
import numpy as np
from distributed import Client, LocalCluster

import dynia
import dynia.distributed
from dynia import thesis
from dynia.claims import either, say

os.makedirs(figure_dir, exist_ok=True)
UNINFORMED = 0.1  # IC of a parameter the window says nothing about: 90 % band of a uniform set


def best_of(function, repeats):
    """Smallest wall-clock time of ``repeats`` calls of ``function``, in seconds."""
    return min(timeit.repeat(function, number=1, repeat=repeats))


def loglog_slope(x, seconds):
    """Slope of log(seconds) against log(x), least squares."""
    return float(np.polyfit(np.log(x), np.log(seconds), 1)[0])


def segment(ic, lo, hi):
    """Peak IC in steps [lo, hi) and the informative segment around it.

    The segment is the contiguous run of steps around the peak whose IC lies
    above half the height of the peak over the uninformed level 0.1. Returns
    (peak, step of peak, first step, width); first step and width are None
    when the peak rises less than 0.02 above 0.1 (nothing to measure).
    """
    window = ic[lo:hi]
    top = int(np.nanargmax(window))
    peak = float(window[top])
    if peak - UNINFORMED < 0.02:
        return peak, lo + top, None, None
    level = UNINFORMED + 0.5 * (peak - UNINFORMED)
    left = right = top
    while left > 0 and window[left - 1] > level:
        left -= 1
    while right < window.size - 1 and window[right + 1] > level:
        right += 1
    return peak, lo + top, lo + left, right - left + 1


# %% [markdown]
# ## 4.1 Window size
#
# Both examples are the package's one shared definition,
# `dynia.synthetic.thesis_example` (the same data as `ch3_example1`,
# `ch3_example2` and `ch5_sampling_benchmark`):
#
# **Example 1** (thesis 3.1.1): `K/(T s + 1)` with K = 2, T = 3, the input of
# `example_firstorder.m` (500 steps, 35 with dips to 10 at 0-based steps
# 139-159 and 329-331 and 0 from step 399), output noise 0.5, K and T sampled
# on [0, 7].
#
# **Example 2** (thesis 3.1.2): `K exp(-theta s)/((T1 s + 1)(T2 s + 1))` with
# K = 2, T1 = 2, T2 = 2/3, theta = 100. The thesis does not print its input;
# the shared one is 600 steps of 0 with unit pulses of 10 steps from steps 100
# and 350, noise 0.2, K in [0, 5], T1 and T2 in [0, 8], theta in [50, 150].
# T1 and T2 enter the model symmetrically (swapping them gives the same
# output) and have the same range, so the swapped pair T1 = 2/3, T2 = 2 fits
# as well as the truth and the two parameters are interchangeable: their
# behavioural values have the same distribution, and their IC curves are the
# same curve up to Monte Carlo sampling (the cell below prints how far apart
# they are). Neither can be identified on its own, only the pair; the
# window study below therefore reads T1's curve for both.
#
# Each example is sampled and simulated once (`model.simulate`); only the
# half window n changes between the curves (`dynia.moving_window` on the same
# simulations).

# %%
rng = np.random.default_rng(seed)
example1, example2 = (dynia.synthetic.thesis_example(number, rng) for number in (1, 2))


def describe(example):
    """The truth and the noise of an example, for titles."""
    truth = ", ".join(f"{name} = {value:.3g}" for name, value in example.truth.items())
    return f"{truth}, noise {example.noise:g}"


u1, y1, clean1, model1 = example1.u, example1.y, example1.y_true, example1.model
true1 = np.array(list(example1.truth.values()))
bounds1 = np.array(list(example1.bounds.values()), dtype=float)
params1 = rng.uniform(bounds1[:, 0], bounds1[:, 1], (ex1_samples, bounds1.shape[0]))
sims1 = model1.simulate(params1, u1)

u2, y2, clean2, model2 = example2.u, example2.y, example2.y_true, example2.model
true2 = np.array(list(example2.truth.values()))
bounds2 = np.array(list(example2.bounds.values()), dtype=float)
params2 = rng.uniform(bounds2[:, 0], bounds2[:, 1], (ex2_samples, bounds2.shape[0]))
sims2 = model2.simulate(params2, u2)
moving = np.flatnonzero(np.abs(clean2) > 0.05)
print(f"example 2: the noise-free output exceeds 0.05 at steps {moving[0]}..{moving[-1]}")

results1, results2, engine_seconds = {}, {}, {}
for n in window_sizes:
    start = time.perf_counter()
    results1[n] = dynia.moving_window(y1, sims1, params1, bounds1, n=n, percentage=percentage,
                                      names=model1.names)
    results2[n] = dynia.moving_window(y2, sims2, params2, bounds2, n=n, percentage=percentage,
                                      names=model2.names)
    engine_seconds[n] = time.perf_counter() - start
print("engine time for both examples per window size (s):",
      {n: round(s, 2) for n, s in engine_seconds.items()})

# %%
colours = plt.cm.viridis(np.linspace(0, 0.9, len(window_sizes)))


def plot_example(u, y, results, names, path, title):
    fig, axes = plt.subplots(1 + len(names), 1, figsize=(11, 2.2 * (1 + len(names))), sharex=True,
                             constrained_layout=True)
    axes[0].plot(u, color="tab:blue", label="input u")
    axes[0].plot(y, color="k", linewidth=0.8, label="measured output y")
    axes[0].legend(loc="upper right", fontsize="small")
    axes[0].set_title(title)
    for p, name in enumerate(names):
        for colour, n in zip(colours, window_sizes):
            axes[1 + p].plot(results[n].ic[p], color=colour, linewidth=1, label=f"n = {n}")
        axes[1 + p].set_ylabel(f"IC of {name}")
        axes[1 + p].set_ylim(0, 1)
    axes[1].legend(loc="upper left", fontsize="small", ncol=len(window_sizes))
    axes[-1].set_xlabel("time step")
    fig.savefig(path, dpi=110)


plot_example(u1, y1, results1, model1.names, f"{figure_dir}/fig4_01.png",
             f"Example 1: first order, {describe(example1)}")
plot_example(u2, y2, results2, model2.names, f"{figure_dir}/fig4_02.png",
             f"Example 2: second order with dead time, {describe(example2)}")
t1, t2 = model2.names.index("T1"), model2.names.index("T2")
print("example 2, mean |IC(T1) - IC(T2)| per half window n:",
      {n: round(float(np.mean(np.abs(results2[n].ic[t1] - results2[n].ic[t2]))), 3) for n in window_sizes})

# %% [markdown]
# ### The trade-off in numbers
#
# For the segments where the data hold information we measure the peak IC and
# the width of the informative segment (steps around the peak whose IC lies
# above half the peak's height over the uninformed level 0.1). For example 2
# we also note how many steps before the output first moves (the first step printed above) the
# theta segment starts: information the window "sees" before it is in the
# data. For example 1 the gain's information outlives the final step to zero:
# we note how many steps after step 399 the IC of K stays above 0.5.
#
# The noise sensitivity of a window size is measured directly: the output
# noise is drawn `noise_repeats` times, the samples and simulations stay the
# same, and we average over time the standard deviation of the IC across the
# realisations.

# %%
segments = [  # (label, example, parameter index, search range)
    ("ex1 T, dip 1 (steps 139-159)", 1, 1, (130, 200)),
    ("ex1 T, dip 2 (steps 329-331)", 1, 1, (315, 385)),
    ("ex2 theta, response 1", 2, 3, (150, 320)),
    ("ex2 K, response 1", 2, 0, (150, 320)),
    ("ex2 theta, response 2", 2, 3, (380, 530)),
]
onset = int(moving[0])
table = {}
for label, example, p, (lo, hi) in segments:
    results = results1 if example == 1 else results2
    table[label] = {n: segment(results[n].ic[p], lo, hi) for n in window_sizes}

k_lag = {n: int(np.argmax(results1[n].ic[0, 399:] < 0.5)) for n in window_sizes}
theta_lead = {n: (onset - table["ex2 theta, response 1"][n][2]
                  if table["ex2 theta, response 1"][n][2] is not None else None)
              for n in window_sizes}


def fmt(value, digits=2):
    return "-" if value is None else (f"{value:.{digits}f}" if isinstance(value, float) else str(value))


# %%
# NBVAL_CHECK_OUTPUT
print("peak IC / width of the informative segment (steps) per half window n;")
print("width '-': the peak rises less than 0.02 above the uninformed level 0.1")
print(f"{'segment':32s}" + "".join(f"{'n=' + str(n):>13s}" for n in window_sizes))
for label, row in table.items():
    print(f"{label:32s}" + "".join(f"{fmt(round(r[0], 2)) + ' / ' + fmt(r[3]):>13s}"
                                   for r in row.values()))
print(f"{'ex1 K: steps IC>0.5 after 399':32s}" + "".join(f"{k_lag[n]:>13d}" for n in window_sizes))
print(f"{'ex2 theta: lead before output':32s}" + "".join(f"{fmt(theta_lead[n]):>13s}" for n in window_sizes))
print(f"{'ex1 K: mean IC, steps 180-319':32s}"
      + "".join(f"{results1[n].ic[0, 180:320].mean():>13.2f}" for n in window_sizes))

# %%
def transient_mask(clean, pad=10):
    """Steps within `pad` of a step where the noise-free output moves by over 1 % of its range."""
    moves = np.flatnonzero(np.abs(np.diff(clean, prepend=clean[0])) > 0.01 * np.ptp(clean))
    mask = np.zeros(clean.size, dtype=bool)
    for step in moves:
        mask[max(0, step - pad):step + pad + 1] = True
    return mask


masks = {1: transient_mask(clean1), 2: transient_mask(clean2)}
noise_sd = {(example, part): {} for example in (1, 2) for part in ("transient", "flat")}
noise_rng = np.random.default_rng(seed + 1)
noisy = {number: [example.y_true + noise_rng.normal(0, example.noise, example.u.size) for _ in range(noise_repeats)]
         for number, example in ((1, example1), (2, example2))}
problems = {1: (sims1, params1, bounds1), 2: (sims2, params2, bounds2)}
for n in window_sizes:
    for example, (sims, params, bounds) in problems.items():
        ics = np.array([dynia.moving_window(y, sims, params, bounds, n=n, percentage=percentage).ic
                        for y in noisy[example]])
        spread = ics.std(axis=0)  # (n_params, n_steps): across the noise realisations
        noise_sd[example, "transient"][n] = spread[:, masks[example]].mean(axis=1)
        noise_sd[example, "flat"][n] = spread[:, ~masks[example]].mean(axis=1)

# %%
# NBVAL_CHECK_OUTPUT
print(f"IC standard deviation across {noise_repeats} noise realisations (same samples), averaged over")
print("the steps near output transients (within 10 steps) and over the flat stretches")
for example, names in ((1, model1.names), (2, model2.names)):
    print(f"example {example}: {masks[example].sum()} transient steps of {masks[example].size}")
    for part in ("transient", "flat"):
        for p, name in enumerate(names):
            print(f"  {part:9s} {name:6s}" + "".join(f"  n={n}: {noise_sd[example, part][n][p]:.3f}"
                                                    for n in window_sizes))

# %%
fig, axes = plt.subplots(1, 3, figsize=(15, 4.2), constrained_layout=True)
for label, row in table.items():
    axes[0].plot(window_sizes, [row[n][0] for n in window_sizes], "o-", label=label)
    widths = [row[n][3] if row[n][3] is not None else np.nan for n in window_sizes]
    axes[1].plot(window_sizes, widths, "o-", label=label)
axes[1].plot(window_sizes, [2 * n + 1 for n in window_sizes], "k--", label="2n + 1 (window length)")
axes[0].axhline(UNINFORMED, color="0.6", linestyle=":", label="uninformed (0.1)")
axes[0].set(xscale="log", xlabel="half window n", ylabel="peak IC", title="Peak IC of short segments")
axes[1].set(xscale="log", yscale="log", xlabel="half window n", ylabel="width (steps)",
            title="Width of the informative segment")
for (example, part), style in zip(noise_sd, ("s-", "s:", "o-", "o:")):
    axes[2].plot(window_sizes, [noise_sd[example, part][n].mean() for n in window_sizes], style,
                 label=f"example {example}, {part} steps (mean over parameters)")
axes[2].set(xscale="log", xlabel="half window n", ylabel="std of IC across noise draws",
            title="Sensitivity to the noise realisation")
axes[2].set_ylim(bottom=0)
for ax in axes:
    ax.set_xticks(window_sizes, [str(n) for n in window_sizes])
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
    ax.legend(fontsize="x-small")
fig.savefig(f"{figure_dir}/fig4_03.png", dpi=110)

# %%
smallest, largest = window_sizes[0], window_sizes[-1]
theta1, theta2, gain1 = table["ex2 theta, response 1"], table["ex2 theta, response 2"], table["ex2 K, response 1"]
dip_long, dip_short = table["ex1 T, dip 1 (steps 139-159)"], table["ex1 T, dip 2 (steps 329-331)"]


def width(row, n):
    """Width of the informative segment at half window n, in words."""
    return "no segment" if row[n][3] is None else str(row[n][3])


def flattened(row):
    """The first half window at which a peak rises less than 0.02 above the uninformed level, in words."""
    n_flat = next((n for n in window_sizes if row[n][3] is None), None)
    if n_flat is None:
        return f"still above it at n = {largest}"
    return f"down to {row[n_flat][0]:.2f}, next to the uninformed level {UNINFORMED:g}, by n = {n_flat}"


def change(row, n_from, n_to):
    """How a segment's width changes between two half windows, in words."""
    if row[n_from][3] is None or row[n_to][3] is None:
        return f"goes from {width(row, n_from)} (n = {n_from}) to {width(row, n_to)} (n = {n_to})"
    verb = either(row[n_to][3] > row[n_from][3], "grows", "does not grow")
    return f"{verb} from {row[n_from][3]} steps (n = {n_from}) to {row[n_to][3]} (n = {n_to})"


leads = [f"{theta_lead[n]} (n = {n})" for n in window_sizes if theta_lead[n] is not None and theta_lead[n] > 0]
lags_past_n = [k_lag[n] - n for n in window_sizes]
say(f"""
    **What the window size does** (the numbers are this run's, from the tables above).

    * **Large windows blur.** A window of 2n+1 steps centred on t attributes a short informative stretch to every
      t within n steps of it. Once n exceeds the stretch's own length the informative segment widens like the
      window (fig4_03, middle): theta's segment at example 2's first response {change(theta1, smallest, largest)},
      K's {change(gain1, smallest, largest)}, and theta's segment starts
      {", ".join(leads) if leads else "no"} steps before the output moves at all. The few informative steps are
      also diluted by 2n uninformative ones: the time constant's peaks at example 1's two input dips (IC
      {dip_long[smallest][0]:.2f} and {dip_short[smallest][0]:.2f} at n = {smallest}) are
      {flattened(dip_short)} for the 3-step dip and {flattened(dip_long)} for the 21-step one. After the
      final step to zero the gain's IC stays above 0.5 for {k_lag[smallest]} steps at n = {smallest} but for
      {k_lag[largest]} at n = {largest} (n + {min(lags_past_n)} to n + {max(lags_past_n)} steps): the window keeps
      seeing the steady stretch before the step long after the output has settled at zero. This is what the
      thesis calls mixing periods of noise and information. (Theta's segment at the second response
      {change(theta2, smallest, largest)}: the flat stretches around it carry a high theta IC of their own, so
      half-height is a poor edge there.)
""")


# %%
def spread(example, part, name, n):
    """Mean standard deviation of the IC across the noise realisations."""
    names = (model1 if example == 1 else model2).names
    return float(noise_sd[example, part][n][names.index(name)])


def spread_words(values):
    """The range of ``values`` in words, one number when they round alike."""
    low, high = f"{min(values):.2f}", f"{max(values):.2f}"
    return low if low == high else f"{low} to {high}"


def spread_range(example, part, name):
    values = [spread(example, part, name, n) for n in window_sizes]
    return f"{values[0]:.3f} to {values[-1]:.3f}" if len(values) > 1 else f"{values[0]:.3f}"


calmest = min(window_sizes, key=lambda n: spread(2, "transient", "theta", n))
lag_calmest = min(window_sizes, key=lambda n: spread(2, "transient", "T1", n))
rises_again = calmest < largest and spread(2, "transient", "theta", largest) > spread(2, "transient", "theta", calmest)
flat_above = all(spread(2, "flat", name, n) > spread(2, "transient", name, n)
                 for name in ("T1", "T2", "theta") for n in window_sizes)
gain_spreads = [spread(2, "transient", "K", n) for n in window_sizes]
gain_peaks = [gain1[n][0] for n in window_sizes]
example1_spread = max(float(noise_sd[1, part][n].max()) for part in ("transient", "flat") for n in window_sizes)
steady_gain = [float(results1[n].ic[0, 180:320].mean()) for n in window_sizes]
cap = 1 - 0.9 * percentage / 100  # the 90 % band of a behavioural set that spans percentage % of the range
say(f"""
    * **Small windows are noisier where the information is.** Near the output transients the spread of the IC
      across noise realisations {either(calmest > smallest, "falls", "does not fall")} as the window grows
      (fig4_03, right): for example 2 from {spread(2, "transient", "theta", smallest):.3f} (n = {smallest}) to
      {spread(2, "transient", "theta", calmest):.3f} (n = {calmest}) for theta and from
      {spread(2, "transient", "T1", smallest):.3f} to {spread(2, "transient", "T1", lag_calmest):.3f}
      (n = {lag_calmest}) for T1 (T2: {spread(2, "transient", "T2", smallest):.3f} to
      {min(spread(2, "transient", "T2", n) for n in window_sizes):.3f}).{either(rises_again,
      f" Past n = {calmest} the spread near theta's transients rises again "
      f"({spread(2, 'transient', 'theta', largest):.3f} at n = {largest}): the window reaches into the flat "
      "stretches.", "")} On those flat stretches the spread is {either(flat_above, "larger at every n",
      "not larger at every n")} and changes less with n (theta {spread_range(2, "flat", "theta")}, T1
      {spread_range(2, "flat", "T1")} and T2 {spread_range(2, "flat", "T2")} from n = {smallest} to n =
      {largest}): there several families of samples fit a flat output equally well (short lags whose response is
      over, or long dead times whose response is still to come) and the noise decides which
      {percentage:g} % are kept, which no window size repairs. This is also why T1's and T2's IC flicker high on
      the flat stretches after each response in fig4_02 while they stay low at the responses themselves: at a
      response both orders of the pair (2, 2/3) and (2/3, 2) fit, so each parameter's behavioural values sit near
      both values and the band is wide. The gain's spread near the transients stays between
      {min(gain_spreads):.3f} and {max(gain_spreads):.3f} at every n, and its peak IC at example 2's first
      response is low ({spread_words(gain_peaks)}), presumably because on a response this
      short the gain trades off against the two lags. On example 1 (noise {example1.noise:g} on an output of
      {np.max(clean1):.0f}) the spreads are {either(example1_spread < 0.03, "small", "not small")} at every n (at
      most {example1_spread:.3f}). The IC is also capped by the behavioural share: with {percentage:g} % kept, a
      perfectly determined parameter reads about 1 - 0.9 x {percentage / 100:g} = {cap:.2f} (the gain on example
      1's steady stretches reads {spread_words(steady_gain)} over the window sizes), so
      noise that does not move the {percentage:g} % boundary does not show.
""")

# %%
lag_range = float(bounds2[[model2.names.index("T1"), model2.names.index("T2")], 1].max())
middle = 10 if 10 in window_sizes[1:] else window_sizes[len(window_sizes) // 2]
small_enough = [n for n in window_sizes if dip_short[n][3] is not None and dip_short[n][0] > dip_short[middle][0]]
theta_best = max(window_sizes, key=lambda n: theta1[n][0])
theta_ratio = spread(2, "transient", "theta", middle) / spread(2, "transient", "theta", smallest)
lag_ratio = spread(2, "transient", "T1", middle) / spread(2, "transient", "T1", smallest)
say(f"""
    * **Choosing n.** The thesis suggests starting from the range of the dominating response time (the lags'
      ranges reach {lag_range:g} steps here). Against what we measure on example 2: n = {middle}
      {either(theta_best == middle, "gives theta's highest peak at the first response",
              f"does not give theta's highest peak at the first response (n = {theta_best} does)")}
      ({theta1[middle][0]:.2f}), and against n = {smallest} it multiplies theta's noise spread near the responses
      by {theta_ratio:.2f} and T1's by {lag_ratio:.2f}, while theta's segment at the first response is
      {width(theta1, middle)} steps wide; on example 1, n = {middle} brings the 3-step dip's peak down to
      {dip_short[middle][0]:.2f}{either(bool(small_enough), f", which n = {' and '.join(map(str, small_enough))} "
      "show higher", "")}. The window has to be matched to the shortest informative stretch one wants to find,
      and below that to the noise. The first and last n steps use truncated windows (thesis 4.1); the segments
      measured above lie away from both ends.
""")

# %% [markdown]
# ## 4.2 Computational complexity
#
# We time, with `time.perf_counter` and the best of `timing_repeats` runs,
#
# * the engine `dynia.moving_window` on precomputed simulations (example 1's
#   model and input, tiled when longer, n = 10, one thread so that the
#   measurement counts work rather than cores), and separately the simulation
#   `model.simulate`;
# * against the number of samples S, the number of steps, and the number of
#   parameters analysed (columns of the params array: SecondOrderDelay on
#   example 2's input with 1 to 4 of its parameters passed to the engine);
# * the one-to-one port of the thesis's MATLAB (`dynia.thesis`, one
#   parameter, `port_steps` steps) against S, to test the thesis's own
#   algorithm against its eq. 4.4.
#
# Timings vary from run to run and machine to machine: they are printed, not
# checked.

# %%
def example1_problem(n_samples, n_steps, generator):
    u = np.resize(u1, n_steps)  # example 1's input, repeated for longer records
    y = model1.simulate(true1[None], u)[0] + generator.normal(0, example1.noise, n_steps)
    params = generator.uniform(0, 7, (n_samples, 2))
    return u, y, params


timing_load = os.getloadavg()[0]
print(f"cores: {os.cpu_count()}; load average over the last minute before timing: {timing_load:.1f}")
timing_rng = np.random.default_rng(seed + 2)
timings = {"samples": {"engine": [], "simulate": []}, "steps": {"engine": [], "simulate": []},
           "params": {"engine": [], "simulate": []}, "port": []}

for n_samples in timing_samples:
    u, y, params = example1_problem(n_samples, timing_fixed_steps, timing_rng)
    timings["samples"]["simulate"].append(best_of(lambda: model1.simulate(params, u), timing_repeats))
    sims = model1.simulate(params, u)
    timings["samples"]["engine"].append(best_of(
        lambda: dynia.moving_window(y, sims, params, bounds1, n=10, workers=1), timing_repeats))
    del sims

# The step eq. 4.4 is about, alone: choosing the behavioural 10 % of 100 windows'
# costs, by the engine's partition and by the stable sort the thesis uses.
timings["select"] = {"partition": [], "sort": []}
for n_samples in timing_samples:
    cost = timing_rng.random((100, n_samples))
    count = n_samples * percentage // 100
    timings["select"]["partition"].append(best_of(
        lambda: dynia.engine.selection.lowest_stable(cost, count), timing_repeats))
    timings["select"]["sort"].append(best_of(
        lambda: np.argsort(cost, axis=1, kind="stable")[:, :count], timing_repeats))

for n_steps in timing_steps:
    u, y, params = example1_problem(timing_fixed_samples, n_steps, timing_rng)
    timings["steps"]["simulate"].append(best_of(lambda: model1.simulate(params, u), timing_repeats))
    sims = model1.simulate(params, u)
    timings["steps"]["engine"].append(best_of(
        lambda: dynia.moving_window(y, sims, params, bounds1, n=10, workers=1), timing_repeats))
    del sims

parameter_counts = [1, 2, 3, 4]
free_order = [3, 0, 1, 2]  # theta, K, T1, T2: the order in which parameters are freed
for count in parameter_counts:
    free = free_order[:count]
    params = np.tile(true2, (timing_fixed_samples, 1))
    params[:, free] = timing_rng.uniform(bounds2[free, 0], bounds2[free, 1], (timing_fixed_samples, count))
    timings["params"]["simulate"].append(best_of(lambda: model2.simulate(params, u2), timing_repeats))
    sims = model2.simulate(params, u2)
    timings["params"]["engine"].append(best_of(
        lambda: dynia.moving_window(y2, sims, params[:, free], bounds2[free], n=10, workers=1),
        timing_repeats))

for n_samples in port_samples:
    u, y, params = example1_problem(n_samples, port_steps, timing_rng)
    sims = model1.simulate(params, u)
    timings["port"].append(best_of(
        lambda: thesis.moving_window_calcs(port_steps, params[:, 0], 0, 7, n_samples, sims, y, 40, 10, 10),
        min(timing_repeats, 3)))

slopes = {
    "engine vs S": loglog_slope(timing_samples, timings["samples"]["engine"]),
    "simulate vs S": loglog_slope(timing_samples, timings["samples"]["simulate"]),
    "engine vs steps": loglog_slope(timing_steps, timings["steps"]["engine"]),
    "simulate vs steps": loglog_slope(timing_steps, timings["steps"]["simulate"]),
    "engine vs parameters": loglog_slope(parameter_counts, timings["params"]["engine"]),
    "simulate vs parameters": loglog_slope(parameter_counts, timings["params"]["simulate"]),
    "thesis port vs S": loglog_slope(port_samples, timings["port"]),
    "selection by partition vs S": loglog_slope(timing_samples, timings["select"]["partition"]),
    "selection by stable sort vs S": loglog_slope(timing_samples, timings["select"]["sort"]),
}
upper = slice(len(timing_samples) // 2, None)  # the larger half of S, past fixed overheads
slopes["engine vs S, larger half"] = loglog_slope(timing_samples[upper], timings["samples"]["engine"][upper])

for name, x, key in (("S", timing_samples, "samples"), ("steps", timing_steps, "steps"),
                     ("parameters", parameter_counts, "params")):
    print(f"run time (ms) against {name}:")
    for value, engine, simulate in zip(x, timings[key]["engine"], timings[key]["simulate"]):
        print(f"  {value:>6d}: engine {engine * 1e3:9.2f}   simulate {simulate * 1e3:9.2f}")
print("thesis port, one parameter, %d steps (s):" % port_steps,
      {s: round(t, 3) for s, t in zip(port_samples, timings["port"])})
print("fitted log-log slopes:")
for name, slope in slopes.items():
    print(f"  {name:28s} {slope:5.2f}")
per_sample_step = np.array(timings["samples"]["engine"]) / (np.array(timing_samples) * timing_fixed_steps) * 1e9
print("engine time per sample and step (ns, one thread):",
      {s: round(float(t), 1) for s, t in zip(timing_samples, per_sample_step)})
half = len(timing_samples) // 2
print(f"  {per_sample_step.min():.1f} to {per_sample_step.max():.1f} ns; median over the smaller half of S "
      f"{np.median(per_sample_step[:half]):.1f} ns, over the larger half {np.median(per_sample_step[half:]):.1f} ns")
print("selection of 100 windows' behavioural sets (ms): partition",
      [round(t * 1e3, 2) for t in timings["select"]["partition"]], "stable sort",
      [round(t * 1e3, 2) for t in timings["select"]["sort"]])

# %%
# Eq. 4.4 predicts a slope of 2 against S. These verdicts come from timings, so they are printed but not
# checked: a loaded machine can tip them, and no checked output may depend on machine load.
print("engine slope against S below 1.5:", slopes["engine vs S"] < 1.5)
print("behavioural selection (partition) slope against S below 1.5:",
      slopes["selection by partition vs S"] < 1.5)
print("thesis port slope against S below 1.5:", slopes["thesis port vs S"] < 1.5)

# %%
fig, axes = plt.subplots(1, 3, figsize=(15, 5.4), layout="constrained")
panels = (("samples", timing_samples, "number of samples S"),
          ("steps", timing_steps, "number of time steps"),
          ("params", parameter_counts, "number of parameters analysed"))
for ax, (key, x, label) in zip(axes, panels):
    for what, marker in (("engine", "o-"), ("simulate", "s-")):
        slope = loglog_slope(x, timings[key][what])
        ax.plot(x, timings[key][what], marker, label=f"{what} (slope {slope:.2f})")
    ax.set(xscale="log", yscale="log", xlabel=label, ylabel="run time (s)")
axes[0].plot(port_samples, timings["port"], "^-",
             label=f"thesis port, {port_steps} steps, 1 parameter (slope {slopes['thesis port vs S']:.2f})")
for what, marker in (("partition", "v--"), ("sort", "d--")):
    axes[0].plot(timing_samples, timings["select"][what], marker, linewidth=0.8,
                 label=f"selection of 100 windows by {what} "
                       f"(slope {slopes['selection by ' + ('partition' if what == 'partition' else 'stable sort') + ' vs S']:.2f})")
reference = timings["samples"]["engine"][-1] * (np.array(timing_samples) / timing_samples[-1]) ** 2
axes[0].plot(timing_samples, reference, "k:", label="O(S^2) of eq. 4.4, through the last point")
axes[0].set_title(f"against S ({timing_fixed_steps} steps)")
axes[1].set_title(f"against steps ({timing_fixed_samples} samples)")
axes[2].set_title(f"against parameters (example 2, {timing_fixed_samples} samples)")
ticks = (sorted(set(timing_samples) | set(port_samples)), timing_steps, parameter_counts)
for ax, values in zip(axes, ticks):
    ax.set_xticks(values, [str(v) for v in values], rotation=45 if len(values) > 5 else 0)
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower left", fontsize="x-small", ncol=3)
for ax in axes[1:]:
    ax.legend(fontsize="x-small")
fig.savefig(f"{figure_dir}/fig4_04.png", dpi=110)

# %%
def slope_words(name, below, good, bad):
    """The fitted slope of ``name`` and a verdict against ``below``, in words."""
    return f"{slopes[name]:.2f} ({either(slopes[name] < below, good, bad)})"


sort_ratio = np.array(timings["select"]["sort"]) / np.array(timings["select"]["partition"])
say(f"""
    **What we measure** (this run, one thread, on {os.cpu_count()} cores with a load average of
    {timing_load:.1f} before timing). The timings depend on the machine and on what else runs on it (on a shared
    2-core machine single points can be off by a factor of two or more), so every number and verdict below is
    rendered from this run's measurement; nothing here is checked by the test suite.

    * **Samples.** The engine's fitted slope against S is {slope_words("engine vs S", 1.5,
      "closer to 1 than to the 2 of eq. 4.4", "closer to the 2 of eq. 4.4 than to 1")}, and over the larger half
      of the sizes alone {slope_words("engine vs S, larger half", 1.5, "closer to 1", "closer to 2")}. The time
      per sample and step is {per_sample_step.min():.1f} to {per_sample_step.max():.1f} ns, with a median of
      {np.median(per_sample_step[:half]):.1f} ns over the smaller half of the sizes and
      {np.median(per_sample_step[half:]):.1f} ns over the larger half; where it is higher at large S, a time
      chunk's arrays outgrow the cache and the window sums, plain additions and linear by construction, become
      memory-bound (this depends on the machine). The step eq. 4.4 is about, picking each window's behavioural
      set, timed alone (`numpy.argpartition` in `dynia.engine.selection.lowest_stable`), has a fitted slope of
      {slope_words("selection by partition vs S", 1.5, "well below 2", "near 2")}; the stable sort the thesis uses
      instead, slope {slopes["selection by stable sort vs S"]:.2f}, grows like S log S and costs
      {sort_ratio.min():.1f} to {sort_ratio.max():.1f} times as much over the sizes. The thesis's own algorithm,
      timed through the one-to-one port, has a slope of {slope_words("thesis port vs S", 1.5,
      "no more quadratic than that", "closer to quadratic")}: it sorts the costs and walks the sorted behavioural
      set once. The behavioural set does grow with S, but it is built once per window, not once per sample, so
      the two factors of S in eq. 4.4 do not multiply.
    * **Steps.** The fitted slopes against the number of steps are {slope_words("engine vs steps", 1.5,
      "well below 2", "near 2")} for the engine and {slope_words("simulate vs steps", 1.5, "well below 2",
      "near 2")} for the simulation (a loaded machine pushes the larger records' points up): every step is one
      vectorised update of all samples, and every window costs the same.
    * **Parameters.** The window sums and the selection are shared by all parameters, and only the limits and
      the gradient, on the small behavioural set, are per parameter, so the engine's time should grow far less
      than in proportion to the parameters analysed. The fitted slope is {slope_words("engine vs parameters", 0.5,
      "well below 1, as expected", "not far below 1: these runs take tens of milliseconds, and on a loaded "
      "machine their points scatter enough to hide the difference")}. The simulation does not depend on how many
      parameters are free at all (the model always has its four); its slope of
      {slopes["simulate vs parameters"]:.2f} is timing noise.

    A whole run therefore costs about S x steps x (2n+1) additions for the window sums plus a linear selection
    per window, linear in everything the engine is handed. Where the thesis's exponential cost (eq. 4.2-4.3)
    could come from is the number of samples the user must hand it, which the next section measures.
""")

# %% [markdown]
# ## The sampling-density argument (eq. 4.1-4.3)
#
# The thesis argues that to keep the sampling density `d = s/p` of every
# parameter, `S = s^n` samples are needed for n parameters. We measure the
# samples the IC curve actually needs on example 2 (n = 10, 10 % behavioural):
# with 1, 2, 3 and 4 free parameters (freed in the order theta, K, T1, T2;
# the others fixed at their true values in the params array, and only the
# free columns passed to the engine), compute the IC curves of all free
# parameters from a reference of `density_reference` samples, then for every
# S of a doubling sequence the RMSE between the IC curves from S samples and
# the reference (over all free parameters and steps, averaged over
# `density_repeats` independent draws). The S needed is the smallest S whose
# RMSE is below `density_tolerance`. The mean absolute error is computed
# alongside, since the RMSE is sensitive to the few steps at which the
# behavioural set splits into two clusters and the IC jumps.

# %%
def free_parameter_ic(count, n_samples, generator):
    free = free_order[:count]
    params = np.tile(true2, (n_samples, 1))
    params[:, free] = generator.uniform(bounds2[free, 0], bounds2[free, 1], (n_samples, count))
    sims = model2.simulate(params, u2)
    return dynia.moving_window(y2, sims, params[:, free], bounds2[free], n=10,
                               percentage=percentage).ic


density = {}
for count in parameter_counts:
    start = time.perf_counter()
    reference_ic = free_parameter_ic(count, density_reference, np.random.default_rng([seed, count, 0]))
    rmse, mae = [], []
    for size in density_sizes:
        draws = [free_parameter_ic(count, size, np.random.default_rng([seed, count, size, r]))
                 for r in range(density_repeats)]
        rmse.append(float(np.mean([np.sqrt(np.mean((ic - reference_ic) ** 2)) for ic in draws])))
        mae.append(float(np.mean([np.mean(np.abs(ic - reference_ic)) for ic in draws])))
    needed = next((s for s, e in zip(density_sizes, rmse) if e < density_tolerance), None)
    needed_mae = next((s for s, e in zip(density_sizes, mae) if e < density_tolerance / 2), None)
    density[count] = dict(reference=reference_ic, rmse=rmse, mae=mae, needed=needed,
                          needed_mae=needed_mae)
    print(f"{count} free parameter(s): {time.perf_counter() - start:.1f} s")

# %%
# NBVAL_CHECK_OUTPUT
print(f"RMSE of the IC curve against the {density_reference}-sample reference")
print(f"{'free':>4s} {'names':22s}" + "".join(f"{s:>8d}" for s in density_sizes) + "   S needed")
for count in parameter_counts:
    names = ",".join(model2.names[i] for i in free_order[:count])
    row = density[count]
    print(f"{count:>4d} {names:22s}" + "".join(f"{e:8.3f}" for e in row["rmse"])
          + f"   {fmt(row['needed'])}")
print(f"S needed for RMSE < {density_tolerance}:",
      {c: density[c]["needed"] for c in parameter_counts})
print(f"S needed for mean absolute error < {density_tolerance / 2}:",
      {c: density[c]["needed_mae"] for c in parameter_counts})
floor = density[parameter_counts[-1]]["rmse"][-1] * np.sqrt(density_sizes[-1] / density_reference)
print(f"reference's own error, extrapolated along S^(-1/2): {floor:.3f}")
print("mean reference IC of theta:",
      {c: round(float(density[c]["reference"][0].mean()), 3) for c in parameter_counts})

# %%
fig, axes = plt.subplots(1, 2, figsize=(13, 4.6), constrained_layout=True)
for count, colour in zip(parameter_counts, plt.cm.plasma(np.linspace(0, 0.8, 4))):
    axes[0].plot(density_sizes, density[count]["rmse"], "o-", color=colour,
                 label=f"{count} free (RMSE)")
    axes[0].plot(density_sizes, density[count]["mae"], "x--", color=colour, linewidth=0.8,
                 label=f"{count} free (mean abs. error)")
axes[0].axhline(density_tolerance, color="k", linestyle=":", label=f"RMSE tolerance {density_tolerance}")
axes[0].plot(density_sizes, density[1]["rmse"][0] * (np.array(density_sizes) / density_sizes[0]) ** -0.5,
             color="0.6", linestyle="-.", label="S^(-1/2)")
axes[0].set(xscale="log", yscale="log", xlabel="number of samples S",
            ylabel="error of the IC curve against the reference",
            title="Monte Carlo error of the IC curves, example 2")
axes[0].legend(fontsize="xx-small", ncol=2)

for key, style, label in (("needed", "o-", f"RMSE < {density_tolerance}"),
                          ("needed_mae", "x--", f"mean absolute error < {density_tolerance / 2}")):
    measured = [(c, density[c][key]) for c in parameter_counts if density[c][key] is not None]
    if measured:
        axes[1].plot(*zip(*measured), style, label=f"measured: smallest S with {label}")
    unreached = [c for c in parameter_counts if density[c][key] is None]
    if unreached:
        axes[1].plot(unreached, [2 * density_sizes[-1]] * len(unreached), "v", color="tab:red",
                     label=f"{label} not reached by S = {density_sizes[-1]}")
anchor = density[1]["needed"] or 2 * density_sizes[-1]
axes[1].plot(parameter_counts, [float(anchor) ** c for c in parameter_counts], "k:",
             label=f"S = s^n with s = {anchor}, the RMSE value for n = 1 (eq. 4.2)")
axes[1].set(yscale="log", xlabel="number of free parameters n", ylabel="samples needed",
            title="Samples needed against the s^n law")
axes[1].set_xticks(parameter_counts, [str(c) for c in parameter_counts])
axes[1].set_ylim(density_sizes[0] / 2, 3 * float(anchor) ** parameter_counts[-1])
axes[1].legend(fontsize="x-small", loc="upper left")
fig.savefig(f"{figure_dir}/fig4_05.png", dpi=110)

# %%
def samples_needed(key):
    """The S needed for every number of free parameters, in words."""
    return ", ".join(f"{density[c][key]} for {c} free" if density[c][key] is not None
                     else f"more than {density_sizes[-1]} for {c} free" for c in parameter_counts)


reached = all(density[c]["needed"] is not None for c in parameter_counts)
needed = [density[c]["needed"] for c in parameter_counts]
no_growth = reached and all(s_needed <= 2 * needed[0] for s_needed in needed)
error_slopes = {c: loglog_slope(density_sizes, density[c]["rmse"]) for c in parameter_counts}
like_root = all(-0.8 < slope < -0.3 for slope in error_slopes.values())
growth_words = (either(no_growth, "does not grow like `s^n`", "may grow with n; it is not measured here")
                + either(reached and needed[-1] < needed[0], "; if anything it falls", ""))
say(f"""
    **What comes out** (this run). On this example the number of samples needed to pin down the IC curves
    {growth_words}. The RMSE criterion
    (< {density_tolerance}) gives {samples_needed("needed")}; the mean absolute error criterion
    (< {density_tolerance / 2}) gives {samples_needed("needed_mae")}. The error falls
    {either(like_root, "roughly like", "not like")} `S^(-1/2)` for every n (fig4_05, left; fitted log-log slopes
    {", ".join(f"{slope:.2f}" for slope in error_slopes.values())}).{either(
        reached and needed[0] == max(needed) and needed[0] > min(needed),
        " The one-parameter case needs the most samples by the RMSE only because its IC curve has a few sharp "
        "jumps (steps at which theta's behavioural set splits into two clusters, dead times that put the response "
        "before the window and ones that put it after, and the IC collapses); where a draw and the reference jump "
        "at different steps, these few steps dominate the RMSE.", "")} The reference's own Monte Carlo error,
    extrapolated along `S^(-1/2)`, is about {floor:.3f}, {either(floor < density_tolerance / 3,
    "well below the tolerance", "not far below the tolerance")}.
""")

# %% [markdown]
# The reason is the way the IC is built. The behavioural set is a fixed
# share (10 %) of the samples, k = S/10, and the IC is read off the 5 % and
# 95 % quantiles of each parameter's behavioural values. The Monte Carlo error
# of a quantile estimated from k points shrinks like `1/sqrt(k)` whatever the
# dimension of the space the points were drawn from. The thesis's density
# argument is about covering the joint parameter space at a fixed resolution,
# which is not what a fixed-share IC measures.

# %%
theta_ic = {c: float(density[c]["reference"][0].mean()) for c in parameter_counts}
say(f"""
    What adding parameters costs instead is the IC itself: the same {percentage:g} % of the box must now also
    spread over directions the window does not identify, so theta's IC
    {either(theta_ic[parameter_counts[-1]] < theta_ic[1], "falls", "does not fall")} as parameters are freed
    (mean reference IC {", ".join(f"{ic:.2f} with {c} free" for c, ic in theta_ic.items())}). More samples do not
    bring it back at a fixed percentage. A smaller percentage or narrower ranges do; with a behavioural set that
    shrinks to a fixed neighbourhood of the best fit, the samples needed would scale with the box volume over that
    neighbourhood, which is the thesis's `s^n`, but we have not measured that regime here. In short: at a fixed
    behavioural share, DYNIA's cost is linear in S and the S needed for a converged IC curve
    {either(no_growth, "does not grow exponentially", "was not shown here not to grow exponentially")} with the
    number of parameters on this example; what the converged curve can resolve
    {either(theta_ic[parameter_counts[-1]] < theta_ic[1], "drops", "does not drop")} as parameters are added.
""")

# %% [markdown]
# ## Parallel speed-up (thesis section 5.1)
#
# Section 5.1 of the thesis proposes parallel computing twice: the moving
# windows are independent of each other once the simulations exist, and the
# Monte Carlo simulations are independent of each other, so C computers
# should each do 1/C of the work, a "linear speed-up". The package does both.
# `dynia.run(..., workers=k)` runs k threads on one machine: the compiled
# simulation splits the samples among them, and the windows are analysed in
# chunks of time steps, one chunk per thread at a time (the compiled kernels
# release the interpreter's lock). `dynia.distributed.run`
# sends the same chunks to the worker processes of a Dask cluster and gathers
# the results on the client; here a `LocalCluster` of 1 or 2 single-threaded
# worker processes on this machine.
#
# We time a complete analysis of example 2 (sampling, simulation, windows,
# verdicts; n = 10, 10 % behavioural) for each size in `parallel_samples`,
# the best of `parallel_repeats` runs, after one warm-up run that loads the
# compiled kernels (in every worker process, for Dask). The cluster's
# start-up is timed apart: it is paid once per session, not per analysis.
# All four configurations must give the same result, bit for bit; that is
# checked. The timings depend on the machine and on whatever else runs on it,
# so they are printed and plotted but not checked; the cell prints the number
# of cores and the load average (the mean number of processes wanting a core)
# before and after the measurement, so that a reader can see what the run
# competed with.

# %%
def time_runs(analyse, cpu_clock):
    """Time ``analyse(n_samples)`` for every size: best-of wall time, the cores that run used, the last result.

    The cores used are the CPU time of every process involved over the wall time: 2 when two workers
    really ran at once, about 1 when they took turns on one core.
    """
    seconds, cores, result = [], [], None
    for n_samples in parallel_samples:
        runs = []
        for _ in range(parallel_repeats):
            cpu, start = cpu_clock(), time.perf_counter()
            result = analyse(n_samples)
            wall = time.perf_counter() - start
            runs.append((wall, (cpu_clock() - cpu) / wall))
        best = min(runs)
        seconds.append(best[0])
        cores.append(best[1])
    return seconds, cores, result


parallel_load = [os.getloadavg()[0]]
print(f"cores: {os.cpu_count()}; load average over the last minute before timing: {parallel_load[0]:.1f}")
parallel_seconds, cores_used, parallel_results, cluster_start = {}, {}, {}, {}
for workers in (1, 2):
    def analyse_in_threads(n_samples, workers=workers):
        return dynia.run(example2.u, example2.y, example2.model, example2.bounds, n_samples=n_samples,
                         workers=workers, rng=seed)

    analyse_in_threads(parallel_samples[0])
    (parallel_seconds["threads", workers], cores_used["threads", workers],
     parallel_results["threads", workers]) = time_runs(analyse_in_threads, time.process_time)

for workers in (1, 2):
    start = time.perf_counter()
    with (LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                       silence_logs=logging.ERROR) as cluster,
          Client(cluster) as client):
        cluster_start[workers] = time.perf_counter() - start

        def analyse_on_cluster(n_samples, client=client):
            return dynia.distributed.run(example2.u, example2.y, example2.model, example2.bounds, client=client,
                                         n_samples=n_samples, rng=seed)

        def cluster_cpu_time(client=client):
            """CPU seconds of this process and of every worker process."""
            return time.process_time() + sum(client.run(time.process_time).values())

        analyse_on_cluster(parallel_samples[0])
        (parallel_seconds["Dask", workers], cores_used["Dask", workers],
         parallel_results["Dask", workers]) = time_runs(analyse_on_cluster, cluster_cpu_time)
parallel_load.append(os.getloadavg()[0])
print(f"load average over the last minute after timing: {parallel_load[1]:.1f}")
print("Dask cluster start-up (s):", {workers: round(seconds, 1) for workers, seconds in cluster_start.items()})
speed_up = {kind: np.array(parallel_seconds[kind, 1]) / np.array(parallel_seconds[kind, 2]) for kind in ("threads", "Dask")}
print("wall time in s (cores in use) and speed-up from 1 to 2 workers")
print(f"{'samples':>8s}" + "".join(f"{kind + ' ' + str(workers):>16s}" for kind, workers in parallel_seconds)
      + f"{'speed-up threads':>18s}{'speed-up Dask':>15s}")
for row, n_samples in enumerate(parallel_samples):
    print(f"{n_samples:>8d}" + "".join(f"{parallel_seconds[key][row]:>9.2f} ({cores_used[key][row]:.2f})"
                                       for key in parallel_seconds)
          + f"{speed_up['threads'][row]:>18.2f}{speed_up['Dask'][row]:>15.2f}")
print("Dask slower than the threads with the same number of workers at every size:",
      all(np.all(np.array(parallel_seconds["Dask", workers]) > np.array(parallel_seconds["threads", workers]))
          for workers in (1, 2)))

# %%
# NBVAL_CHECK_OUTPUT
one_thread = parallel_results["threads", 1]
for (kind, workers), result in parallel_results.items():
    same = all(np.array_equal(getattr(result, field), getattr(one_thread, field), equal_nan=True)
               for field in ("ic", "ci", "gradient", "samples"))
    print(f"{kind}, {workers} worker(s): the same IC, limits, gradient and samples as one thread:", same)

# %%
fig, (ax_time, ax_speed, ax_cores) = plt.subplots(1, 3, figsize=(16, 4.6), constrained_layout=True)
styles = {("threads", 1): "o-", ("threads", 2): "o--", ("Dask", 1): "s-", ("Dask", 2): "s--"}
colours = {"threads": "tab:blue", "Dask": "tab:orange"}
for (kind, workers), seconds in parallel_seconds.items():
    label = f"{kind}, {workers} worker{'s' if workers > 1 else ''}"
    ax_time.plot(parallel_samples, seconds, styles[kind, workers], color=colours[kind], label=label)
    ax_cores.plot(parallel_samples, cores_used[kind, workers], styles[kind, workers], color=colours[kind], label=label)
ax_time.set(xscale="log", yscale="log", xlabel="number of samples S", ylabel="wall time of the analysis (s)",
            title=f"Complete analysis of example 2 ({y2.size} steps), best of {parallel_repeats}")
ax_time.legend(fontsize="small")
for kind, ratios in speed_up.items():
    ax_speed.plot(parallel_samples, ratios, "o-" if kind == "threads" else "s-", color=colours[kind],
                  label=f"{kind}: time with 1 worker / with 2")
ax_speed.axhline(2, color="k", linestyle=":", label="linear speed-up on 2 workers (thesis 5.1)")
ax_speed.axhline(1, color="0.6", linestyle="-", linewidth=0.8, label="no speed-up")
ax_speed.set(xscale="log", xlabel="number of samples S", ylabel="speed-up", ylim=(0, 3.2),
             title=f"Speed-up from 1 to 2 workers ({os.cpu_count()} cores, shared)")
ax_speed.legend(fontsize="small", loc="upper right")
ax_cores.axhline(os.cpu_count(), color="k", linestyle=":", label=f"all {os.cpu_count()} cores")
two_workers_cores = max(max(cores_used[kind, 2]) for kind in ("threads", "Dask"))
ran_at_once = bool(two_workers_cores >= 1.5)
ax_cores.set(xscale="log", xlabel="number of samples S", ylabel="CPU time / wall time",
             ylim=(0, os.cpu_count() + 1.2),
             title="Cores the analysis actually had\n" + either(
                 ran_at_once, f"2 workers ran at once (up to {two_workers_cores:.2f} cores)",
                 f"2 workers never ran at once here (at most {two_workers_cores:.2f} cores)"))
ax_cores.legend(fontsize="small", loc="upper right", ncols=2)
for ax in (ax_time, ax_speed, ax_cores):
    ax.set_xticks(parallel_samples, [str(s) for s in parallel_samples])
    ax.xaxis.set_minor_formatter(plt.NullFormatter())
fig.savefig(f"{figure_dir}/parallel_speedup.png", dpi=110)

# %% [markdown]
# **What `parallel_speedup.png` shows, and what limits it.** Left: the wall
# time of a complete analysis against S for each configuration; middle: the
# speed-up, the time with one worker over the time with two, against the
# thesis's linear speed-up of 2; right: the cores the analysis actually had,
# its CPU time (the notebook's process plus, for Dask, the worker processes)
# over its wall time. The checked cell shows that all four configurations
# give the same IC, limits, gradient and samples, bit for bit: parallelism
# changes only the time.

# %%
best_speed_up = max(float(ratios.max()) for ratios in speed_up.values())
worst_speed_up = min(float(ratios.min()) for ratios in speed_up.values())
loaded = max(parallel_load) >= os.cpu_count() - 0.5
say(f"""
    Read the speed-up together with the right panel and the printed load average. A speed-up near 2 needs two
    cores free for the two workers. In this render the load average was {parallel_load[0]:.1f} before the timing
    and {parallel_load[1]:.1f} after it, on {os.cpu_count()} cores, and with two workers the analysis had at
    most {two_workers_cores:.2f} cores (CPU time over wall time, right panel):
    {either(ran_at_once, "the two workers did run at once", "**the two workers never ran at once on the machine "
            "that rendered this report**, so the figure cannot show a parallel speed-up, only the overheads")}.
    The speed-up from one worker to two ranges from {worst_speed_up:.2f} to {best_speed_up:.2f} over the sizes
    and both kinds{either(worst_speed_up < 1, "; below 1 a second worker cost time", "")}.
    {either(loaded, "Other processes shared the cores (the load average is near or above their number), so "
            "these numbers say more about the machine's load than about the method; rerun the notebook on an "
            "idle machine to measure the speed-up itself.", "The machine was not fully loaded during the timing.")}
    What limits the speed-up even on an idle 2-core machine:
""")

# %% [markdown]
# * **Two cores are at most a factor of 2**, and the operating system, the
#   notebook's kernel and (for Dask) the scheduler take their share too.
# * **Serial parts** run on one core whatever the workers: drawing the
#   samples, setting up the chunks, the verdicts after the windows, and
#   assembling the result (Amdahl's law: the speed-up is bounded by one over
#   the serial share).
# * **Memory bandwidth.** The window sums are memory-bound at large S (the
#   complexity section above), and two cores share one memory bus, so two
#   threads rarely make that part twice as fast.
# * **Dask's costs.** Its workers are processes, not threads: each task's
#   samples and results are pickled and sent between processes through the
#   scheduler, where threads share memory, and the cluster's start-up
#   (printed above) is paid once per session. On one machine this is pure
#   overhead against the threads (whether Dask was slower than the threads
#   at every size in this run is printed above). Dask pays off where its workers add cores
#   that threads cannot reach: the thesis's "clusters of PCs", several
#   machines with a scheduler (`dynia.distributed` says how to start one).
# * **Small problems** are dominated by fixed costs per analysis (starting the
#   threads, scheduling the tasks), so any speed-up shows only at the larger S.

# %%
say(f"""
    So the thesis is right that the windows and the simulations split into independent pieces with no change to
    the result (checked above), but a linear speed-up is an upper bound, which this run
    {either(best_speed_up >= 1.8, "came close to", f"did not reach (at best {best_speed_up:.2f})")};
    {either(ran_at_once, "the measurement here shows what two workers running at once gain",
            "the measurement here documents the overheads, not the method's limit")}.
""")
