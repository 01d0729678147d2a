"""Refrigerant properties for the quasi-static cycle: CoolProp HEOS, tabulated once per fluid.

The cycle (``acid.plant.cycle``) needs, as functions of the saturation temperatures T_e
(evaporating) and T_c (condensing), with fixed superheat SH and subcooling SC:

* ``p_sat(T)``: saturation pressure, Pa;
* suction state 1 at (p_sat(T_e), T_e + SH): density ``rho1``, enthalpy ``h1``, entropy ``s1``;
* liquid-line state 3 at (p_sat(T_c), T_c - SC): enthalpy ``h3``;
* isentropic discharge enthalpy ``h2s(T_e, T_c)`` = h(p_sat(T_c), s1(T_e)).

These are evaluated with ``CoolProp.AbstractState("HEOS", fluid)`` (never ``PropsSI`` in a
loop) on a uniform grid: 0.5 K for the one-dimensional properties, 1 K x 1 K for ``h2s``, and
interpolated linearly with direct index arithmetic (a few hundred ns per lookup in plain
Python). Linear interpolation on these grids is accurate to better than 0.05 % in enthalpy
differences (checked in ``tests/test_plant_cycle.py`` against direct HEOS evaluations). The
table is built once per (fluid, SH, SC) and process (``functools.lru_cache``) and kept on
disk (``ACID_CACHE_DIR``, else ``$XDG_CACHE_HOME/acid`` or ``~/.cache/acid``; keyed by fluid,
SH, SC, grids and the CoolProp version), because importing CoolProp alone takes about 3 s:
with the disk cache a plant starts without importing it. Building takes about 0.3 s.
"""

from __future__ import annotations

import functools
import hashlib
import os
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

#: 1-D grid: -45 .. 90 degC (R1234yf's critical point is 94.7 degC), 0.5 K spacing.
T1_LO, T1_HI, DT1 = 228.15, 363.15, 0.5
#: 2-D grid for h2s: T_e in -40 .. 40 degC, T_c in -5 .. 90 degC, 1 K spacing.
TE_LO, TE_HI, TC_LO, TC_HI, DT2 = 233.15, 313.15, 268.15, 363.15, 1.0


@dataclass(frozen=True, eq=False)
class RefrigerantTable:
    """Tabulated properties of one refrigerant (SI units, K, Pa, J/kg, kg/m^3, J/(kg K)).

    One-dimensional arrays are on ``T1 = T1_LO + DT1 * i``; ``h2s[i, j]`` is on
    ``T_e = TE_LO + DT2 * i``, ``T_c = TC_LO + DT2 * j``. The ``*_list`` attributes hold the
    same numbers as Python lists (flat, row-major for ``h2s``) for fast scalar lookups.
    """

    fluid: str
    superheat: float
    subcool: float
    T1: np.ndarray
    p_sat: np.ndarray
    rho1: np.ndarray
    h1: np.ndarray
    s1: np.ndarray
    h3: np.ndarray
    Te2: np.ndarray
    Tc2: np.ndarray
    h2s: np.ndarray

    @property
    def lists(self) -> tuple[list, list, list, list, list]:
        """(p_sat, rho1, h1, h3, h2s_flat) as Python lists, for scalar index arithmetic."""
        return _lists(self)

    # Vectorised accessors (numpy), for tests and analysis; the cycle uses inlined lookups.
    def interp1(self, name: str, T) -> np.ndarray:
        """Linear interpolation of a 1-D property (``p_sat``, ``rho1``, ``h1``, ``s1``, ``h3``)."""
        return np.interp(np.asarray(T, dtype=float), self.T1, getattr(self, name))

    def interp_h2s(self, T_e, T_c) -> np.ndarray:
        """Bilinear interpolation of the isentropic discharge enthalpy, J/kg."""
        T_e, T_c = np.broadcast_arrays(np.asarray(T_e, float), np.asarray(T_c, float))
        x = np.clip((T_e - TE_LO) / DT2, 0.0, len(self.Te2) - 1.000001)
        y = np.clip((T_c - TC_LO) / DT2, 0.0, len(self.Tc2) - 1.000001)
        i, j = x.astype(int), y.astype(int)
        fx, fy = x - i, y - j
        h = self.h2s
        return ((1 - fx) * (1 - fy) * h[i, j] + fx * (1 - fy) * h[i + 1, j]
                + (1 - fx) * fy * h[i, j + 1] + fx * fy * h[i + 1, j + 1])


