"""Plain port of the DYNIA in Wagener's MCAT toolbox 5.1 (``id_time.m``): an oracle.

``id_time.m`` (Thorsten Wagener, Penn State, October 2004) is a GUI routine;
this module ports its numerical core, for the centred ("medium", running
mean) window and one parameter, with its loops, so that the ``"mcat"`` flavour
of :func:`dynia.engine.moving_window` can be tested against it. Time and
sample indices are 0-based here.

Shape convention: as MCAT, ``mct`` is (n_steps, n_samples), one column per
simulation, and ``dat`` is (n_samples, n_params); ``obs`` is (n_steps,).

What ``id_time.m`` does at each time step
-----------------------------------------
1. Residual of every simulation: the mean absolute error over the window
   (steps t-n .. t+n clipped to the record).
2. Likelihood ``L = 1 - residual/max(residual)``. The test guarding the
   division is ``max(residual) ~= 0`` on the whole residual matrix built so
   far, which MATLAB reads as "every window so far had a non-zero maximum";
   once one window had all residuals 0, ``L = 1 - residual`` from then on.
   Where ``min(L) <= 0`` (always, after the division: the worst simulation
   gets 0) ``L = L - min(L) + 1000*eps``.
3. The population is sorted by ``L`` ascending (stable) and cut into
   ``grouping = 10`` blocks of ``cls = floor(n_samples/10)``; the behavioural
   set is the top block, sorted positions ``cls*9 .. cls*10-1``. When
   ``n_samples`` is not a multiple of 10 the very best ``n_samples - 10*cls``
   simulations fall outside it.
4. Limits: the first sorted behavioural value whose rank/cls exceeds 0.05
   and 0.95 (unweighted; ``1 - conf`` split evenly for other levels).
5. Gradient: the sorted values get a tie nudge (for k = 1 .. count-2, a value
   equal to its predecessor is raised by (value after - predecessor)/1000;
   the last pair is never checked); the CDF with knots [sample minimum -
   0.001 (0 if that is negative), nudged values, sample maximum + 0.001] and
   levels [0, rank/cls, 1] is linearly interpolated at ``containers + 1``
   equally spaced points from the sample minimum to the sample maximum, and
   ``gradient()`` (unit spacing) of that is the colour; NaN becomes 0.
6. ``IC = 1 - (ucl - lcl)/(max(dat) - min(dat))``: the sample range, not the
   prior bounds.

Deviations
----------
- ``mean`` is taken as the left-to-right sum over the count (the order of a
  plain loop), so that the engine can reproduce the residuals bit for bit.
- Windows are clipped at both ends of the record (MATLAB indexes outside
  the data, and fails, for records shorter than 2n).
- ``interp_special`` (an MCAT helper whose source is not published with
  ``id_time.m``) is taken to be plain linear interpolation (``numpy.interp``).
- The grid ``min:step:max`` is built with ``numpy.linspace`` (MATLAB's colon
  operator may differ in the last bit of some points).
- ``percentage`` generalises ``grouping = 10`` to ``grouping = 100/percentage``,
  which must be a whole number; ``conf_level`` generalises 90.
- The knot at ``max(min - 0.001, 0)`` lies above the smallest values when a
  parameter can be negative, which breaks the CDF; that raises ``ValueError``.
"""

import math

import numpy as np

from ..errors import SettingsError

__all__ = ["id_time"]

_EPS = np.finfo(float).eps


def id_time(mct, obs, dat, p1, window, *, containers=20, percentage=10, conf_level=90):
    """MCAT DYNIA of parameter ``p1`` with a centred window of half width ``window``.

    Parameters
    ----------
    mct : array_like, shape (n_steps, n_samples)
        Simulated output, one column per parameter set.
    obs : array_like, shape (n_steps,)
        Observed output.
    dat : array_like, shape (n_samples, n_params)
        Parameter sets.
    p1 : int
        Column of ``dat`` analysed (0-based).
    window : int
        Half window (MCAT's ``n``; window size 2n+1).
    containers, percentage, conf_level : optional
        MCAT's 20 containers, top 10 % and 90 % limits.

    Returns
    -------
    infocontent : ndarray (n_steps,)
    lcl, ucl : ndarray (n_steps,)
    dtcolor : ndarray (containers + 1, n_steps)
        CDF gradient at the points ``XI``.
    XI : ndarray (containers + 1,)

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(2)
    >>> dat = rng.uniform(0, 1, (100, 1))
    >>> mct = np.ones((12, 1)) * dat[:, 0]
    >>> ic, lcl, ucl, colour, XI = id_time(mct, 0.3 * np.ones(12), dat, 0, 2)
    >>> bool(np.all(ic > 0.8))
    True
    """
    mct = np.asarray(mct, dtype=float)
    obs = np.asarray(obs, dtype=float)
    dat = np.asarray(dat, dtype=float)
    t, n_samples = mct.shape
    grouping = _grouping(percentage)
    low_level = (100 - conf_level) / 200
    high_level = (100 + conf_level) / 200
    if dat[:, p1].min() < 0:
        raise SettingsError(
            f"parameter column {p1} has negative samples; MCAT's CDF knot at max(min-0.001, 0) then lies above them"
        )

    residual = np.zeros((n_samples, t))
    lcl = np.zeros(t)
    ucl = np.zeros(t)
    dtcolor = np.zeros((containers + 1, t))
    low, high = dat[:, p1].min(), dat[:, p1].max()
    XI = np.linspace(low, high, containers + 1)
    for dt in range(t):
        for no in range(n_samples):
            start, stop = max(dt - window, 0), min(dt + window + 1, t)
            residual[no, dt] = np.cumsum(np.abs(mct[start:stop, no] - obs[start:stop]))[-1] / (stop - start)
        if np.all(residual[:, : dt + 1].max(axis=0) != 0):
            L = residual[:, dt] / residual[:, dt].max()
        else:
            L = residual[:, dt].copy()
        L = 1 - L
        if L.min() <= 0:
            L = L - L.min() + 1000 * _EPS

        J = np.argsort(L, kind="stable")
        pop = dat[J, :]
        cls = math.floor(len(pop) / grouping)
        tm = pop[cls * (grouping - 1) : cls * grouping, p1]
        tmx = np.sort(tm, kind="stable")
        tmy = np.arange(1, len(tmx) + 1) / cls

        ucl[dt] = tmx[np.nonzero(tmy > high_level)[0][0]]
        lcl[dt] = tmx[np.nonzero(tmy > low_level)[0][0]]

        temp1 = low - 0.001
        if temp1 < 0:
            temp1 = 0
        temp2 = high + 0.001
        for kk in range(len(tmx) - 2):
            if tmx[kk] == tmx[kk + 1]:
                tmx[kk + 1] = tmx[kk + 1] + (tmx[kk + 2] - tmx[kk]) / 1000
        YI = np.interp(XI, np.concatenate([[temp1], tmx, [temp2]]), np.concatenate([[0.0], tmy, [1.0]]))
        FX = np.gradient(YI)
        dtcolor[:, dt] = np.nan_to_num(FX, nan=0.0)
    infocontent = 1 - (ucl - lcl) / (high - low)
    return infocontent, lcl, ucl, dtcolor, XI


def _grouping(percentage):
    """MCAT's number of population blocks, ``100/percentage``, which must be whole."""
    grouping = 100 / percentage
    if abs(grouping - round(grouping)) > 1e-9 * grouping or round(grouping) < 1:
        raise SettingsError(
            f"the mcat flavour splits the population into 100/percentage blocks; "
            f"percentage={percentage} does not divide 100 into a whole number of blocks"
        )
    return round(grouping)
