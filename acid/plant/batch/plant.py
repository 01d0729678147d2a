"""The high-fidelity plant stepped for B scenarios at once (numpy arrays of shape (B,)).

``BatchPlant`` runs the same model as ``acid.plant.hifi.HifiPlant`` (same equations, same
operation order, same refrigerant tables) for B members that may differ in their
configuration (ambient, humidity, solar, cabin, controller set-points and gains, initial
state), their inputs (blower flow, evaporator set-point, vehicle speed, ambient per sample)
and their length. Every member's cycle is solved by the same Newton iteration as
``acid.plant.cycle.make_solver``, vectorised: the members still iterating are gathered, their
state points looked up in the refrigerant tables with numpy index arithmetic, and each member
stops on its own convergence test, so a member takes exactly the iterations it takes alone.

Members must share the refrigerant tables (fluid, superheat, subcooling) and the time steps
(``Ts``, ``dt_int``); they may differ in the compressor map, UA values and motor losses (the
shipped vehicles in one batch: ``CycleParams`` holds a number where all members agree, an
array where they differ). The measurement noise is not modelled (deterministic plants
only). The trajectories equal the single plant's to rounding
(numpy's ``exp`` and ``**`` may differ from ``math``'s by an ulp); ``tests/test_plant_batch.py``
checks 1e-9 K and a relative 1e-9 on powers. Energy balances are not accumulated (use
``HifiPlant.balance`` for the check).

Each numpy call costs a few microseconds whatever B is, so one member alone runs about 20x
slower than ``HifiPlant``; per plant the batch runs 0.6x the single plant's speed at B = 16,
5-6x at B = 256 and 10-12x at B = 1024 (``benchmarks/bench_plant_batch.py``). The heating
plant's batch is ``acid.plant.batch.heating.BatchHeatingPlant``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from acid import __version__
from acid.errors import ConfigError, SolverWarning
from acid.plant import cycle as _cycle
from acid.plant import refrigerant as rf
from acid.plant.base import InputSchedule, checked_ambient
from acid.plant.config import PlantConfig
from acid.plant.hifi import (
    FAN_LEVELS,
    G_CA_NATURAL,
    INITIAL_KEYS,
    MODES,
    STATE_UNITS,
    humidity_ratio,
)

#: Configuration fields of the refrigerant cycle (tables, compressor map, UA values, motor
#: losses) and the time steps. Members may differ in all of them but ``SHARED_FIELDS``.
CYCLE_FIELDS = ("refrigerant", "superheat", "subcool", "V_disp", "eta_v0", "k_v", "c_L",
                "eta_is_max", "k_is", "PR_opt", "c_is_lo", "c_is_hi", "N_max", "UA_er0",
                "UA_cr0", "n_r", "m_r0", "dT_suc0", "P_loss0", "P_loss_N", "P_loss_cu",
                "P_rated", "Ts", "dt_int")
#: Fields every member must share: the refrigerant tables and the time steps.
SHARED_FIELDS = ("refrigerant", "superheat", "subcool", "Ts", "dt_int")
#: The cycle's per-member numbers (as ``make_solver`` takes them, derived ones included).
_PARAM_NAMES = ("eta_v0", "k_v", "c_L", "eta_is_max", "k_is", "PR_opt", "c_is_lo", "c_is_hi",
                "UA_er0", "UA_cr0", "n_r", "dT_suc0", "P_loss0", "P_loss_N", "P_loss_cu",
                "Vd60", "inv_Nmax", "inv_m0", "inv_Pr")


def check_shared(configs: Sequence[PlantConfig]) -> None:
    """Refuse (``ConfigError``, one line) members that differ in a ``SHARED_FIELDS`` field."""
    c0 = configs[0]
    for c in configs[1:]:
        diff = [f for f in SHARED_FIELDS if getattr(c, f) != getattr(c0, f)]
        if diff:
            raise ConfigError("batch plant members must share the refrigerant and the time "
                              f"steps; they differ in {', '.join(diff)}")


class CycleParams:
    """The cycle's numbers for a set of members: a float where every member has the same,
    an array (one per member) otherwise; ``take(idx)`` selects members."""

    __slots__ = (*_PARAM_NAMES, "varying")

    def __init__(self, values: dict, varying: tuple[str, ...]):
        for k, v in values.items():
            setattr(self, k, v)
        self.varying = varying

    @classmethod
    def of(cls, configs: Sequence[PlantConfig]) -> CycleParams:
        def one(c):
            return {"eta_v0": c.eta_v0, "k_v": c.k_v, "c_L": c.c_L,
                    "eta_is_max": c.eta_is_max, "k_is": c.k_is, "PR_opt": c.PR_opt,
                    "c_is_lo": c.c_is_lo, "c_is_hi": c.c_is_hi, "UA_er0": c.UA_er0,
                    "UA_cr0": c.UA_cr0, "n_r": c.n_r, "dT_suc0": c.dT_suc0,
                    "P_loss0": c.P_loss0, "P_loss_N": c.P_loss_N, "P_loss_cu": c.P_loss_cu,
                    "Vd60": c.V_disp / 60.0, "inv_Nmax": 1.0 / c.N_max,
                    "inv_m0": 1.0 / c.m_r0, "inv_Pr": 1.0 / c.P_rated}
        rows = [one(c) for c in configs]
        values, varying = {}, []
        for k in _PARAM_NAMES:
            col = [float(r[k]) for r in rows]
            if all(x == col[0] for x in col):
                values[k] = col[0]
            else:
                values[k] = np.array(col)
                varying.append(k)
        return cls(values, tuple(varying))

    def take(self, idx: np.ndarray) -> CycleParams:
        if not self.varying:
            return self
        out = CycleParams({k: getattr(self, k) for k in _PARAM_NAMES}, self.varying)
        for k in self.varying:
            setattr(out, k, getattr(self, k)[idx])
        return out

    def tile3(self) -> CycleParams:
        """The members three times over (the residual and its two neighbours)."""
        if not self.varying:
            return self
        out = CycleParams({k: getattr(self, k) for k in _PARAM_NAMES}, self.varying)
        for k in self.varying:
            x = getattr(self, k)
            setattr(out, k, np.concatenate((x, x, x)))
        return out


class BatchCycle:
    """The cycle solve of ``acid.plant.cycle.make_solver`` on arrays.

    ``configs``: one ``PlantConfig`` per member (or one for all); the members share the
    refrigerant tables and may differ in the compressor map, UA values and motor losses."""

    def __init__(self, configs: Sequence[PlantConfig] | PlantConfig):
        if isinstance(configs, PlantConfig):
            configs = [configs]
        configs = list(configs)
        check_shared(configs)
        config = configs[0]
        tab = rf.table(config.refrigerant, config.superheat, config.subcool)
        self.P, self.R = np.asarray(tab.p_sat, float), np.asarray(tab.rho1, float)
        self.H1, self.H3 = np.asarray(tab.h1, float), np.asarray(tab.h3, float)
        self.H2S = np.asarray(tab.h2s, float).ravel()
        self.nc = len(tab.Tc2)
        self.i1max, self.iemax, self.icmax = len(tab.p_sat) - 2, len(tab.Te2) - 2, self.nc - 2
        self.SH = config.superheat
        self.inv1, self.inv2 = 1.0 / rf.DT1, 1.0 / rf.DT2
        self.params = CycleParams.of(configs)
        self.size = len(configs)

    def _lin1(self, T):
        x = (T - rf.T1_LO) * self.inv1
        i = x.astype(np.int64)
        np.maximum(i, 0, out=i)
        np.minimum(i, self.i1max, out=i)
        return i, x - i

    def p_sat(self, T):
        """Saturation pressure (Pa) from the cycle's table, as ``hifi._p_sat_function``."""
        i, f = self._lin1(T)
        P = self.P
        return P[i] + f * (P[i + 1] - P[i])

    def state(self, Te, Tc, N, dTs, p: CycleParams | None = None):
        """Vectorised ``state`` of ``make_solver`` (same operations, element by element);
        ``p``: the members' parameters (default: all members, in order)."""
        c = self.params if p is None else p
        SH = self.SH
        P, R, H1, H3, H2S, nc = self.P, self.R, self.H1, self.H3, self.H2S, self.nc
        i, f = self._lin1(Te)
        pe = P[i] + f * (P[i + 1] - P[i])
        h1 = H1[i] + f * (H1[i + 1] - H1[i])
        Ts = Te - dTs
        i, f = self._lin1(Ts)
        ps = P[i] + f * (P[i + 1] - P[i])
        rho = (R[i] + f * (R[i + 1] - R[i])) * (Ts + SH) / (Te + SH)
        h1s = H1[i] + f * (H1[i + 1] - H1[i])
        j, f = self._lin1(Tc)
        pc = P[j] + f * (P[j + 1] - P[j])
        h3 = H3[j] + f * (H3[j + 1] - H3[j])
        x = (Ts - rf.TE_LO) * self.inv2
        i = x.astype(np.int64)
        np.maximum(i, 0, out=i)
        np.minimum(i, self.iemax, out=i)
        fe = x - i
        x = (Tc - rf.TC_LO) * self.inv2
        j = x.astype(np.int64)
        np.maximum(j, 0, out=j)
        np.minimum(j, self.icmax, out=j)
        fc = x - j
        k = i * nc + j
        h2s = ((1.0 - fe) * (H2S[k] + fc * (H2S[k + 1] - H2S[k]))
               + fe * (H2S[k + nc] + fc * (H2S[k + nc + 1] - H2S[k + nc])))
        PR = pc / ps
        PR = np.where(PR < 1.0, 1.0, PR)
        ev = c.eta_v0 - c.k_v * (PR - 1.0) - c.c_L / N
        ev = np.where(ev < 0.05, 0.05, ev)
        d = PR - c.PR_opt
        r = N * c.inv_Nmax
        ei = c.eta_is_max - c.k_is * d * d - c.c_is_lo / N - c.c_is_hi * r * r
        ei = np.where(ei < 0.2, 0.2, ei)
        dh = (h2s - h1s) * (Te + SH) / (Ts + SH)
        dh = np.where(dh < 0.0, 0.0, dh)
        m = ev * rho * c.Vd60 * N
        return m, pe, pc, h1, h1 + dh / ei, h3, ev, ei, ps

    def flow(self, Te, Tc, N, dTs, p: CycleParams | None = None):
        """The refrigerant mass flow of ``state`` alone (the same operations), kg/s."""
        c = self.params if p is None else p
        SH = self.SH
        P, R = self.P, self.R
        Ts = Te - dTs
        i, f = self._lin1(Ts)
        ps = P[i] + f * (P[i + 1] - P[i])
        rho = (R[i] + f * (R[i + 1] - R[i])) * (Ts + SH) / (Te + SH)
        j, f = self._lin1(Tc)
        pc = P[j] + f * (P[j + 1] - P[j])
        PR = pc / ps
        PR = np.where(PR < 1.0, 1.0, PR)
        ev = c.eta_v0 - c.k_v * (PR - 1.0) - c.c_L / N
        ev = np.where(ev < 0.05, 0.05, ev)
        return ev * rho * c.Vd60 * N

    def _residual(self, Te, Tc, N, Tew, Tcw, dTs, c: CycleParams):
        m, _, _, h1, h2, h3, _, _, _ = self.state(Te, Tc, N, dTs, c)
        g = (m * c.inv_m0) ** c.n_r
        return (c.UA_er0 * g * (Tew - Te) - m * (h1 - h3),
                c.UA_cr0 * g * (Tc - Tcw) - m * (h2 - h3))

    def solve(self, N, Tew, Tcw, Te, Tc, dTs, members=None):
        """Newton solves for members with N > 0 (all given arrays are those members').

        ``dTs`` is each member's warm-start suction drop (the previous solution's);
        ``members``: their indices in the configuration list (default: all, in order).
        Returns (T_e, T_c, m_r, Q_e, Q_c, P_el, W, p_s, p_c, dTs, iterations).
        """
        FD = _cycle._FD
        if members is None:
            members = np.arange(len(N))
        pm = self.params.take(members)
        varying = bool(pm.varying)
        Te = np.where(Te > Tew, Tew - 0.5, Te)
        Tc = np.where(Tc < Tcw, Tcw + 0.5, Tc)
        dTs = dTs.copy()
        its = np.zeros(len(N), dtype=np.int64)
        act = np.arange(len(N))
        full = True  # act is every member (no gather of the parameters needed)
        for it in range(1, _cycle._MAX_ITER + 1):
            if act.size == 0:
                break
            n_, tew, tcw = N[act], Tew[act], Tcw[act]
            te, tc, ds = Te[act], Tc[act], dTs[act]
            its[act] = it
            c = pm if (full or not varying) else pm.take(act)
            # the residual and its two finite-difference neighbours in one vectorised call
            na = act.size
            r1, r2 = self._residual(np.concatenate((te, te + FD, te)),
                                    np.concatenate((tc, tc, tc + FD)),
                                    np.concatenate((n_, n_, n_)),
                                    np.concatenate((tew, tew, tew)),
                                    np.concatenate((tcw, tcw, tcw)),
                                    np.concatenate((ds, ds, ds)), c.tile3())
            F1, a1, b1 = r1[:na], r1[na:2 * na], r1[2 * na:]
            F2, a2, b2 = r2[:na], r2[na:2 * na], r2[2 * na:]
            J11, J21 = (a1 - F1) / FD, (a2 - F2) / FD
            J12, J22 = (b1 - F1) / FD, (b2 - F2) / FD
            det = J11 * J22 - J12 * J21
            ok = det != 0.0  # a singular Jacobian ends that member's iteration unchanged
            all_ok = bool(ok.all())
            if not all_ok:
                det = np.where(ok, det, 1.0)
            dTe = (J22 * F1 - J12 * F2) / det
            dTc = (J11 * F2 - J21 * F1) / det
            adTe, adTc = np.abs(dTe), np.abs(dTc)
            big = np.where(adTe > adTc, adTe, adTc)
            damp = big > 8.0
            if damp.any():
                scale = np.where(damp, 8.0 / np.where(damp, big, 1.0), 1.0)
                dTe = np.where(damp, dTe * scale, dTe)
                dTc = np.where(damp, dTc * scale, dTc)
            te_n = te - dTe
            tc_n = tc - dTc
            te_n = np.where(te_n > tew, tew, te_n)
            tc_n = np.where(tc_n < tcw, tcw, tc_n)
            q = self.flow(te_n, tc_n, n_, ds, c) * c.inv_m0
            d_new = c.dT_suc0 * q * q
            change = np.abs(d_new - ds)
            if all_ok:
                Te[act], Tc[act], dTs[act] = te_n, tc_n, d_new
                done = (big < _cycle._TOL) & (change < _cycle._TOL_SUC)
            else:
                Te[act] = np.where(ok, te_n, te)
                Tc[act] = np.where(ok, tc_n, tc)
                dTs[act] = np.where(ok, d_new, ds)
                done = ~ok | ((big < _cycle._TOL) & (change < _cycle._TOL_SUC))
            if done.any():
                act = act[~done]
                full = False
        if act.size:
            for k in act:
                _warn_not_converged(N[k], Tew[k], Tcw[k])
        c = pm
        m, _, pc, h1, h2, h3, _, _, ps = self.state(Te, Tc, N, dTs, c)
        W = m * (h2 - h1)
        x = W * c.inv_Pr
        P_el = W + c.P_loss0 + c.P_loss_N * N * c.inv_Nmax + c.P_loss_cu * x * x
        return Te, Tc, m, m * (h1 - h3), m * (h2 - h3), P_el, W, ps, pc, dTs, its


