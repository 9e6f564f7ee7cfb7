"""Reference values of the `ke_static` friction law (docs/contact.md, "Friction").

An independent numpy/scipy implementation of the law as docs/contact.md states it, written
from the equations, not from hdi's Rust code:

  one summit at interference w (KE units w* = w/w_c, L_c = (2/3)*pi*K*H*R*w_c):
    P/L_c    = Kogut–Etsion 2002 load fits (w*^1.5; 1.03 w*^1.425; 1.40 w*^1.263; 3/K w*)
    F_s/L_c  = 2*pi*dgamma_max*R*f_el(w/eps)/L_c,
               f_el(l) = (8/3) l * int_1^inf [q^-3 - q^-9] x dx,
               q = 1 + (l/pi) G(x),  G(x) = sqrt(x^2-1) - (2-x^2) arccos(1/x)
    Q_max/L_c = 0.4155 * (P/L_c + F_s/L_c)^(0.970/1.5)   for 0 < w* <= 110, else 0
  rough surface (Greenwood–Williamson, d = h, sigma_s = sigma):
    Q(h) = eta * L_c * int_0^inf Q_max/L_c(w) phi(h + w) dw
    k_fr = -dQ/dh, here by a five-point central difference of Q (step 1e-3 sigma), so the
           Rust model's analytic derivative is checked against an independent one.

Writes `ke_static.csv` beside this script: one row per (set, h*), columns
set, h_star, h_m, Q_Pa, kfr_Pa_per_m; and `ke_static_sphere.csv`: the Ch. 3.1 DLC sphere
(R = 102 um, E = 180 GPa, nu = 0.24, H = 18 GPa, eps = 0.3 nm) at w = 0.1 and 1 nm with
dgamma = 0.06 N/m and 0, columns omega_m, delta_gamma_N_per_m, P_N, F_s_N, Q_N.

Run once with numpy 2.4 / scipy 1.17 (python3 make_ke_static.py); the files are frozen.
"""

import csv
import math
import os

import numpy as np
from scipy import integrate

HERE = os.path.dirname(os.path.abspath(__file__))
C_KE = 0.4155
M_KE = 0.970 / 1.5
QUAD = dict(epsabs=0.0, epsrel=1e-13, limit=1000)


def hertz_gap(x):
    if x <= 1.0:
        return 0.0
    return math.sqrt(x * x - 1.0) - (2.0 - x * x) * math.acos(1.0 / x)


def f_el(lam):
    """Elastic DMT/LJ adhesion factor, by quadrature in u with x = 1 + u^2."""
    if lam == 0.0:
        return 1.0

    def integrand(u):
        x = 1.0 + u * u
        q = 1.0 + lam / math.pi * hertz_gap(x)
        return (q ** -3 - q ** -9) * x * 2.0 * u

    s = min(lam ** (-1.0 / 3.0), lam ** -0.25)
    t = max(lam ** (-1.0 / 3.0), lam ** -0.25)
    total = 0.0
    for a, b in [(0.0, s), (s, t), (t, 4.0 * t), (4.0 * t, 40.0 * t)]:
        total += integrate.quad(integrand, a, b, **QUAD)[0]
    total += integrate.quad(integrand, 40.0 * t, np.inf, epsabs=0.0, epsrel=1e-12, limit=1000)[0]
    return 8.0 / 3.0 * lam * total


