"""Compiled per-decision work of ``ExcitationEnv.step`` (numba): the measured vector, the
regressors, the linear-range weight and the rank-one information update.

Compiled once per machine (``cache=True`` keeps the machine code beside this module).
At 6 x 6 the arithmetic is a few hundred flops; in Python its interpreter work was
most of a step's cost beyond JSBSim's (benchmarks/gym_throughput.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def rank_one(inv: np.ndarray, theta: np.ndarray, design: np.ndarray, w_design: np.ndarray,
             count: np.ndarray, x: np.ndarray, y: np.ndarray, weight: float,
             acc: np.ndarray) -> None:
    """Add one sample to every design's information, in place.

    Parameters
    ----------
    inv : (D, k, k) P = M^-1 of each design, updated (Sherman-Morrison).
    theta : (G, k) each coefficient's estimate (bias first), updated (recursive least
        squares, Ljung & Soderstrom 1983: with P_0 = I and theta_0 = 0 it is exactly
        M^-1 X^T W y).
    design : (G,) each coefficient's design.
    w_design : (D,) 1 / sigma^2 of each design's residual.
    count : (D,) how many coefficients share each design (each counts in log det).
    x : (D, k) the sample's regressors per design, bias first.
    y : (G,) the sample's dependent variables.
    weight : the sample's weight in [0, 1] (residual variance sigma^2 / weight).
    acc : (2,) [sum over coefficients of log det M, summed weights], updated.
    """
    k = x.shape[1]
    v = np.empty(k)
    for d in range(x.shape[0]):
        p, xd = inv[d], x[d]
        q = 0.0
        for i in range(k):
            s = 0.0
            for j in range(k):
                s += p[i, j] * xd[j]
            v[i] = s
            q += xd[i] * s
        wd = w_design[d] * weight
        wq = wd * q
        # matrix determinant lemma; Sherman-Morrison gain P x w / (1 + w x' P x)
        acc[0] += count[d] * math.log1p(wq)
        c = wd / (1.0 + wq)
        for i in range(k):
            gi = c * v[i]
            for j in range(k):
                p[i, j] -= gi * v[j]
        for g in range(theta.shape[0]):
            if design[g] == d:
                e = y[g]
                for j in range(k):
                    e -= theta[g, j] * xd[j]
                for j in range(k):
                    theta[g, j] += e * (c * v[j])
    acc[1] += weight


# the layout of ``decide``'s arrays: its int64 ``layout`` starts with HEADER, then holds
# design (G), slot entries (D x (k - 1)), linear-range entries (R), the targets' places
# (T x 3: design, slot, coefficient); its float64 ``par`` holds w_design (D), count (D),
# w_coef (G), slot parameters (D x (k - 1) x 3), linear-range parameters (R x 2); ``state``
# holds inv (D x k x k), theta (G x k), acc (2); ``out`` gets the measured vector (m),
# crb (T), estimate (T), weight, log det
HEADER = ("D", "k", "G", "T", "R", "m", "i_speed", "n_obs", "weighted")


def pack(design: np.ndarray, slot_idx: np.ndarray, range_idx: np.ndarray, places: np.ndarray,
         w_design: np.ndarray, count: np.ndarray, w_coef: np.ndarray, slot_par: np.ndarray,
         range_par: np.ndarray, m: int, i_speed: int, n_obs: int, weighted: bool
         ) -> tuple[np.ndarray, np.ndarray]:
    """``decide``'s (layout, par) from its parts (see ``decide``).

    Parameters
    ----------
    design : numpy.ndarray
        Per coefficient, its design index; shape (G,).
    slot_idx : numpy.ndarray
        Per design and regressor slot, its entry in the measured vector; shape (D, k - 1).
    range_idx : numpy.ndarray
        Per linear-range variable, its entry in the flight core's values; shape (R,).
    places : numpy.ndarray
        Per target, (design, slot, coefficient); shape (T, 3).
    w_design : numpy.ndarray
        Per design, w = 1 / sigma^2; shape (D,).
    count : numpy.ndarray
        Per design, how many coefficients share it; shape (D,).
    w_coef : numpy.ndarray
        Per coefficient, 1 / sigma^2; shape (G,).
    slot_par : numpy.ndarray
        Per slot, (trim value, scaling, scaling x V); shape (D, k - 1, 3).
    range_par : numpy.ndarray
        Per linear-range variable, (trim value, 1 / range); shape (R, 2).
    m : int
        Length of the measured vector (observation, then y).
    i_speed : int
        Entry of the airspeed in the measured vector.
    n_obs : int
        Length of the observation.
    weighted : bool
        Weight samples by the linear range.

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray]
        (layout, par): int64 header and indices, float parameters.
    """
    d, k1 = slot_idx.shape
    head = [d, k1 + 1, len(design), len(places), len(range_idx), m, i_speed, n_obs,
            int(weighted)]
    layout = np.concatenate([np.array(head), design, slot_idx.ravel(), range_idx,
                             places.ravel()]).astype(np.int64)
    par = np.concatenate([w_design, count, w_coef, slot_par.ravel(), range_par.ravel()])
    return layout, par


@njit(cache=True)
def decide(values: np.ndarray, noise: np.ndarray, t: float, layout: np.ndarray,
           par: np.ndarray, state: np.ndarray, out: np.ndarray) -> None:
    """One decision's work after the flight core's values are read, in place.

    Parameters
    ----------
    values : the flight core's values (SI), in the environment's read order.
    noise : the decision's noise row: [time, *values] + noise is the measured vector
        (its y entries carry minus their trim value).
    t : elapsed time (s).
    layout, par : the constants (``pack``): per design its w = 1 / sigma^2 and how many
        coefficients share it; per coefficient its design and 1 / sigma^2; per regressor
        slot its entry in the measured vector and (trim value, scaling, scaling x V):
        regressor = (measured - trim) (scaling + scaling x V / measured airspeed); per
        linear-range variable its entry in ``values`` and (trim value, 1 / range); per
        target its (design, slot) in inv and (coefficient, slot) in theta.
    state : inv, theta, acc of ``rank_one``, flat; updated.
    out : written: the measured vector (observation first, then y), the targets' bounds
        (sqrt of the diagonal of inv) and estimates, the sample's weight (1, or by the
        linear range when ``weighted``), and log det of the targets' information.
    """
    nd, k, ng, nt, nr, m, i_speed, n_obs, weighted = layout[:9]
    o_design = 9
    o_slot = o_design + ng
    o_range = o_slot + nd * (k - 1)
    o_place = o_range + nr
    p_count = nd
    p_wcoef = 2 * nd
    p_slot = p_wcoef + ng
    p_range = p_slot + nd * (k - 1) * 3
    inv = state[:nd * k * k].reshape((nd, k, k))
    theta = state[nd * k * k:nd * k * k + ng * k].reshape((ng, k))
    acc = state[nd * k * k + ng * k:]
    out[0] = t + noise[0]
    for i in range(values.shape[0]):
        out[i + 1] = values[i] + noise[i + 1]
    weight = 1.0
    if weighted:
        d = 0.0
        for r in range(nr):
            a = abs(values[layout[o_range + r]] - par[p_range + 2 * r]) * par[
                p_range + 2 * r + 1]
            if a > d:
                d = a
        weight = 1.0 if d <= 1.0 else max(0.0, 2.0 - d)
    speed = out[i_speed]
    x = np.empty((nd, k))
    for dd in range(nd):
        x[dd, 0] = 1.0
        for s in range(k - 1):
            j = dd * (k - 1) + s
            x[dd, s + 1] = (out[layout[o_slot + j]] - par[p_slot + 3 * j]) * (
                par[p_slot + 3 * j + 1] + par[p_slot + 3 * j + 2] / speed)
    if weight > 0.0:
        rank_one(inv, theta, layout[o_design:o_slot], par[:nd], par[p_count:p_wcoef], x,
                 out[n_obs:m], weight, acc)
    logdet = acc[0]
    for g in range(ng):
        logdet -= math.log1p(acc[1] * par[p_wcoef + g])
    for i in range(nt):
        dg, sl, g = layout[o_place + 3 * i], layout[o_place + 3 * i + 1], layout[
            o_place + 3 * i + 2]
        out[m + i] = math.sqrt(max(0.0, inv[dg, sl, sl]))
        out[m + nt + i] = theta[g, sl]
    out[m + 2 * nt] = weight
    out[m + 2 * nt + 1] = logdet
