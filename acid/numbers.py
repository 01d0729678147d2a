"""How numbers are printed in reports: one helper, so that no table shows ``-0.00``."""

from __future__ import annotations

import math


def format_number(x, spec: str = ".3g") -> str:
    """``x`` formatted with the format ``spec``; "n/a" when missing or not finite.

    A value that rounds to zero is printed without a sign (``-1e-10`` with ``".2f"`` gives
    ``"0.00"``, not ``"-0.00"``).
    """
    try:
        x = float(x)
    except (TypeError, ValueError):
        return "n/a"
    if not math.isfinite(x):
        return "n/a"
    s = format(x, spec)
    if s.startswith("-") and float(s.rstrip("%")) == 0.0:
        s = s[1:]
    return s


def format_estimate(value, stderr=math.nan, low=math.nan, high=math.nan,
                    spec: str = ".4g", interval: bool = True) -> str:
    """``value ± stderr [low, high]`` (the parts that are finite), numbers as ``spec``."""
    out = format_number(value, spec)
    if _finite(stderr):
        out += f" ± {format_number(stderr, '.2g')}"
    if interval and _finite(low) and _finite(high):
        out += f" [{format_number(low, spec)}, {format_number(high, spec)}]"
    return out


def _finite(x) -> bool:
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False
