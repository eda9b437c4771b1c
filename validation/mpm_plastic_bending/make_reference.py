"""Closed form of validation/mpm_plastic_bending (run: python3 make_reference.py > reference.csv).

A strip (L = 10, b = 1, h = 0.1, E = 1.2e6, nu = 0, elastic-perfectly plastic, yield 600) bent by an
end moment M per unit width: M is the same in every section, so the curvature kappa is uniform and
the strip is a circular arc, at any rotation: w_tip = (1 - cos(kappa L)) / kappa, u_tip = sin(kappa L)
/ kappa - L. The moment-curvature law of the section: sigma(z) = E kappa z capped at the yield stress
(nu = 0: uniaxial), M = b int sigma z dz. Two references:
  - exact: M / M_y = 1.5 (1 - (kappa_y / kappa)^2 / 3) beyond kappa_y = 2 yield / (E h), M_y = yield b h^2 / 6;
  - lobatto7: the same integral by the 7-point Lobatto rule through the thickness (what the shell
    integrates with shell.thickness_points: 7); it saturates at 1.4396 M_y instead of 1.5 M_y.
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


def curvature(m, law):
    lo, hi = 0.0, 100 * KY
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if law(mid) < m else (lo, mid)
    return 0.5 * (lo + hi)


print("# Closed form (make_reference.py): elastic-perfectly plastic strip in pure bending, nu = 0, E = 1.2e6, yield 600,")
print("# L = 10, b = 1, h = 0.1 (M_y = 1, kappa_y = 0.01); uniform curvature, circular arc. exact: continuous")
print("# section law; lobatto7: the section integrated by the shell's 7-point Lobatto rule")
print("load_factor,moment,w_exact,u_exact,w_lobatto7,u_lobatto7")
for k in range(1, LEVELS + 1):
    f = k / LEVELS
    m = f * M_MAX
    row = [f, m]
    for law in (moment_exact, moment_lobatto7):
        c = curvature(m, law)
        row += [(1 - math.cos(c * L)) / c, math.sin(c * L) / c - L]
    print(",".join(f"{v:.12g}" for v in row))
