#!/usr/bin/env python3
"""Independent scipy reference of the *improved 2-DOF* slider model (dynamics.md §5.1).

Written from /work/shared/spec/dynamics.md (§1.1, §1.2, §2.1–2.4, §3.1, §3.2, §3.4, §4, §5.1,
§5.3, §5.4, §6, §7 S2, §8, §10, §11.1–11.2, §12) and the ISBL per-unit-area table
tests/data/isbl/improved_2dof.csv, without looking at the project's Rust sources.
It serves (1) as a cross-check of the Rust implementation and (2) as the scipy `solve_ivp`
side of a speed comparison.

State y = [z, ϑ, ż, ϑ̇]: COM heave from the nominal state and pitch increment ϑ = θ − θ0.
All internal quantities SI; reports in nm / mN / %.

Usage (see bench/README.md):
    python bench/two_dof_scipy.py --actuation 8.5 --synthetic-dmw
    python bench/two_dof_scipy.py --sweep 9 12 0.25 --synthetic-dmw --jobs 2
"""
from __future__ import annotations

import argparse
import bisect
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field, asdict

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator
from scipy.optimize import fsolve

NM = 1e-9
HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_ISBL = os.path.join(HERE, "..", "tests", "data", "isbl", "improved_2dof.csv")


# ----------------------------------------------------------------------------------------
# Parameters (§11.1, §11.2; [assumption] defaults of the spec)
# ----------------------------------------------------------------------------------------
@dataclass
class Params:
    # slider (Tab 2.1 / §11.1)
    l: float = 1.23e-3
    l_w: float = 0.70e-3
    l_t: float = 0.30e-3
    rho: float = 4250.0              # AlTiC density [assumption] -> m = 1.098 mg
    theta0: float = 100e-6
    FH_nom: float = 11e-9            # anchored at the TE: s_TE = FH_nom + T0
    k_susp: float = 10.0             # suspension heave stiffness k
    k_theta: float = 5e-5            # pitch stiffness [assumption]
    zeta_susp: float = 0.02          # ζ, ζ_θ
    zeta_ab: float = 0.03            # ζ_f, ζ_r
    zeta_c: float = 0.05             # contact damping ratio
    f1_ab: float = 110e3             # 1st pitch [assumption]
    f2_ab: float = 300e3             # 2nd pitch [assumption]
    beta_kr: float = 1.0             # rear-spring stiffening amplitude β
    # TFC bulge (Tab 2.1)
    a_tfc: float = 3e-6
    w_tfc: float = 50e-6             # full width (y semi-axis w/2)
    x_tfc: float = 8e-6              # ellipsoid centre from the TE
    # interface (§11.2)
    sigma: float = 0.5e-9
    T0: float = 0.75e-9
    t_lube: float = 1.5e-9
    eps_lj: float = 0.3e-9           # LJ ε for the F_s tail above the table (contact-isbl §6.4)
    # DMW
    U: float = 19.5                  # disk speed
    transit_delay: bool = True
    # switches
    contact_force: str = "interference_tangent"   # | "static_curve"
    interface: bool = True           # False: no interfacial forces at all
    ab_lost_FH: float = 15e-9        # AB-loss guard on the TE FH (= s_TE − T0)

    @property
    def m(self):
        return self.rho * self.l * self.l_w * self.l_t

    @property
    def J(self):
        return self.m * (self.l ** 2 + self.l_t ** 2) / 12.0


# ----------------------------------------------------------------------------------------
# §3.1 modal inversion (stiff rear), refined with the suspension terms
# ----------------------------------------------------------------------------------------
def ab_matrices(p: Params, kf, kr):
    L2 = p.l / 2
    K = np.array([[p.k_susp + kf + kr, L2 * (kf - kr)],
                  [L2 * (kf - kr), p.k_theta + L2 * L2 * (kf + kr)]])
    M = np.diag([p.m, p.J])
    return M, K


def modal_inversion(p: Params):
    m, J, d = p.m, p.J, p.l / 2
    lam1, lam2 = (2 * math.pi * p.f1_ab) ** 2, (2 * math.pi * p.f2_ab) ** 2
    A = 1 / m + d * d / J
    S = (lam1 + lam2) / A                     # k_f + k_r
    Pr = lam1 * lam2 * m * J / (2 * d) ** 2   # k_f k_r
    disc = S * S - 4 * Pr
    if disc < 0:
        raise ValueError("frequency ratio too small for a real root pair")
    k_small, k_big = (S - math.sqrt(disc)) / 2, (S + math.sqrt(disc)) / 2
    kf, kr = k_small, k_big                   # stiff rear

    def resid(x):
        M, K = ab_matrices(p, x[0], x[1])
        ev = np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)
        return [ev[0] / lam1 - 1, ev[1] / lam2 - 1]

    sol = fsolve(resid, [kf, kr], xtol=1e-14)
    return float(sol[0]), float(sol[1]), (k_small, k_big)


