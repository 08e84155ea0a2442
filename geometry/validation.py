"""Parameter validation shared by every package (geometry is the lowest layer).

Every check raises :class:`ParameterError` whose message names the parameter, the value
it got and the allowed range, e.g. ``gap = -0.0003 m: must be finite and > 0``. The CLI
turns a ParameterError into one line on stderr and exit status 2.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np


class ParameterError(ValueError):
    """A parameter is outside its allowed range (message names it, its value and the range)."""


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return repr(value)


def check_finite(name: str, value: Any, unit: str = "") -> float:
    """Return ``value`` as float; raise if it is not a finite real number."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name} = {value!r}: must be a finite number{_unit(unit)}")
    v = float(value)
    if not math.isfinite(v):
        raise ParameterError(f"{name} = {_fmt(v)}: must be finite{_unit(unit)}")
    return v


def check_positive(name: str, value: Any, unit: str = "") -> float:
    """Finite and > 0."""
    v = check_finite(name, value, unit)
    if v <= 0:
        raise ParameterError(f"{name} = {_fmt(v)}{unit}: must be finite and > 0")
    return v


def check_nonnegative(name: str, value: Any, unit: str = "") -> float:
    """Finite and >= 0."""
    v = check_finite(name, value, unit)
    if v < 0:
        raise ParameterError(f"{name} = {_fmt(v)}{unit}: must be finite and >= 0")
    return v


def check_range(
    name: str,
    value: Any,
    lo: float,
    hi: float,
    unit: str = "",
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """Finite and inside [lo, hi] (or open at either end)."""
    v = check_finite(name, value, unit)
    bad_lo = v <= lo if lo_open else v < lo
    bad_hi = v >= hi if hi_open else v > hi
    if bad_lo or bad_hi:
        lb = "(" if lo_open else "["
        hb = ")" if hi_open else "]"
        raise ParameterError(
            f"{name} = {_fmt(v)}{unit}: must be in {lb}{_fmt(lo)}, {_fmt(hi)}{hb}{unit}"
        )
    return v


def check_int(name: str, value: Any, lo: int, hi: int) -> int:
    """An integer in [lo, hi]."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ParameterError(f"{name} = {value!r}: must be an integer in [{lo}, {hi}]")
    v = int(value)
    if not lo <= v <= hi:
        raise ParameterError(f"{name} = {v}: must be an integer in [{lo}, {hi}]")
    return v


def check_choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    """One of a fixed set of strings."""
    if value not in choices:
        raise ParameterError(f"{name} = {value!r}: must be one of {', '.join(choices)}")
    return str(value)


def _unit(unit: str) -> str:
    return f" ({unit.strip()})" if unit else ""
