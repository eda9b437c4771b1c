"""Closed form of validation/mpm_plastic_bending (run: python3 make_reference.py > reference.csv).

A strip (L = 10, b = 1, h = 0.1, E = 1.2e6, nu = 0, elastic-perfectly plastic, yield 600) bent by an
end moment M per unit width: M is the same in every section, so the curvature kappa is uniform and
the strip is a circular arc, at any rotation: w_tip = (1 - cos(kappa L)) / kappa, u_tip = sin(kappa L)
/ kappa - L. The moment-curvature law of the section: sigma(z) = E kappa z capped at the yield stress
(nu = 0: uniaxial), M = b int sigma z dz. Two references:
  - exact: M / M_y = 1.5 (1 - (kappa_y / kappa)^2 / 3) beyond kappa_y = 2 yield / (E h), M_y = yield b h^2 / 6;
  - lobatto7: the same integral by the 7-point Lobatto rule through the thickness (what the shell
    integrates with shell.thickness_points: 7); it saturates at 1.4396 M_y instead of 1.5 M_y.
  - shell7: the plate strip's section as a shell theory has it (Kirchhoff-Love: the in-plane strains
    linear through the thickness in both directions, eps = e + z k), 7 Lobatto points, plane-stress J2
    (von Mises, nu = 0, perfectly plastic) at each. Given kappa_x, the other three (e_x, e_y, k_y) make
    N_x = N_y = M_y = 0 (free edges); followed in small increments of kappa_x from zero (the yielded
    points flow laterally, -1/2 of their axial plastic strain, which the linear lateral strain cannot
    follow: sigma_y appears and the section is stiffer than the uniaxial law).
"""
import math

import numpy as np
from numpy.polynomial.legendre import Legendre

E, YIELD, L, B, H = 1.2e6, 600.0, 10.0, 1.0, 0.1
MY = YIELD * B * H * H / 6.0          # = 1
KY = 2.0 * YIELD / (E * H)            # = 0.01
LEVELS, M_MAX = 13, 1.3               # M / M_y up to 1.3


def lobatto(n):
    p = Legendre.basis(n - 1)
    x = np.concatenate(([-1.0], np.sort(p.deriv().roots()), [1.0]))
    return x, 2.0 / (n * (n - 1) * p(x) ** 2)


X7, W7 = lobatto(7)


def moment_exact(k):
    r = k / KY
    return MY * (r if r <= 1 else 1.5 * (1 - 1 / (3 * r * r)))


def moment_lobatto7(k):
    s = np.clip(k / KY * X7, -1.0, 1.0)
    return MY * 1.5 * float(np.sum(W7 * s * X7))


def plane_stress_return(trial):
    """Closest-point return of a plane-stress trial (sigma_x, sigma_y; no shear) onto the von Mises
    yield surface, nu = 0 (C = E I): sigma = (I + dg E P)^-1 trial, P = [[2, -1], [-1, 2]] / 3;
    dg by bisection on sigma_vm(dg) = yield."""
    vm = lambda s: math.sqrt(max(0.0, s[0] ** 2 - s[0] * s[1] + s[1] ** 2))
    if vm(trial) <= YIELD:
        return trial
    p = np.array([[2.0, -1.0], [-1.0, 2.0]]) / 3.0
    at = lambda dg: np.linalg.solve(np.eye(2) + dg * E * p, trial)
    lo, hi = 0.0, 1.0 / E
    while vm(at(hi)) > YIELD:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if vm(at(mid)) > YIELD else (lo, mid)
    return at(0.5 * (lo + hi))


def shell7_moment_curve(k_end, steps=4000):
    """(kappa_x, M_x) pairs of the shell section (see the module text), kappa_x from 0 to k_end."""
    z, w = X7 * H / 2.0, W7 * H / 2.0
    stress = np.zeros((7, 2))      # converged sigma_x, sigma_y per point
    strain = np.zeros(3)           # e_x, e_y, k_y
    kx = 0.0
    curve = [(0.0, 0.0)]

    def section(kx_new, s3, commit=False):
        d_eps_x = (s3[0] - strain[0]) + z * (kx_new - kx)
        d_eps_y = (s3[1] - strain[1]) + z * (s3[2] - strain[2])
        new = np.array([plane_stress_return(stress[q] + E * np.array([d_eps_x[q], d_eps_y[q]])) for q in range(7)])
        forces = np.array([np.sum(w * new[:, 0]), np.sum(w * new[:, 1]), np.sum(w * z * new[:, 1])])
        return forces, np.sum(w * z * new[:, 0]), new

    for i in range(1, steps + 1):
        kx_new = k_end * i / steps
        s3 = strain.copy()
        for _ in range(50):  # Newton on (e_x, e_y, k_y), finite-difference Jacobian
            f, _, _ = section(kx_new, s3)
            if np.max(np.abs(f)) < 1e-10 * YIELD * H:
                break
            jac = np.zeros((3, 3))
            for c in range(3):
                d = np.zeros(3)
                d[c] = 1e-9 if c < 2 else 1e-8
                jac[:, c] = (section(kx_new, s3 + d)[0] - f) / d[c]
            s3 = s3 - np.linalg.solve(jac, f)
        _, m, stress[:] = section(kx_new, s3)
        strain[:] = s3
        kx = kx_new
        curve.append((kx, B * m))
    return curve


SHELL7 = shell7_moment_curve(3.0 * KY)


def moment_shell7(k):
    ks, ms = zip(*SHELL7)
    return float(np.interp(k, ks, ms))


def curvature(m, law):
    lo, hi = 0.0, 100 * KY
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if law(mid) < m else (lo, mid)
    return 0.5 * (lo + hi)


print("# Closed form (make_reference.py): elastic-perfectly plastic strip in pure bending, nu = 0, E = 1.2e6, yield 600,")
print("# L = 10, b = 1, h = 0.1 (M_y = 1, kappa_y = 0.01); uniform curvature, circular arc. exact: continuous")
print("# section law; lobatto7: the section integrated by the shell's 7-point Lobatto rule; shell7: the shell's")
print("# 7-point section with strains linear through the thickness in both directions (free edges), J2 plane stress")
print("load_factor,moment,w_exact,u_exact,w_lobatto7,u_lobatto7,w_shell7,u_shell7")
for k in range(1, LEVELS + 1):
    f = k / LEVELS
    m = f * M_MAX
    row = [f, m]
    for law in (moment_exact, moment_lobatto7, moment_shell7):
        c = curvature(m, law)
        row += [(1 - math.cos(c * L)) / c, math.sin(c * L) / c - L]
    print(",".join(f"{v:.12g}" for v in row))
