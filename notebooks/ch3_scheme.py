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
# # The implementation scheme (thesis Figure 3.1)
#
# The thesis's Figure 3.1 is a flowchart of its MATLAB implementation: provide
# data, model structure and settings; sample and simulate once; then, for every
# time step, compute the window's cost, select the behavioural set and run the
# DYNIA analysis (likelihood, CLD, gradient, confidence limits) on it. This
# notebook draws the same scheme for this package's pipeline, naming the
# function that does each step. Nothing here is random, so there is no seed.

# %% tags=["parameters"]
figure_dir: str = "figures"  # where the PNG goes

# %%
import os

import matplotlib.pyplot as plt
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

import dynia

os.makedirs(figure_dir, exist_ok=True)

STEPS = [
    ("Inputs", "input u, measured output y, sample time dt\n"
               "model structure (dynia.models) and a range per parameter\n"
               "n_samples, window half-width n, percentage, bins, conf_level, flavour"),
    ("Sample once", "dynia.sampling: uniform (the thesis), Latin hypercube or Sobol,\n"
                    "every draw through rng -> samples (n_samples x n_params)"),
    ("Simulate once", "model.simulate_chunks: exact zero-order-hold discretisation per sample,\n"
                      "all samples together, streamed in blocks of time steps"),
    ("Every window t  (dynia.engine)", "cost of each sample: MAE^2 over steps t-n .. t+n present\n"
                                         "behavioural set: the lowest percentage %, ties by sample index\n"
                                         "selected once per window, shared by every parameter"),
    ("Every parameter  (dynia.engine.cld)", "likelihood 1 - cost, normalised; sorted values -> CLD\n"
                                     "limits -> IC(t) = 1 - (upper - lower)/(high - low)\n"
                                     "gradient: likelihood mass per bin of the range"),
    ("DyniaResult", ".ic, .ci, .gradient, .to_dataframe()\n"
                    ".plot_information_content(), .plot_identifiability()"),
]

fig, ax = plt.subplots(figsize=(11, 11))
ax.set_xlim(0, 1.25)  # room right of the boxes for the loop arrow
ax.set_ylim(0, len(STEPS))
ax.axis("off")
box_height = 0.72
for row, (title, body) in enumerate(STEPS):
    top = len(STEPS) - row - 0.14
    loop = row in (3, 4)
    ax.add_patch(FancyBboxPatch((0.04, top - box_height), 0.92, box_height,
                                boxstyle="round,pad=0.01,rounding_size=0.02",
                                facecolor="#e8eef7" if loop else "#f4f4f4", edgecolor="k"))
    ax.text(0.5, top - 0.12, title, ha="center", va="center", fontsize=12, weight="bold")
    ax.text(0.5, top - 0.45, body, ha="center", va="center", fontsize=9.5, linespacing=1.5)
    if row < len(STEPS) - 1:
        ax.add_patch(FancyArrowPatch((0.5, top - box_height - 0.01), (0.5, top - 1 + 0.01),
                                     arrowstyle="-|>", mutation_scale=18, color="k"))
# The two blue boxes repeat for every window: draw the loop back.
loop_top, loop_bottom = len(STEPS) - 3 - 0.14 - 0.3, len(STEPS) - 4 - 0.14 - 0.5
ax.add_patch(FancyArrowPatch((0.97, loop_bottom), (0.97, loop_top), connectionstyle="arc3,rad=0.4",
                             arrowstyle="-|>", mutation_scale=16, color="tab:blue"))
ax.text(1.06, (loop_top + loop_bottom) / 2, "next window\n(chunks of windows\nin parallel)",
        ha="left", va="center", fontsize=9, color="tab:blue")
ax.set_title(f"Figure 3.1: the DYNIA pipeline of dynia {dynia.__version__}", fontsize=13)
fig.savefig(f"{figure_dir}/fig3_01.png", dpi=120, bbox_inches="tight")

# %% [markdown]
# **Figure 3.1** follows the thesis's scheme step for step, with three
# differences that come from the implementation, not the method:
#
# - the behavioural set of a window depends only on the costs, so it is
#   selected once per window for all parameters, where the thesis's scripts
#   rerun the whole moving window once per parameter;
# - the simulation is exact (zero-order hold) instead of forward Euler, and it
#   is streamed into the analysis in blocks of time, so the n_samples x n_steps
#   matrix of simulated outputs is never held in memory;
# - the gradient is the likelihood mass per bin, the quantity the thesis's
#   `cld_gradient` sets out to compute (the port in `dynia.thesis` keeps its
#   quirks).