@functools.lru_cache(maxsize=8)
def _lists(table: RefrigerantTable):
    return (table.p_sat.tolist(), table.rho1.tolist(), table.h1.tolist(), table.h3.tolist(),
            table.h2s.ravel().tolist())


_ARRAYS = ("T1", "p_sat", "rho1", "h1", "s1", "h3", "Te2", "Tc2", "h2s")


def cache_dir() -> Path:
    """Folder of the on-disk property tables."""
    env = os.environ.get("ACID_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "acid"


def _cache_file(fluid: str, superheat: float, subcool: float) -> Path:
    try:
        cp_version = version("CoolProp")
    except PackageNotFoundError:
        cp_version = "unknown"
    key = repr((fluid, float(superheat), float(subcool), T1_LO, T1_HI, DT1, TE_LO, TE_HI,
                TC_LO, TC_HI, DT2, cp_version))
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    return cache_dir() / f"refrigerant-{fluid}-{digest}.npz"


@functools.lru_cache(maxsize=8)
def table(fluid: str = "R134a", superheat: float = 5.0, subcool: float = 5.0
          ) -> RefrigerantTable:
    """The property table of ``fluid`` (built with CoolProp HEOS on first use, then cached).

    Parameters
    ----------
    fluid : CoolProp fluid name, "R134a" or "R1234yf".
    superheat : suction superheat above T_e, K.
    subcool : liquid-line subcooling below T_c, K.
    """
    path = _cache_file(fluid, superheat, subcool)
    if path.is_file():
        try:
            with np.load(path) as z:
                arrays = {k: z[k] for k in _ARRAYS}
        except (OSError, ValueError, KeyError):
            arrays = None  # unreadable cache: rebuild below
        if arrays is not None:
            for arr in arrays.values():
                arr.setflags(write=False)
            return RefrigerantTable(fluid, float(superheat), float(subcool), **arrays)
    tab = _build(fluid, superheat, subcool)
    from acid._io import atomic_path
    from acid.errors import AcidError

    try:
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, **{k: getattr(tab, k) for k in _ARRAYS})
    except (OSError, AcidError):
        pass  # a read-only home or a full disk only costs the rebuild next time
    return tab


def _build(fluid: str, superheat: float, subcool: float) -> RefrigerantTable:
    """Evaluate the table with CoolProp HEOS (about 0.3 s plus CoolProp's import)."""
    from CoolProp import CoolProp as CP

    AS = CP.AbstractState("HEOS", fluid)
    T1 = T1_LO + DT1 * np.arange(int(round((T1_HI - T1_LO) / DT1)) + 1)
    n = T1.size
    p_sat, rho1, h1, s1, h3 = (np.empty(n) for _ in range(5))
    for k, T in enumerate(T1):
        AS.update(CP.QT_INPUTS, 1.0, T)
        p = AS.p()
        p_sat[k] = p
        AS.specify_phase(CP.iphase_gas)
        AS.update(CP.PT_INPUTS, p, T + superheat)
        rho1[k], h1[k], s1[k] = AS.rhomass(), AS.hmass(), AS.smass()
        AS.specify_phase(CP.iphase_liquid)
        AS.update(CP.PT_INPUTS, p, T - subcool)
        h3[k] = AS.hmass()
        AS.unspecify_phase()

    Te2 = TE_LO + DT2 * np.arange(int(round((TE_HI - TE_LO) / DT2)) + 1)
    Tc2 = TC_LO + DT2 * np.arange(int(round((TC_HI - TC_LO) / DT2)) + 1)
    pc = np.interp(Tc2, T1, p_sat)
    s_suc = np.interp(Te2, T1, s1)
    h_suc = np.interp(Te2, T1, h1)
    p_suc = np.interp(Te2, T1, p_sat)
    h2s = np.empty((Te2.size, Tc2.size))
    for i in range(Te2.size):
        for j in range(Tc2.size):
            if pc[j] <= p_suc[i]:
                h2s[i, j] = h_suc[i]  # no compression (pressure ratio <= 1)
                continue
            AS.update(CP.PSmass_INPUTS, pc[j], s_suc[i])
            h2s[i, j] = AS.hmass()
    for arr in (p_sat, rho1, h1, s1, h3, h2s):
        arr.setflags(write=False)
    return RefrigerantTable(fluid, float(superheat), float(subcool), T1, p_sat, rho1, h1, s1,
                            h3, Te2, Tc2, h2s)