def _warn_not_converged(N, Tew, Tcw) -> None:
    import warnings

    warnings.warn(f"cycle Newton solve did not converge at N = {N:.0f} rpm, "
                  f"T_ew = {Tew - 273.15:.2f} degC, T_cw = {Tcw - 273.15:.2f} degC; using the "
                  "last iterate", SolverWarning, stacklevel=4)


class BatchMembers:
    """What the batched plants share: per-member configuration arrays and the front end's
    tables (``hifi.front_end`` vectorised). Subclasses set ``cfgs``, ``B``, ``T_amb``,
    ``_arrays``, ``_ft``, ``_hA_cache`` and ``_fe_speed``."""

    cfgs: list[PlantConfig]
    T_amb: np.ndarray

    def _a(self, name: str) -> np.ndarray:
        """The members' values of configuration field ``name`` (cached; read-only)."""
        a = self._arrays.get(name)
        if a is None:
            a = self._arrays[name] = np.array([float(getattr(c, name)) for c in self.cfgs])
            a.setflags(write=False)
        return a

    def _front_rows(self, idx: np.ndarray, v: np.ndarray, T_amb: np.ndarray):
        """``hifi.front_end`` for members ``idx`` at speeds ``v`` and ambients ``T_amb`` (K),
        vectorised (the same operations): tables (5, k, L+1) of G_ca, P_fan, m_ca, s and the
        condenser wall's decay factor exp(-G_ca dt / C_cw); the recirculation rise (k,) and
        the fan floor level (k,)."""
        A = lambda name: self._a(name)[idx]  # noqa: E731
        v = np.where(self._fe_speed[idx], v, 0.0)
        rho = A("p_atm") / (287.05 * T_amb)
        cp = A("c_p_air")
        dp0, Q_free, K_front = A("dp_fan0"), A("Q_fan_free"), A("K_front")
        dp_ram = 0.5 * rho * A("C_ram") * v * v
        K_fan = dp0 / Q_free ** 2
        Q_off = np.sqrt(dp_ram / (K_front + A("K_fan_off")))
        Q_full0 = np.sqrt(dp0 / (K_front + K_fan))
        P_1 = dp0 * (1.0 - (Q_full0 / Q_free) ** 2) * Q_full0 / A("eta_fan")
        col = lambda x: x[:, None]  # noqa: E731
        s = np.broadcast_to(np.arange(FAN_LEVELS + 1) / FAN_LEVELS, (idx.size, FAN_LEVELS + 1))
        P = np.array([[si ** 3 for si in s[0]]]) * col(P_1)
        Q = np.sqrt((col(dp_ram) + col(dp0) * s * s) / col(K_front + K_fan))
        off = (s == 0.0) | (Q <= col(Q_off)) | (Q > s * col(Q_free))
        Q = np.where(off, col(Q_off), Q)
        P = np.where(off & (s != 0.0), 0.0, P)
        s = np.where(off, 0.0, s)
        m = col(rho) * Q
        mcp = m * col(cp)
        pos = m > 0.0
        msafe = np.where(pos, m, 1.0)
        UA = col(A("UA_ca0")) * (msafe / col(A("m_ca0"))) ** col(A("n_ca"))
        G = np.where(pos, mcp * (1.0 - np.exp(-UA / np.where(pos, mcp, 1.0))), 0.0)
        G = np.where(G > G_CA_NATURAL, G, G_CA_NATURAL)
        dt = self.cfgs[0].dt_int
        a = np.exp(-G * dt / col(A("C_cw")))
        zero = np.zeros(idx.size)
        rise = A("dT_recirc") * np.maximum(zero, 1.0 - v / A("v_recirc"))
        floor = A("s_fan_low") * np.maximum(zero, 1.0 - v / A("v_fan_off"))
        return (np.stack((G, P, m, s, a)), rise,
                np.round(floor * FAN_LEVELS).astype(np.int64))

    def _front_tables(self, v: np.ndarray):
        """Per member: the front end's tables at its speed and ambient, stacked (B, L+1);
        only the members whose speed or ambient changed are computed again."""
        if self._ft is None:
            L = FAN_LEVELS + 1
            self._ft = (np.full(self.B, np.nan), np.full(self.B, np.nan),
                        np.empty((5, self.B, L)), np.empty(self.B),
                        np.empty(self.B, dtype=np.int64))
        v_last, T_last, tabs, rise, floor = self._ft
        idx = np.nonzero((v != v_last) | (self.T_amb != T_last))[0]
        if idx.size:
            t, r, f = self._front_rows(idx, v[idx], self.T_amb[idx])
            tabs[:, idx], rise[idx], floor[idx] = t, r, f
            v_last[idx], T_last[idx] = v[idx], self.T_amb[idx]
        return tabs[0], tabs[1], tabs[2], tabs[3], tabs[4], rise, floor

    def _hA_ext(self, v_cab: np.ndarray) -> np.ndarray:
        out = np.empty(self.B)
        for b, c in enumerate(self.cfgs):
            key = (id(c), float(v_cab[b]))
            h = self._hA_cache.get(key)
            if h is None:
                if len(self._hA_cache) > 4096:
                    self._hA_cache.clear()
                h = self._hA_cache[key] = (c.hA_ext(key[1]), c)
            out[b] = h[0]
        return out