# ----------------------------------------------------------------------------------------
# ISBL curves: PCHIP on ln y vs h* (scalar, fast), monotone inversion of p
# ----------------------------------------------------------------------------------------
class Pchip1D:
    """Scalar evaluation of a scipy PCHIP on a uniform grid (piecewise cubic coefficients)."""

    def __init__(self, x, y):
        pc = PchipInterpolator(x, y, extrapolate=True)
        self.x0 = float(x[0])
        self.dx = float(x[1] - x[0])
        self.n = len(x) - 1
        self.xs = [float(v) for v in x]
        self.c = [tuple(float(v) for v in pc.c[:, i]) for i in range(self.n)]
        self.ys = [float(v) for v in y]
        self._pc = pc

    def idx(self, x):
        i = int((x - self.x0) // self.dx)
        return 0 if i < 0 else (self.n - 1 if i >= self.n else i)

    def __call__(self, x):
        i = self.idx(x)
        c0, c1, c2, c3 = self.c[i]
        u = x - self.xs[i]
        return ((c0 * u + c1) * u + c2) * u + c3

    def solve_in(self, i, target):
        """x in interval i with value = target (monotone cubic): Newton + bisection safeguard."""
        c0, c1, c2, c3 = self.c[i]
        lo, hi = 0.0, self.dx
        flo, fhi = self.ys[i] - target, self.ys[i + 1] - target
        # linear guess
        u = lo + (hi - lo) * flo / (flo - fhi) if flo != fhi else 0.5 * self.dx
        for _ in range(60):
            f = ((c0 * u + c1) * u + c2) * u + c3 - target
            df = (3 * c0 * u + 2 * c1) * u + c2
            if (f > 0) == (flo > 0):
                lo, flo = u, f
            else:
                hi = u
            un = u - f / df if df != 0 else 0.5 * (lo + hi)
            if not (lo < un < hi):
                un = 0.5 * (lo + hi)
            if abs(un - u) < 1e-15:
                u = un
                break
            u = un
        return self.xs[i] + u


class Isbl:
    """Per-unit-nominal-area ISBL curves of the improved interface vs solid separation h (m)."""

    def __init__(self, path, p: Params):
        data = np.genfromtxt(path, delimiter=",", names=True)
        self.sigma = p.sigma
        hs = data["h_star"]
        if not np.allclose(data["h_m"], hs * p.sigma, rtol=1e-9, atol=1e-20):
            raise ValueError("table h_m != h_star*sigma: sigma mismatch")
        self.hs_min, self.hs_max = float(hs[0]), float(hs[-1])
        self.lnP = Pchip1D(hs, np.log(data["P_Pa"]))
        self.lnkc = Pchip1D(hs, np.log(data["kc_Pa_per_m"]))
        self.lnQ = Pchip1D(hs, np.log(data["Q_Pa"]))
        self.lnAr = Pchip1D(hs, np.log(data["Ar_frac"]))
        self.lnFs = Pchip1D(hs, np.log(data["Fs_const_Pa"]))
        self.lnP_nodes_neg = [-v for v in self.lnP.ys]  # increasing, for bisect
        # F_s tail above the table (contact-isbl §6.4), matched at the last node
        self.t, self.eps = p.t_lube, p.eps_lj
        self.Fs_last = float(data["Fs_const_Pa"][-1])
        self.tail_last = self._tail(self.hs_max * p.sigma)
        self.out_below = 0

    def _tail(self, h):
        D = h - self.t + self.eps
        r = self.eps / D
        return r * r * (1 + 3 * self.sigma ** 2 / (D * D))

    def fs(self, h):
        """adhesion stress F_s(h) [Pa]"""
        x = h / self.sigma
        if x > self.hs_max:
            return self.Fs_last * self._tail(h) / self.tail_last
        return math.exp(self.lnFs(x))

    def kc(self, h):
        x = h / self.sigma
        if x > self.hs_max:
            return 0.0
        return math.exp(self.lnkc(x))

    def p(self, h):
        x = h / self.sigma
        return 0.0 if x > self.hs_max else math.exp(self.lnP(x))

    def q(self, h):
        x = h / self.sigma
        return 0.0 if x > self.hs_max else math.exp(self.lnQ(x))

    def ar(self, h):
        x = h / self.sigma
        return 0.0 if x > self.hs_max else math.exp(self.lnAr(x))

    def p_inv(self, pressure):
        """h* with p(h*) = pressure (monotone inversion of the same PCHIP)."""
        L = math.log(pressure)
        # nodes of -lnP increasing; find interval
        j = bisect.bisect_right(self.lnP_nodes_neg, -L) - 1
        if j < 0:
            self.out_below += 1
            j = 0  # beyond the deepest node: extrapolate the first cubic
            # Newton on the extrapolated cubic
            c0, c1, c2, c3 = self.lnP.c[0]
            u = 0.0
            for _ in range(60):
                f = ((c0 * u + c1) * u + c2) * u + c3 - L
                df = (3 * c0 * u + 2 * c1) * u + c2
                du = f / df
                u -= du
                if abs(du) < 1e-15:
                    break
            return self.lnP.xs[0] + u
        if j >= self.lnP.n:
            return None  # pressure below the table's last node (far tail)
        return self.lnP.solve_in(j, L)


# ----------------------------------------------------------------------------------------
# DMW input (§6): cubic Hermite on (D, V)
# ----------------------------------------------------------------------------------------
class Dmw:
    def __init__(self, D, V, fs, t_start=0.0, wrap=False, label=""):
        self.D = [float(v) for v in D]
        self.V = [float(v) for v in V]
        self.fs = float(fs)
        self.hh = 1.0 / self.fs
        self.t_start = float(t_start)
        self.N = len(self.D)
        self.wrap = wrap
        self.label = label
        self.T_rec = (self.N - 1) / self.fs

    def __call__(self, t):
        """(D, V) at record time t (s, on the record's own axis)."""
        x = (t - self.t_start) * self.fs
        i = int(math.floor(x))
        if self.wrap:
            i %= (self.N - 1)
            x = i + (x - math.floor(x))
        elif i < 0 or i >= self.N - 1:
            if i == self.N - 1 and x == i:
                i -= 1
            else:
                raise ValueError(f"DMW record too short: t = {t:.6e} s outside the record")
        u = x - i
        D0, D1, V0, V1 = self.D[i], self.D[i + 1], self.V[i], self.V[i + 1]
        hh = self.hh
        u2 = u * u
        u3 = u2 * u
        d = ((2 * u3 - 3 * u2 + 1) * D0 + (u3 - 2 * u2 + u) * hh * V0
             + (-2 * u3 + 3 * u2) * D1 + (u3 - u2) * hh * V1)
        v = ((6 * u2 - 6 * u) * (D0 - D1) / hh + (3 * u2 - 4 * u + 1) * V0
             + (3 * u2 - 2 * u) * V1)
        return d, v

    def std(self):
        return float(np.std(self.D))


def read_dmw_h5(path, wrap=False):
    import h5py
    with h5py.File(path, "r") as f:
        g = f["/dmw/tracks"]
        D = np.asarray(g["D1"][...], dtype=float)
        V = np.asarray(g["V1"][...], dtype=float) if "V1" in g else None
        fs = None
        t_start = 0.0
        if "time" in g:
            tt = np.asarray(g["time"][...], dtype=float)
            t_start = float(tt[0])
            fs = 1.0 / float(np.mean(np.diff(tt)))
            a = g["time"].attrs
            if "sampling_rate" in a:
                fs = float(a["sampling_rate"])
        for obj in (g, f["/dmw"]):
            if fs is None and "sampling_rate" in obj.attrs:
                fs = float(obj.attrs["sampling_rate"])
            if "t0" in obj.attrs and "time" not in g:
                t_start = float(obj.attrs["t0"])
        if fs is None:
            fs = 4e6
            print("warning: no time axis / sampling_rate found; assuming 4 MS/s", file=sys.stderr)
        if V is None:  # derivative of displacement (§6)
            V = np.gradient(D, 1.0 / fs)
    return Dmw(D, V, fs, t_start, wrap, label=f"h5:{path}")


def synthetic_dmw(T_need, seed=12345, fs=4e6, sigma=1e-9, frac_line=0.8, f_line=10.7e3,
                  n_tail=64, f_lo=10e3, f_hi=500e3):
    """Spec §6 synthetic track: 80 % of the variance in a line at 10.7 kHz, the rest in n_tail
    incommensurate sinusoids, frequencies log-uniform in [10, 500] kHz, amplitude ∝ f^-2,
    random phases; seeded (numpy default_rng). Sampled analytically (D and V) at fs."""
    rng = np.random.default_rng(seed)
    f = np.sort(np.exp(rng.uniform(math.log(f_lo), math.log(f_hi), n_tail)))
    ph = rng.uniform(0, 2 * math.pi, n_tail)
    ph_line = rng.uniform(0, 2 * math.pi)
    a = f ** -2.0
    a *= math.sqrt(2 * (1 - frac_line) * sigma ** 2 / np.sum(a ** 2))
    a_line = math.sqrt(2 * frac_line * sigma ** 2)
    N = int(math.ceil(T_need * fs)) + 2
    t = np.arange(N) / fs
    w = 2 * np.pi * f
    D = a_line * np.sin(2 * math.pi * f_line * t + ph_line)
    V = a_line * 2 * math.pi * f_line * np.cos(2 * math.pi * f_line * t + ph_line)
    for k in range(n_tail):
        arg = w[k] * t + ph[k]
        D += a[k] * np.sin(arg)
        V += a[k] * w[k] * np.cos(arg)
    # normalise on the generated span (finite records of closely spaced low-frequency
    # components do not reach their nominal variance): line variance exactly frac_line·σ²,
    # then the tail scaled so that the total (mean-removed) std is exactly σ.
    Dl = a_line * np.sin(2 * math.pi * f_line * t + ph_line)
    Vl = a_line * 2 * math.pi * f_line * np.cos(2 * math.pi * f_line * t + ph_line)
    gl = math.sqrt(frac_line) * sigma / np.std(Dl)
    Dl, Vl, a_line = Dl * gl, Vl * gl, a_line * gl
    Dt, Vt = D - D.mean() * 0 - (Dl / gl), V - (Vl / gl)
    Dl0, Dt0 = Dl - Dl.mean(), Dt - Dt.mean()
    A, B, Cc = np.mean(Dt0 ** 2), 2 * np.mean(Dl0 * Dt0), np.mean(Dl0 ** 2) - sigma ** 2
    gt = (-B + math.sqrt(B * B - 4 * A * Cc)) / (2 * A)
    D, V, a = Dl + gt * Dt, Vl + gt * Vt, a * gt
    dm = Dmw(D, V, fs, 0.0, False, label=f"synthetic(seed={seed}, n_tail={n_tail})")
    dm.meta = dict(seed=seed, f_line=f_line, a_line=a_line, f_tail=f.tolist(), a_tail=a.tolist(),
                   phase_tail=ph.tolist(), phase_line=ph_line)
    return dm


# ----------------------------------------------------------------------------------------
# The model
# ----------------------------------------------------------------------------------------
class Model:
    def __init__(self, p: Params, actuation, isbl: Isbl, dmw: Dmw | None, T_sim):
        self.p = p
        self.h = actuation
        self.isbl = isbl
        self.dmw = dmw
        m, J, l = p.m, p.J, p.l
        self.kf, self.kr_nom, _ = modal_inversion(p)
        self.kr = self.kr_nom * (1 + p.beta_kr * (actuation / 15e-9) ** 2)
        # damping (§3.4): nominal stiffnesses
        self.cf = 2 * p.zeta_ab * math.sqrt(self.kf * m)
        self.cr = 2 * p.zeta_ab * math.sqrt(self.kr_nom * m)
        self.c = 2 * p.zeta_susp * math.sqrt(p.k_susp * m)
        self.cth = 2 * p.zeta_susp * math.sqrt(p.k_theta * J)
        L2 = l / 2
        self.L2 = L2
        # C, K of §5.1 (rear spring force on the right-hand side)
        self.C = np.array([[self.c + self.cf + self.cr, L2 * (self.cf - self.cr)],
                           [L2 * (self.cf - self.cr), self.cth + L2 * L2 * (self.cf + self.cr)]])
        self.K = np.array([[p.k_susp + self.kf, L2 * self.kf],
                           [L2 * self.kf, p.k_theta + L2 * L2 * self.kf]])
        self.Minv = (1 / m, 1 / J)
        # geometry
        self.cx = -l / 2 + p.x_tfc            # ellipsoid centre (body)
        self.cz = -p.l_t / 2
        self.a = p.a_tfc
        self.hw = p.w_tfc / 2
        # nominal: s_TE0 = FH_nom + T0; POC offset from TE at θ0
        th0 = p.theta0
        self.sin0, self.cos0 = math.sin(th0), math.cos(th0)
        self.s_TE0 = p.FH_nom + p.T0
        self.hs0 = self._hs(th0)
        self.s_POC0 = self.s_TE0 + self.sin0 * p.x_tfc - self.hs0
        # nominal area by truncation 3σ at θ0 (§2.4), constant per actuation
        self.hT = 3 * p.sigma
        self.An = self.nominal_area(th0) if (p.interface and actuation > 0) else 0.0
        # contact damping (§3.4): k_c,ref at h_c = 2.5σ
        self.kc_ref = self.An * isbl.kc(2.5 * p.sigma)
        self.cc = 2 * p.zeta_c * math.sqrt(self.kc_ref * m)
        # DMW points (body x) and time offset: TE reads the record start at t = 0
        self.x_ref = self.cx
        self.t_off = (self.x_ref - (-l / 2)) / p.U if p.transit_delay else 0.0
        if dmw is not None and not dmw.wrap:
            need = self.t_off + T_sim + ((l / 2 - self.x_ref) / p.U if p.transit_delay else 0.0)
            if dmw.t_start + dmw.T_rec < dmw.t_start + need - 1e-15:
                raise ValueError(f"DMW record ({dmw.T_rec:.4e} s) shorter than needed "
                                 f"({need:.4e} s); use --dmw-wrap")
        self.nrhs = 0

    # --- geometry -----------------------------------------------------------------------
    def _hs(self, th):
        s, c = math.sin(th), math.cos(th)
        return math.sqrt((self.a * s) ** 2 + (self.h * c) ** 2)

    def nominal_area(self, th):
        hs = self._hs(th)
        u = min(self.hT / hs, 1.0)   # clamp: cut deeper than the half-ellipsoid (h < 0.75 nm)
        return math.pi * self.a * self.hw * self.h / hs * (2 * u - u * u)

    def dmw_at(self, x, t):
        if self.dmw is None:
            return 0.0, 0.0
        tau = self.dmw.t_start + t + self.t_off
        if self.p.transit_delay:
            tau += (x - self.x_ref) / self.p.U
        return self.dmw(tau)

    def kinematics(self, t, y):
        """POC spacing, its rate, lever arms (world offsets COM -> POC), DMW under LE/TE."""
        z, th_d, zd, thd = y
        th = self.p.theta0 + th_d
        s, c = math.sin(th), math.cos(th)
        half = 0.5 * th_d
        sh = math.sin(half)
        dsin = 2 * math.cos(self.p.theta0 + half) * sh       # sinθ − sinθ0
        dcos = -2 * math.sin(self.p.theta0 + half) * sh      # cosθ − cosθ0
        a2s = self.a * self.a * s
        h2c = self.h * self.h * c
        hs = math.sqrt(a2s * s + h2c * c)
        # POC (body) = centre − D² n / h_s, n = (sinθ, 0, cosθ)
        px = self.cx - a2s / hs
        pz = self.cz - h2c / hs
        rx = c * px - s * pz
        rz = s * px + c * pz
        # altitude increments relative to the nominal POC
        Zinc = z + dsin * self.cx + dcos * self.cz - (hs - self.hs0)
        zd_poc, vd_poc = self.dmw_at(px, t)
        sp = self.s_POC0 + Zinc - zd_poc
        sp_dot = zd + thd * rx - vd_poc          # envelope theorem: Ż_POC = ż + θ̇ r_x
        return sp, sp_dot, rx, rz

    def interface_forces(self, s, sdot):
        """(F_c, Q, F_s, F_c unclipped, A_r)"""
        An = self.An
        if An == 0.0:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        isb = self.isbl
        Fs = An * isb.fs(s)
        hc3 = 3 * self.p.sigma
        if s >= hc3:
            return 0.0, 0.0, Fs, 0.0, 0.0
        if self.p.contact_force == "interference_tangent":
            Fc_raw = An * isb.kc(s) * (hc3 - s) - self.cc * sdot
        else:
            Fc_raw = An * isb.p(s) - self.cc * sdot
        if Fc_raw <= 0.0:
            return 0.0, 0.0, Fs, Fc_raw, 0.0
        hstar = isb.p_inv(Fc_raw / An)
        if hstar is None:
            return Fc_raw, 0.0, Fs, Fc_raw, 0.0
        x = hstar
        Q = An * math.exp(isb.lnQ(x))
        Ar = An * math.exp(isb.lnAr(x))
        return Fc_raw, Q, Fs, Fc_raw, Ar

    def rhs(self, t, y):
        self.nrhs += 1
        z, th_d, zd, thd = y
        L2 = self.L2
        # AB: DMW under LE / TE
        zdf, vdf = self.dmw_at(L2, t)
        zdr, vdr = self.dmw_at(-L2, t)
        z_r = z - L2 * th_d
        Far = self.kr * (zdr - z_r)
        kfz = self.kf * zdf + self.cf * vdf
        crv = self.cr * vdr
        f1 = kfz + crv + Far
        f2 = L2 * kfz - L2 * (crv + Far)
        # interface
        if self.An > 0.0:
            s, sdot, rx, rz = self.kinematics(t, y)
            Fc, Q, Fs, _, _ = self.interface_forces(s, sdot)
            f1 += Fc - Fs
            f2 += rx * Fc + rz * Q - rx * Fs
        C, K = self.C, self.K
        a1 = (f1 - C[0, 0] * zd - C[0, 1] * thd - K[0, 0] * z - K[0, 1] * th_d) * self.Minv[0]
        a2 = (f2 - C[1, 0] * zd - C[1, 1] * thd - K[1, 0] * z - K[1, 1] * th_d) * self.Minv[1]
        return [zd, thd, a1, a2]

    def s_TE(self, t, y):
        z, th_d = y[0], y[1]
        half = 0.5 * th_d
        sh = math.sin(half)
        dsin = 2 * math.cos(self.p.theta0 + half) * sh
        dcos = -2 * math.sin(self.p.theta0 + half) * sh
        zdr, _ = self.dmw_at(-self.L2, t)
        return self.s_TE0 + z + dsin * (-self.L2) + dcos * self.cz - zdr

    # --- static equilibrium (no DMW, interfacial forces on) --------------------------------
    def static(self):
        dm = self.dmw
        self.dmw = None

        def res(q):
            y = [q[0] * NM, q[1] * 1e-6, 0.0, 0.0]
            r = self.rhs(0.0, y)
            return [r[2] * self.p.m * 1e6, r[3] * self.p.J * 1e9]
        q, info, ier, msg = fsolve(res, [0.0, 0.0], xtol=1e-13, full_output=True)
        y = [q[0] * NM, q[1] * 1e-6, 0.0, 0.0]
        s, sdot, rx, rz = self.kinematics(0.0, y)
        Fc, Q, Fs, _, _ = self.interface_forces(s, 0.0)
        self.dmw = dm
        return dict(z_nm=q[0], dtheta_urad=q[1], clearance_nm=(s - 3 * self.p.sigma) / NM,
                    Fc_mN=Fc * 1e3, Fs_mN=Fs * 1e3, converged=bool(ier == 1))


# ----------------------------------------------------------------------------------------
# metrics (§8)
# ----------------------------------------------------------------------------------------
def fhm_samples(fh, nom):
    srt = np.sort(fh)
    return 100 * (srt[-5:].mean() - srt[:5].mean()) / nom


def fhm_peaks(fh, nom):
    d = np.diff(fh)
    imax = np.where((d[:-1] > 0) & (d[1:] <= 0))[0] + 1
    imin = np.where((d[:-1] < 0) & (d[1:] >= 0))[0] + 1
    if len(imax) < 5 or len(imin) < 5:
        return float("nan")
    mx = np.sort(fh[imax])[-5:].mean()
    mn = np.sort(fh[imin])[:5].mean()
    return 100 * (mx - mn) / nom


def regime(cbar, T0):
    if cbar > 2 * T0:
        return "flying"
    if cbar > T0:
        return "mobile-lube contact"
    if cbar >= 0:
        return "bonded-lube contact"
    return "solid contact"


def run_case(actuation_nm, *, dmw_mode="none", dmw_h5=None, dmw_wrap=False, seed=12345,
             max_step=1e-8, T_sim=2e-3, t_win=(0.5e-3, 2e-3), dt_out=0.25e-6,
             params: Params | None = None, isbl_path=DEFAULT_ISBL, init="nominal"):
    p = params or Params()
    isbl = Isbl(isbl_path, p)
    if dmw_mode == "none":
        dmw = None
    elif dmw_mode == "synthetic":
        dmw = synthetic_dmw(T_sim + p.l / p.U + 10e-6, seed=seed)
    elif dmw_mode == "h5":
        dmw = read_dmw_h5(dmw_h5, wrap=dmw_wrap)
    else:
        raise ValueError(dmw_mode)
    h = actuation_nm * NM
    mdl = Model(p, h, isbl, dmw, T_sim)
    y0 = [0.0, 0.0, 0.0, 0.0]
    st = None
    if init == "static":
        st = mdl.static()
        y0 = [st["z_nm"] * NM, st["dtheta_urad"] * 1e-6, 0.0, 0.0]
    atol_d, atol_a = 1e-14, 1e-11
    w = 2 * math.pi * 1e6
    atol = np.array([atol_d, atol_a, atol_d * w, atol_a * w])

    def ev_ab_lost(t, y):
        return mdl.s_TE(t, y) - p.T0 - p.ab_lost_FH
    ev_ab_lost.terminal = True
    ev_ab_lost.direction = 1

    t_eval = np.arange(0.0, T_sim + 0.5 * dt_out, dt_out)
    t_eval = t_eval[t_eval <= T_sim]
    t0w = time.perf_counter()
    sol = solve_ivp(mdl.rhs, (0.0, T_sim), y0, method="RK45", rtol=1e-8, atol=atol,
                    max_step=max_step, t_eval=t_eval, events=ev_ab_lost)
    wall = time.perf_counter() - t0w
    out = dict(actuation_nm=actuation_nm, wall_s=wall, nfev=int(sol.nfev),
               nfev_counted=mdl.nrhs, status=int(sol.status), message=sol.message,
               max_step=max_step, dmw=(dmw.label if dmw else "none"),
               dmw_std_nm=(dmw.std() / NM if dmw else 0.0),
               An_um2=mdl.An * 1e12, kf=mdl.kf, kr_nom=mdl.kr_nom, kr=mdl.kr, cc=mdl.cc,
               ab_lost=bool(sol.status == 1))
    if st is not None:
        out["static_init"] = st
    if sol.status == 1:
        out["ab_lost_at_s"] = float(sol.t_events[0][0])
        return out
    tt = sol.t
    Y = sol.y
    sel = (tt >= t_win[0] - 1e-15) & (tt <= t_win[1] + 1e-15)
    n = int(sel.sum())
    s_arr = np.empty(n)
    Fc = np.zeros(n); Q = np.zeros(n); Fs = np.zeros(n); Fraw = np.zeros(n); Ar = np.zeros(n)
    idx = np.where(sel)[0]
    for k, j in enumerate(idx):
        y = Y[:, j]
        s, sdot, rx, rz = mdl.kinematics(tt[j], y)
        s_arr[k] = s
        Fc[k], Q[k], Fs[k], Fraw[k], Ar[k] = mdl.interface_forces(s, sdot)
    c = s_arr - 3 * p.sigma
    fh = s_arr - p.T0
    incontact = c < 0
    mu = np.where(Fc > 1e-6, Q / np.where(Fc > 0, Fc, 1), np.nan)
    out.update(
        n_samples=n,
        clearance_mean_nm=c.mean() / NM, clearance_std_nm=c.std() / NM,
        FH_mean_nm=fh.mean() / NM, FH_std_nm=fh.std() / NM,
        FHM_pct=fhm_samples(fh, p.FH_nom), FHM_peaks_pct=fhm_peaks(fh, p.FH_nom),
        contact_pct=100 * incontact.mean(),
        Fc_mean_mN=Fc.mean() * 1e3, Q_mean_mN=Q.mean() * 1e3, Fs_mean_mN=Fs.mean() * 1e3,
        Ar_mean_um2=Ar.mean() * 1e12,
        mu_ratio_of_means=(Q.mean() / Fc.mean() if Fc.mean() > 0 else float("nan")),
        mu_mean_inst=(float(np.nanmean(mu)) if np.any(np.isfinite(mu)) else float("nan")),
        clip_pct_of_contact=(100 * (incontact & (Fraw <= 0)).sum() / max(incontact.sum(), 1)),
        regime=regime(c.mean() / NM, p.T0 / NM),
        z_final_m=float(Y[0, -1]), theta_final_rad=float(Y[1, -1]),
        max_abs_z_m=float(np.abs(Y[0]).max()), max_abs_theta_rad=float(np.abs(Y[1]).max()),
        p_inv_out_below=isbl.out_below,
    )
    return out


# ----------------------------------------------------------------------------------------
# CLI
# ----------------------------------------------------------------------------------------
def fmt_case(r):
    if r.get("ab_lost"):
        return f"{r['actuation_nm']:6.2f}  AB LOST at t = {r['ab_lost_at_s']:.4e} s"
    return (f"{r['actuation_nm']:6.2f} {r['clearance_mean_nm']:9.4f} {r['clearance_std_nm']:8.4f} "
            f"{r['FH_mean_nm']:8.4f} {r['FHM_pct']:7.3f} {r['contact_pct']:7.2f} "
            f"{r['Fc_mean_mN']:10.5f} {r['Q_mean_mN']:10.5f} {r['Fs_mean_mN']:9.5f} "
            f"{r['wall_s']:8.2f} {r['nfev']:9d}  {r['regime']}")


HEADER = (" act/nm  c_mean/nm  c_std/nm  FH/nm   FHM/%  cont/%    Fc/mN      Q/mN      Fs/mN"
          "   wall/s      nfev  regime")


def _case_kwargs(args):
    mode = "none"
    if args.synthetic_dmw:
        mode = "synthetic"
    elif args.dmw_h5:
        mode = "h5"
    p = Params(beta_kr=args.beta, contact_force=args.contact_force,
               transit_delay=not args.no_transit_delay, interface=not args.no_interface)
    return dict(dmw_mode=mode, dmw_h5=args.dmw_h5, dmw_wrap=args.dmw_wrap, seed=args.seed,
                max_step=args.max_step, T_sim=args.duration, params=p, init=args.init)


def _worker(a):
    act, kw = a
    return run_case(act, **kw)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--dmw-h5", metavar="FILE", help="hdi dmw.h5: /dmw/tracks/{D1,V1,time}")
    g.add_argument("--no-dmw", action="store_true", help="zero excitation (default)")
    g.add_argument("--synthetic-dmw", action="store_true", help="spec §6 synthetic track")
    ap.add_argument("--dmw-wrap", action="store_true", help="periodic extension of short records")
    ap.add_argument("--seed", type=int, default=12345, help="synthetic DMW seed")
    ap.add_argument("--actuation", type=float, default=8.5, help="h_TFC in nm")
    ap.add_argument("--sweep", nargs=3, type=float, metavar=("START", "STOP", "STEP"))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--max-step", type=float, default=1e-8, help="s; 'inf' allowed")
    ap.add_argument("--duration", type=float, default=2e-3)
    ap.add_argument("--beta", type=float, default=1.0, help="rear-spring stiffening β")
    ap.add_argument("--contact-force", default="interference_tangent",
                    choices=["interference_tangent", "static_curve"])
    ap.add_argument("--no-transit-delay", action="store_true")
    ap.add_argument("--no-interface", action="store_true", help="switch interfacial forces off")
    ap.add_argument("--init", default="nominal", choices=["nominal", "static"])
    ap.add_argument("--static", action="store_true",
                    help="only print the static equilibrium (no DMW) at the actuation(s)")
    ap.add_argument("--json", action="store_true", help="emit JSON on stdout")
    args = ap.parse_args(argv)
    kw = _case_kwargs(args)

    if args.sweep:
        a0, a1, da = args.sweep
        acts = [round(a0 + k * da, 10) for k in range(int(math.floor((a1 - a0) / da + 1e-9)) + 1)]
    else:
        acts = [args.actuation]

    if args.static:
        p = kw["params"]
        isbl = Isbl(DEFAULT_ISBL, p)
        rows = []
        for a in acts:
            mdl = Model(p, a * NM, isbl, None, args.duration)
            st = mdl.static()
            st.update(actuation_nm=a, line_nm=(p.FH_nom + p.x_tfc * p.theta0 + p.T0 - 3 * p.sigma) / NM - a,
                      An_um2=mdl.An * 1e12)
            rows.append(st)
        if args.json:
            print(json.dumps(rows, indent=1))
        else:
            print(" act/nm  c_static/nm  11.05-h/nm  diff/nm   Fs/mN     Fc/mN    z/nm   dθ/µrad")
            for r in rows:
                print(f"{r['actuation_nm']:6.2f} {r['clearance_nm']:11.5f} {r['line_nm']:11.5f} "
                      f"{r['clearance_nm'] - r['line_nm']:9.5f} {r['Fs_mN']:8.5f} {r['Fc_mN']:9.5f} "
                      f"{r['z_nm']:7.4f} {r['dtheta_urad']:8.4f}")
        return

    t0 = time.perf_counter()
    if len(acts) > 1 and args.jobs > 1:
        import multiprocessing as mp
        with mp.get_context("fork").Pool(args.jobs) as pool:
            res = pool.map(_worker, [(a, kw) for a in acts], chunksize=1)
    else:
        res = [run_case(a, **kw) for a in acts]
    total = time.perf_counter() - t0

    if args.json:
        print(json.dumps(dict(cases=res, total_wall_s=total, jobs=args.jobs), indent=1, default=float))
        return
    r0 = res[0]
    print(f"# improved 2-DOF, scipy RK45 rtol 1e-8, max_step {args.max_step:g} s, DMW {r0['dmw']}"
          f" (std {r0['dmw_std_nm']:.4f} nm), k_f {r0['kf']:.4e}, k_r,nom {r0['kr_nom']:.4e} N/m")
    if len(res) == 1:
        r = r0
        if r.get("ab_lost"):
            print(fmt_case(r))
        else:
            print(f"actuation          {r['actuation_nm']} nm   (A_n {r['An_um2']:.3f} µm², k_r {r['kr']:.4e} N/m, c_c {r['cc']:.4e} N·s/m)")
            print(f"wall time          {r['wall_s']:.3f} s")
            print(f"RHS evaluations    {r['nfev']}")
            print(f"clearance c=s-3σ   mean {r['clearance_mean_nm']:.5f} nm, std {r['clearance_std_nm']:.5f} nm")
            print(f"FH = s - T0        mean {r['FH_mean_nm']:.5f} nm, std {r['FH_std_nm']:.5f} nm")
            print(f"FHM/BV             {r['FHM_pct']:.4f} % (samples), {r['FHM_peaks_pct']:.4f} % (extrema)")
            print(f"solid contact      {r['contact_pct']:.3f} % of samples (clip acted on {r['clip_pct_of_contact']:.2f} % of them)")
            print(f"mean F_c, Q, F_s   {r['Fc_mean_mN']:.6f}, {r['Q_mean_mN']:.6f}, {r['Fs_mean_mN']:.6f} mN")
            print(f"mean A_r           {r['Ar_mean_um2']:.5f} µm²;  μ (ratio of means) {r['mu_ratio_of_means']:.4f}")
            print(f"regime             {r['regime']}")
            print(f"max|z|, max|ϑ|     {r['max_abs_z_m']:.3e} m, {r['max_abs_theta_rad']:.3e} rad")
    else:
        print(HEADER)
        for r in res:
            print(fmt_case(r))
        first = next((r["actuation_nm"] for r in res if not r.get("ab_lost") and r["contact_pct"] > 0), None)
        print(f"# first actuation with solid contact in the steady window: {first}")
    print(f"# total wall time {total:.2f} s ({len(acts)} case(s), jobs {args.jobs})")


if __name__ == "__main__":
    main()