class Interface:
    def __init__(self, sigma, R, eta, E, nu, H, eps, dgamma_max):
        estar = 1.0 / (2.0 * (1.0 - nu * nu) / E)
        self.K = 0.454 + 0.41 * nu
        self.wc = (math.pi * self.K * H / (2.0 * estar)) ** 2 * R
        self.Lc = 2.0 / 3.0 * math.pi * self.K * H * R * self.wc
        self.sigma, self.R, self.eta, self.eps = sigma, R, eta, eps
        self.adh = 2.0 * math.pi * dgamma_max * R / self.Lc

    def load(self, ws):
        if ws <= 0.0:
            return 0.0
        if ws <= 1.0:
            return ws ** 1.5
        if ws <= 6.0:
            return 1.03 * ws ** 1.425
        if ws <= 110.0:
            return 1.40 * ws ** 1.263
        return 3.0 / self.K * ws

    def qmax(self, w):
        ws = w / self.wc
        if ws <= 0.0 or ws > 110.0:
            return 0.0
        return C_KE * (self.load(ws) + self.adh * f_el(w / self.eps)) ** M_KE

    def friction(self, h):
        s = self.sigma
        phi = lambda z: math.exp(-0.5 * (z / s) ** 2) / (s * math.sqrt(2.0 * math.pi))
        top = max(0.0, -h) + 40.0 * s
        edges = [0.0] + [b for b in (self.wc, 6.0 * self.wc, 110.0 * self.wc) if b < top] + [top]
        # A few extra breaks over the Gaussian's bulk for quad.
        extra = [max(0.0, -h) + k * s for k in (-4, -2, -1, 0, 1, 2, 4, 8) if 0.0 < max(0.0, -h) + k * s < top]
        edges = sorted(set(edges + extra))
        total = 0.0
        for a, b in zip(edges[:-1], edges[1:]):
            total += integrate.quad(lambda w: self.qmax(w) * phi(h + w), a, b, **QUAD)[0]
        return self.eta * self.Lc * total

    def friction_stiffness(self, h):
        d = 1e-3 * self.sigma
        q = [self.friction(h + k * d) for k in (-2, -1, 1, 2)]
        return -(q[0] - 8.0 * q[1] + 8.0 * q[2] - q[3]) / (12.0 * d)


def sets():
    dlc = dict(E=280e9, nu=0.25, eps=0.3e-9)
    variable_max = 0.100 * math.exp(-2.41e9 * 0.3e-9) + 0.019  # dgamma(eps), Ch. 3.2.3 law
    return {
        "initial_2dof": Interface(0.87e-9, 0.43e-6, 124e12, H=13e9, dgamma_max=0.06, **dlc),
        "improved_2dof": Interface(0.50e-9, 0.43e-6, 124e12, H=13e9, dgamma_max=0.06, **dlc),
        "mtl_table_3_2": Interface(0.82e-9, 3.89e-6, 15.7e12, H=15e9, dgamma_max=variable_max, **dlc),
    }


def main():
    h_stars = [-1.0, 0.0, 0.6, 1.0, 2.0, 3.0, 4.0, 6.0]
    rows = []
    for name, m in sets().items():
        for hs in h_stars:
            h = hs * m.sigma
            rows.append([name, hs, f"{h:.6e}", f"{m.friction(h):.12e}", f"{m.friction_stiffness(h):.12e}"])
            print(rows[-1], flush=True)
    with open(os.path.join(HERE, "ke_static.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["set", "h_star", "h_m", "Q_Pa", "kfr_Pa_per_m"])
        w.writerows(rows)
    sphere_rows = []
    for dgamma in (0.06, 0.0):
        sph = Interface(0.87e-9, 102e-6, 124e12, E=180e9, nu=0.24, H=18e9, eps=0.3e-9, dgamma_max=dgamma)
        for w in (0.1e-9, 1e-9):
            P = sph.Lc * sph.load(w / sph.wc)
            Fs = 2.0 * math.pi * dgamma * sph.R * f_el(w / sph.eps)
            Q = sph.Lc * sph.qmax(w)
            sphere_rows.append([f"{w:.3e}", dgamma, f"{P:.12e}", f"{Fs:.12e}", f"{Q:.12e}"])
            print(sphere_rows[-1], flush=True)
    with open(os.path.join(HERE, "ke_static_sphere.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["omega_m", "delta_gamma_N_per_m", "P_N", "F_s_N", "Q_N"])
        w.writerows(sphere_rows)


if __name__ == "__main__":
    main()