class BatchPlant(BatchMembers):
    """B high-fidelity plants stepped together; see the module docstring.

    Parameters
    ----------
    configs : one ``PlantConfig`` per member (or one shared config with ``size``).
    mode : "direct" or "nominal", for every member (as ``HifiPlant``).
    size : number of members when ``configs`` is a single config.
    """

    name = "hifi"

    def __init__(self, configs: Sequence[PlantConfig] | PlantConfig | None = None,
                 mode: str = "direct", size: int | None = None):
        if mode not in MODES:
            raise ConfigError(f"plant mode {mode!r} unknown (choose 'direct' or 'nominal')")
        if configs is None or isinstance(configs, PlantConfig):
            configs = [configs or PlantConfig()] * int(size or 1)
        self.cfgs = list(configs)
        if not self.cfgs:
            raise ConfigError("a batch plant needs at least one member")
        c0 = self.cfgs[0]
        check_shared(self.cfgs)
        self.B = len(self.cfgs)
        self.mode = mode
        self.Ts = float(c0.Ts)
        self.n_sub = int(round(self.Ts / c0.dt_int))
        self._cyc = BatchCycle(self.cfgs)
        self._hA_cache: dict = {}
        self._arrays: dict = {}
        self._ft = None
        self._fe_speed = np.array([bool(c.front_end_speed) for c in self.cfgs], bool)
        self._cabin_speed = np.array([bool(c.cabin_speed) for c in self.cfgs], bool)
        self._aw = np.array([bool(c.anti_windup) for c in self.cfgs], bool)
        self._a_N = np.array([math.exp(-c.dt_int / c.tau_N) for c in self.cfgs])
        self.reset()

    def reset(self, initial: Sequence[dict[str, float] | None] | None = None) -> dict:
        """Reset every member (as ``HifiPlant.reset``); ``initial``: one dict (or None) each."""
        from acid.plant.hifi import HifiPlant

        initial = list(initial) if initial is not None else [None] * self.B
        if len(initial) != self.B:
            raise ConfigError(f"{len(initial)} initial states for {self.B} batch members")
        # the single plant's own reset gives each member's start (validation included)
        starts = []
        for c, init in zip(self.cfgs, initial, strict=True):
            p = HifiPlant(c, mode=self.mode)
            p.reset(init)
            starts.append(p)
        g = lambda name: np.array([float(getattr(p, name)) for p in starts])  # noqa: E731
        self.T_amb, self.w_amb = g("T_amb"), g("w_amb")
        self.T_cab, self.T_int, self.T_shell = g("T_cab"), g("T_int"), g("T_shell")
        self.T_int_slow, self.T_ew, self.T_cw = g("T_int_slow"), g("T_ew"), g("T_cw")
        self.w_cab, self.N, self.T_e, self.T_c = g("w_cab"), g("N"), g("T_e"), g("T_c")
        self.p_c, self.p_s, self.T_reset = g("p_c"), g("p_s"), g("T_reset")
        self.cut_out = np.array([p.cut_out for p in starts], bool)
        self.ac_demand = np.array([p.ac_demand for p in starts], bool)
        self.comp_on = np.array([p._comp.on for p in starts], bool)
        self.comp_integ = np.array([float(p._comp.integ) for p in starts])
        self.bl_integ = np.array([float(p._blower.integ) for p in starts])
        self.dTs = np.zeros(self.B)  # each member's suction-drop warm start
        self.t = 0.0
        return self.measure()

    def measure(self) -> dict[str, np.ndarray]:
        """Every member's states, keyed as ``HifiPlant.measure`` (arrays of shape (B,))."""
        return {"T_cab": self.T_cab.copy(), "T_evap": self.T_ew.copy(),
                "T_int": self.T_int.copy(), "T_shell": self.T_shell.copy(),
                "T_amb": self.T_amb.copy(), "w_cab": self.w_cab.copy(),
                "T_cw": self.T_cw.copy(), "T_int_slow": self.T_int_slow.copy(),
                "N_comp_state": self.N.copy(), "comp_integrator": self.comp_integ.copy(),
                "blower_integrator": self.bl_integ.copy(),
                "T_evap_set_eff": self._a("T_ew_set") + self.T_reset,
                "ac_state": self.comp_on.astype(float), "cut_out": self.cut_out.astype(float),
                "ac_demand": self.ac_demand.astype(float), "T_e_last": self.T_e.copy(),
                "T_c_last": self.T_c.copy(),
                "p_dis_last": np.where(self.p_c == self.p_c, self.p_c, 0.0)}

    def step(self, W_bl, T_evap_set, v_veh=0.0, T_amb=None, T_cab_set=None,
             compressor_enabled=None) -> dict[str, np.ndarray]:
        """Advance every member one sample period (``HifiPlant.step``, element by element).

        Inputs are arrays of shape (B,) (scalars broadcast); ``T_amb``, ``T_cab_set`` (K)
        and ``compressor_enabled`` as the single plant's keywords, None for its defaults.
        Returns row k as ``HifiPlant.step`` does, each channel an array of shape (B,).
        """
        B, cfgs, cyc = self.B, self.cfgs, self._cyc
        A = self._a
        nominal = self.mode == "nominal"
        shape = (B,)
        enabled = (np.ones(shape, bool) if compressor_enabled is None
                   else np.broadcast_to(np.asarray(compressor_enabled, bool), shape).copy())
        T_cab_set = (A("T_cab_set") if T_cab_set is None
                     else np.broadcast_to(np.asarray(T_cab_set, float), shape).copy())
        T_set_in = (A("T_ew_set") if nominal
                    else np.broadcast_to(np.asarray(T_evap_set, float), shape).copy())
        v = np.broadcast_to(np.asarray(v_veh, float), shape).copy()
        if T_amb is not None:
            T_amb = np.broadcast_to(np.asarray(T_amb, float), shape)
            for b in range(B):
                T_k = checked_ambient(T_amb[b])
                if T_k != self.T_amb[b]:
                    c = cfgs[b]
                    self.T_amb[b] = T_k
                    self.w_amb[b] = humidity_ratio(T_k, c.RH_amb, c.p_atm)
        if not np.all(np.isfinite(v) & (v >= 0.0)):
            raise ConfigError(f"vehicle speed must be a finite non-negative number, got {v}")
        if not nominal:
            W_cmd = np.broadcast_to(np.asarray(W_bl, float), shape).copy()
            if not (np.all(np.isfinite(W_cmd)) and np.all(np.isfinite(T_set_in))):
                raise ConfigError("non-finite input W_bl or T_evap_set")
            W_cmd = np.minimum(np.maximum(W_cmd, A("W_bl_min")), A("W_bl_max"))
        else:
            W_cmd = np.zeros(shape)
        row = self.measure()

        c0 = cfgs[0]
        dt, n = c0.dt_int, self.n_sub
        cp = A("c_p_air")
        T_amb, w_amb, p_atm = self.T_amb, self.w_amb, A("p_atm")
        G_st, P_st, m_st, s_st_tab, a_st, rise, lev_floor = self._front_tables(v)
        T_ca_in = T_amb + rise
        v_cab = np.where(self._cabin_speed, v, 0.0)
        fan_x = FAN_LEVELS / (A("p_fan_high") - A("p_fan_low"))
        hA_ext = self._hA_ext(v_cab)
        m_inf = A("m_inf0") + A("k_inf") * v_cab
        Ginf = m_inf * cp
        hA_int, hA_sh, hA_is, C_cab = A("hA_int"), A("hA_sh"), A("hA_int_slow"), A("C_cab")
        M_cab = C_cab / cp
        k_int, k_is, k_sh = dt / A("C_int"), dt / A("C_int_slow"), dt / A("C_sh")
        Q_si, Q_ss = A("Q_solar_int"), A("Q_solar_shell")
        Q_pass, m_moist = A("Q_pass"), A("m_moist_pass")
        UA_ea0, W_ea0, n_ea, C_ew, h_fg = A("UA_ea0"), A("W_ea0"), A("n_ea"), A("C_ew"), A("h_fg")
        b1, b2, b3, f_bh = A("beta1"), A("beta2"), A("beta3"), A("f_bl_heat")
        k_rec, r_max = A("k_rec"), A("r_max")
        W_min, W_max = A("W_bl_min"), A("W_bl_max")
        a_N = self._a_N
        N_min, N_max = A("N_min"), A("N_max")
        p_fl, p_der, p_cut = A("p_fan_low"), A("p_derate"), A("p_cut")
        k_der = (N_max - N_min) / (p_cut - p_der)
        T_e_min, K_frost = A("T_e_min"), A("K_frost")
        reset_max = A("T_ew_set_max") - A("T_ew_set")
        k_reset = A("k_reset")
        Kp_c, Ki_c, h_off, h_on = A("Kp_comp"), A("Ki_comp"), A("hyst_off"), A("hyst_on")
        aw = self._aw
        Kp_b, Ki_b = A("Kp_bl"), A("Ki_bl")
        exp = np.exp
        rows_idx = np.arange(B)

        T_cab, T_int, T_is, T_sh = self.T_cab, self.T_int, self.T_int_slow, self.T_shell
        T_ew, T_cw, w_cab, N = self.T_ew, self.T_cw, self.w_cab, self.N
        T_e, T_c, p_c, p_s = self.T_e, self.T_c, self.p_c, self.p_s
        T_reset, cut, demand = self.T_reset, self.cut_out, self.ac_demand
        on, integ, bl_integ, dTs = self.comp_on, self.comp_integ, self.bl_integ, self.dTs
        z = np.zeros(shape)
        s_W, s_Pbl, s_Pc, s_Qe, s_Qc, s_Qlat = z.copy(), z.copy(), z.copy(), z.copy(), z.copy(), \
            z.copy()
        s_Tain, s_N, s_r, s_Te, s_Tc, s_on = z.copy(), z.copy(), z.copy(), z.copy(), z.copy(), \
            z.copy()
        s_Pf, s_W_sh, s_ps, s_pc, s_m, s_mca = z.copy(), z.copy(), z.copy(), z.copy(), z.copy(), \
            z.copy()
        s_st, s_Tset = z.copy(), z.copy()

        for _ in range(n):
            if nominal:  # BlowerLoop.update, element by element
                e = T_cab - T_cab_set
                u = Kp_b * e + bl_integ
                hold = aw & (((u >= W_max) & (e > 0.0)) | ((u <= W_min) & (e < 0.0)))
                bl_integ = np.where(hold, bl_integ, bl_integ + Ki_b * e * dt)
                W = np.where(u < W_min, W_min, np.where(u > W_max, W_max, u))
                e_cab = T_cab - T_cab_set
                lower = demand & ((e_cab > 0.0) | (W <= W_min))
                T_r = T_reset - k_reset * e_cab * dt
                T_r = np.where(T_r < 0.0, 0.0, np.where(T_r > reset_max, reset_max, T_r))
                T_reset = np.where(lower, T_r, T_reset)
                off = demand & (T_reset >= reset_max) & (e_cab < -0.5)
                back = ~demand & (e_cab > 0.5)
                demand = (demand & ~off) | back
                T_set = T_set_in + T_reset
            else:
                W = W_cmd
                T_set = T_set_in
            # protections on the last cycle state: head-pressure cut-out/derate, frost
            ran = p_c == p_c
            cut = np.where(ran & (p_c > p_cut), True,
                           np.where(ran & cut & (p_c < p_cut - 6.0e5), False, cut))
            N_cap = N_max
            N_cap = np.where(ran & (p_c > p_der), N_cap - k_der * (p_c - p_der), N_cap)
            N_cap = np.where(ran & (T_e < T_e_min), N_cap - K_frost * (T_e_min - T_e), N_cap)
            N_cap = np.where(ran & (N_cap < N_min), N_min, N_cap)
            # CompressorLoop.update, element by element
            en = enabled & demand & ~cut
            e = T_ew - T_set
            stop = ~en | (on & (e < -h_off))
            start = en & ~on & (e > h_on)
            idle = en & ~on & ~(e > h_on)
            on = np.where(stop, False, on | start)
            integ = np.where(stop, N_min, integ)
            run = en & ~stop & ~idle
            u = Kp_c * e + integ
            hold = aw & (((u >= N_cap) & (e > 0.0)) | ((u <= N_min) & (e < 0.0)))
            integ = np.where(run & ~hold, integ + Ki_c * e * dt, integ)
            integ = np.where(run & aw & (integ > N_cap), N_cap, integ)
            N_cmd = np.where(run, np.where(u < N_min, N_min, np.where(u > N_cap, N_cap, u)), 0.0)
            N = N_cmd + (N - N_cmd) * a_N
            N = np.where((N < 1.0) & (N_cmd == 0.0), 0.0, N)
            runs = N > 0.0
            x = np.where(runs & ran, (np.where(ran, p_c, p_fl) - p_fl) * fan_x + 0.5, 0.0)
            st = x.astype(np.int64)
            st = np.where(st < lev_floor, lev_floor, np.where(st > FAN_LEVELS, FAN_LEVELS, st))
            st = np.where(runs & ran, st, np.where(runs, lev_floor, 0))
            G_ca = G_st[rows_idx, st]
            # air mixing, blower heat
            r = k_rec * (T_amb - T_cab)
            r = np.where(r < 0.0, 0.0, np.where(r > r_max, r_max, r))
            P_bl = (b1 * W + b2) * W + b3
            Wcp = W * cp
            T_mix = T_amb + r * (T_cab - T_amb) + f_bh * P_bl / Wcp
            w_mix = w_amb + r * (w_cab - w_amb)
            eps = 1.0 - exp(-UA_ea0 * (W / W_ea0) ** n_ea / Wcp)
            G_a = eps * Wcp
            t_ew = T_ew - 273.15
            p_ws = 611.2 * exp(17.62 * t_ew / (243.12 + t_ew))
            w_sat = 0.621945 * p_ws / (p_atm - p_ws)
            wet = w_mix > w_sat
            w_ain = np.where(wet, w_mix - eps * (w_mix - w_sat), w_mix)
            Q_lat = np.where(wet, W * (w_mix - w_ain) * h_fg, 0.0)
            # refrigerant cycle: Newton on the running members, walls' saturation otherwise
            T_e, T_c = T_ew.copy(), T_cw.copy()
            m_r, Q_e, Q_c, P_c, W_sh = z.copy(), z.copy(), z.copy(), z.copy(), z.copy()
            p_c = np.full(shape, math.nan)
            p_s = np.full(shape, math.nan)
            s_ps += np.where(runs, 0.0, cyc.p_sat(T_ew))
            s_pc += np.where(runs, 0.0, cyc.p_sat(T_cw))
            k = np.nonzero(runs)[0]
            if k.size:
                out = cyc.solve(N[k], T_ew[k], T_cw[k], self.T_e[k], self.T_c[k], dTs[k], k)
                (T_e[k], T_c[k], m_r[k], Q_e[k], Q_c[k], P_c[k], W_sh[k], p_s[k], p_c[k],
                 dTs[k]) = out[:10]
                s_ps[k] += p_s[k]
                s_pc[k] += p_c[k]
            self.T_e, self.T_c = T_e, T_c
            # thermal masses (exponential Euler on each node's own term)
            Tinf = T_mix + (Q_lat - Q_e) / G_a
            T_ew_n = Tinf + (T_ew - Tinf) * exp(-G_a * dt / C_ew)
            T_ain = T_mix - eps * (T_mix - 0.5 * (T_ew + T_ew_n))
            Tinf = T_ca_in + Q_c / G_ca
            T_cw_n = Tinf + (T_cw - Tinf) * a_st[rows_idx, st]
            G = hA_int + hA_sh + Wcp + Ginf
            Tinf = (hA_int * T_int + hA_sh * T_sh + Wcp * T_ain + Ginf * T_amb + Q_pass) / G
            T_cab_n = Tinf + (T_cab - Tinf) * exp(-G * dt / C_cab)
            T_int_n = T_int + k_int * (Q_si + hA_int * (T_cab - T_int) + hA_is * (T_is - T_int))
            T_is = T_is + k_is * hA_is * (T_int - T_is)
            T_sh_n = T_sh + k_sh * (Q_ss + hA_ext * (T_amb - T_sh) + hA_sh * (T_cab - T_sh))
            winf = (W * w_ain + m_inf * w_amb + m_moist) / (W + m_inf)
            w_cab_n = winf + (w_cab - winf) * exp(-(W + m_inf) * dt / M_cab)
            T_ew, T_cw, T_cab, T_int, T_sh = T_ew_n, T_cw_n, T_cab_n, T_int_n, T_sh_n
            w_cab = w_cab_n
            s_W += W
            s_Pbl += P_bl
            s_Pc += P_c
            s_W_sh += W_sh
            s_Qe += Q_e
            s_Qc += Q_c
            s_Qlat += Q_lat
            s_Tain += T_ain
            s_N += N
            s_r += r
            s_Te += T_e
            s_Tc += T_c
            s_on += on
            s_Pf += P_st[rows_idx, st]
            s_m += m_r
            s_mca += m_st[rows_idx, st]
            s_st += s_st_tab[rows_idx, st]
            s_Tset += T_set

        self.T_cab, self.T_int, self.T_int_slow, self.T_shell = T_cab, T_int, T_is, T_sh
        self.T_ew, self.T_cw, self.w_cab, self.N = T_ew, T_cw, w_cab, N
        self.T_e, self.T_c, self.p_c, self.p_s = T_e, T_c, p_c, p_s
        self.T_reset, self.cut_out, self.ac_demand = T_reset, cut, demand
        self.comp_on, self.comp_integ, self.bl_integ, self.dTs = on, integ, bl_integ, dTs
        self.t += n * dt
        inv = 1.0 / n
        P_comp = s_Pc * inv
        Q_evap = s_Qe * inv
        row.update(
            T_ain=s_Tain * inv, W_bl=s_W * inv, T_evap_set=s_Tset * inv, v_veh=v,
            N_comp=s_N * inv, P_comp=P_comp, P_bl=s_Pbl * inv, P_fan=s_Pf * inv,
            COP=np.where(P_comp > 0.0, Q_evap / np.where(P_comp > 0.0, P_comp, 1.0), 0.0),
            recirc=s_r * inv, Q_evap=Q_evap, Q_cond=s_Qc * inv, Q_lat=s_Qlat * inv,
            W_comp=s_W_sh * inv, T_e=s_Te * inv, T_c=s_Tc * inv, ac_on=s_on * inv,
            p_suc=s_ps * inv, p_dis=s_pc * inv,
            m_r=s_m * inv, m_ca=s_mca * inv, fan_speed=s_st * inv,
        )
        return row

    def run(self, schedules: Sequence[InputSchedule],
            initial: Sequence[dict[str, float] | None] | None = None
            ) -> list[dict[str, np.ndarray]]:
        """Reset and run one schedule per member; per member, its channels as (n_b,) arrays
        (kelvin inside). Members may differ in length: a member that has ended holds its last
        inputs while the others go on, and its rows stop at its own length."""
        if len(schedules) != self.B:
            raise ConfigError(f"{len(schedules)} schedules for {self.B} batch members")
        for s in schedules:
            if abs(s.Ts - self.Ts) > 1e-9:
                raise ConfigError(f"schedule sample time {s.Ts} s differs from the plant's "
                                  f"{self.Ts} s")
            if len(s) == 0:
                raise ConfigError("an empty schedule in the batch")
        lens = np.array([len(s) for s in schedules])
        n = int(lens.max())

        def padded(name):
            cols = [getattr(s, name) for s in schedules]
            if all(x is None for x in cols):
                return None
            out = np.empty((n, self.B))
            for b, (s, x) in enumerate(zip(schedules, cols, strict=True)):
                if x is None:
                    x = np.full(len(s), self.cfgs[b].T_amb)  # only T_amb reaches here
                out[:len(x), b] = x
                out[len(x):, b] = x[-1]
            return out

        W, Tset, v = padded("W_bl"), padded("T_evap_set"), padded("v_veh")
        Tamb = padded("T_amb")
        self.reset(initial)
        cols: dict[str, np.ndarray] = {}
        for k in range(n):
            row = self.step(W[k], Tset[k], v[k], T_amb=None if Tamb is None else Tamb[k])
            if not cols:
                cols = {name: np.empty((n, self.B)) for name in row}
            for name, x in row.items():
                cols[name][k] = x
        return [{name: x[:lens[b], b] for name, x in cols.items()} for b in range(self.B)]

    def simulate(self, schedules: Sequence[InputSchedule],
                 initial: Sequence[dict[str, float] | None] | None = None,
                 metadata: dict | None = None) -> list:
        """``HifiPlant.simulate`` for every member: one ``Dataset`` each (degC storage)."""
        out = []
        for b, (cols, s) in enumerate(zip(self.run(schedules, initial), schedules, strict=True)):
            d = self.cfgs[b].to_dict()
            d.update(mode=self.mode, meas_noise_std_K=0.0)
            meta = {"plant": self.name, "plant_config": d, "excitation": s.spec,
                    "acid_version": __version__}
            if "seed" in s.spec:
                meta["seed"] = s.spec["seed"]
            meta.update(metadata or {})
            out.append(_dataset(cols, self.Ts, meta, dict(STATE_UNITS)))
        return out


def _dataset(cols: dict[str, np.ndarray], Ts: float, metadata: dict, units: dict[str, str]):
    """``measurements_to_dataset`` on columns (the same units and conversions)."""
    from acid.data import CHANNELS, Dataset
    from acid.plant.base import guess_unit
    from acid.units import K2C, is_temperature

    channels, out_units = {}, {}
    for name, v in cols.items():
        v = np.array(v, dtype=float)
        unit = CHANNELS[name].unit if name in CHANNELS else (units.get(name)
                                                             or guess_unit(name))
        if is_temperature(unit):
            v, unit = K2C(v), "degC"
        channels[name], out_units[name] = v, unit
    time = np.arange(len(next(iter(cols.values())))) * Ts
    return Dataset(time=time, channels=channels, units=out_units, Ts=Ts, metadata=metadata)


__all__ = ["CYCLE_FIELDS", "INITIAL_KEYS", "SHARED_FIELDS", "BatchCycle", "BatchPlant",
           "CycleParams", "check_shared"]
