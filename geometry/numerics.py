"""Numerical kernels shared by every layer (geometry is the lowest): bracketed root finding
vectorised over many functions at once."""

from __future__ import annotations

from typing import Any

import numpy as np


def illinois(
    f: Any, lo: np.ndarray, hi: np.ndarray, flo: np.ndarray, fhi: np.ndarray, rtol: float
) -> np.ndarray:
    """Roots of f in the brackets [lo, hi] (f(lo), f(hi) of opposite signs), all at once:
    the Illinois variant of regula falsi ([dowell-jarratt1971]; superlinear, bracketed).
    ``f(act, x)`` evaluates the functions of the brackets ``act`` at ``x``. Each bracket
    is refined until hi − lo ≤ rtol·|hi| (or f = 0 exactly); returns the midpoints."""
    lo, hi, flo, fhi = (np.array(a, dtype=float) for a in (lo, hi, flo, fhi))
    side = np.zeros(lo.shape)
    act = np.nonzero(hi - lo > rtol * np.abs(hi))[0]
    for _ in range(200):
        if act.size == 0:
            break
        lo_a, hi_a, flo_a, fhi_a, sd = lo[act], hi[act], flo[act], fhi[act], side[act]
        x = hi_a - fhi_a * (hi_a - lo_a) / (fhi_a - flo_a)
        x = np.where(np.isfinite(x), x, 0.5 * (lo_a + hi_a))
        # at least δ from either end (Brent's minimum step, [numerical-recipes] §9.3): a root
        # within δ of an end is then straddled by the next bracket, of width ≤ δ
        d = 0.4 * rtol * np.abs(hi_a)
        x = np.clip(x, lo_a + d, hi_a - d)
        fx = f(act, x)
        left = fx * flo_a > 0  # x replaces lo
        hit = fx == 0
        flo[act] = np.where(left, fx, np.where(sd == -1, 0.5 * flo_a, flo_a))
        fhi[act] = np.where(left, np.where(sd == 1, 0.5 * fhi_a, fhi_a), fx)
        lo[act] = np.where(left | hit, x, lo_a)
        hi[act] = np.where(left & ~hit, hi_a, x)
        side[act] = np.where(left, 1.0, -1.0)
        act = act[hi[act] - lo[act] > rtol * np.abs(hi[act])]
    return 0.5 * (lo + hi)
