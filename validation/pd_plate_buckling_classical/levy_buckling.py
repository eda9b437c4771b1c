#!/usr/bin/env python3
"""Exact buckling coefficients of uniformly compressed rectangular plates whose loaded edges x = 0, a
are simply supported (Levy's method, Timoshenko & Gere section 9.3): w = f(y) sin(m pi x / a),
f'''' - 2 alpha^2 f'' + (alpha^4 - n alpha^2) f = 0, n = N_x / D, alpha = m pi / a. The lowest n with
a non-trivial f for the unloaded-edge conditions; printed as k = n b^2 / pi^2 and P = N b.
Usage: levy_buckling.py  (no arguments; the cases of check.yaml)"""
import math
import numpy as np


def determinant(n, alpha, b, nu, condition):
    s1 = math.sqrt(alpha * alpha + alpha * math.sqrt(n))
    q = math.sqrt(max(alpha * math.sqrt(n) - alpha * alpha, 1e-300))
    # general solution: A cosh(s1 y) + B sinh(s1 y) + C cos(q y) + E sin(q y)
    def rows_at(y, kind):
        ch, sh, c, s = math.cosh(s1 * y), math.sinh(s1 * y), math.cos(q * y), math.sin(q * y)
        f = [ch, sh, c, s]
        f1 = [s1 * sh, s1 * ch, -q * s, q * c]
        f2 = [s1 * s1 * ch, s1 * s1 * sh, -q * q * c, -q * q * s]
        f3 = [s1 ** 3 * sh, s1 ** 3 * ch, q ** 3 * s, -q ** 3 * c]
        if kind == "simple":
            return [f, f2]
        if kind == "clamped":
            return [f, f1]
        if kind == "free":  # M_y = 0, V_y = 0
            return [[f2[i] - nu * alpha * alpha * f[i] for i in range(4)],
                    [f3[i] - (2 - nu) * alpha * alpha * f1[i] for i in range(4)]]
        raise ValueError(kind)
    lower, upper = condition
    m = np.array(rows_at(0.0, lower) + rows_at(b, upper))
    scale = np.abs(m).max(axis=0)
    return np.linalg.det(m / scale)


def lowest_n(alpha, b, nu, condition, n_max):
    grid = np.linspace(alpha * alpha * 1.0001, n_max, 20000)
    values = [determinant(n, alpha, b, nu, condition) for n in grid]
    for i in range(len(grid) - 1):
        if values[i] == 0 or values[i] * values[i + 1] < 0:
            lo, hi = grid[i], grid[i + 1]
            for _ in range(100):
                mid = 0.5 * (lo + hi)
                if determinant(lo, alpha, b, nu, condition) * determinant(mid, alpha, b, nu, condition) <= 0:
                    hi = mid
                else:
                    lo = mid
            return 0.5 * (lo + hi)
    return math.inf


def coefficient(a, b, nu, condition):
    best = math.inf
    for m in range(1, 6):
        alpha = m * math.pi / a
        best = min(best, lowest_n(alpha, b, nu, condition, 40 * math.pi ** 2 / b ** 2) * b * b / math.pi ** 2)
    return best


if __name__ == "__main__":
    b, t, e = 200.0, 2.0, 69000.0
    for name, a, nu, cond in [("simply supported (check)", 200.0, 0.33, ("simple", "simple")),
                              ("unloaded edges simple / free", 200.0, 0.33, ("simple", "free")),
                              ("unloaded edges clamped", 200.0, 0.0, ("clamped", "clamped"))]:
        k = coefficient(a, b, nu, cond)
        d = e * t ** 3 / (12 * (1 - nu * nu))
        print(f"{name}: a/b = {a / b:g}, nu = {nu}: k = {k:.4f}, P = N b = {k * math.pi ** 2 * d / b:.1f} N")
