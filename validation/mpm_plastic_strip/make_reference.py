"""Closed form of validation/mpm_plastic_strip (run: python3 make_reference.py > reference.csv).

Uniaxial stress in a J2 strip with linear isotropic hardening, logarithmic strains (the hypoelastic
corotational update integrates the rate of deformation, so along fixed axes the strains are
logarithmic and the stress is the Cauchy stress):
  eps_x = sigma / E + eps_p,  eps_y = eps_z = -nu sigma / E - eps_p / 2,  sigma = yield + H eps_p (if above yield).
A dead traction T per reference edge length carries T b0 = sigma b h, so T = h0 sigma exp(eps_y + eps_z).
u_end = L (exp(eps_x) - 1), v_side = (b0 / 2) (exp(eps_y) - 1) (the strip is held on its axis y = b0 / 2); sigma from T by bisection.
"""
import math

E, NU, YIELD, H = 200000.0, 0.3, 200.0, 2000.0
L, B, T0 = 100.0, 10.0, 1.0
LEVELS = 10
SIGMA_MAX = 300.0  # eps_p = 0.05 at the last level


def state(sigma):
    eps_p = max(0.0, (sigma - YIELD) / H)
    eps_x = sigma / E + eps_p
    eps_y = -NU * sigma / E - 0.5 * eps_p
    return eps_p, eps_x, eps_y


def traction(sigma):
    eps_p, eps_x, eps_y = state(sigma)
    return T0 * sigma * math.exp(2.0 * eps_y)


def sigma_of(t):
    lo, hi = 0.0, 10.0 * SIGMA_MAX
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if traction(mid) < t:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


t_max = traction(SIGMA_MAX)
print("# Closed form (make_reference.py): J2 plane-stress strip, uniaxial stress, E = 2e5, nu = 0.3, yield 200, H = 2000,")
print(f"# L = 100, b = 10, h = 1; dead traction per reference width, T_max = {t_max!r} (sigma = 300, eps_p = 0.05)")
print("load_factor,traction,sigma,eps_p,u_end,v_side")
for k in range(1, LEVELS + 1):
    f = k / LEVELS
    s = sigma_of(f * t_max)
    eps_p, eps_x, eps_y = state(s)
    print(f"{f:.10g},{f * t_max:.12g},{s:.12g},{eps_p:.12g},{L * math.expm1(eps_x):.12g},{0.5 * B * math.expm1(eps_y):.12g}")
