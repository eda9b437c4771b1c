#!/usr/bin/env python3
"""Exact buckling coefficient of a uniformly compressed rectangular plate whose loaded edges x = 0, a
are clamped and whose unloaded edges y = 0, b are simply supported (Levy's method with the sine across
the width; Timoshenko & Gere, Theory of Elastic Stability, 1961, section 9.2 / 9.3):
w = X(x) sin(pi y / b), X'''' - (2 beta^2 - n) X'' + beta^4 X = 0, n = N_x / D, beta = pi / b. For
n > 4 beta^2, X = A cos p1 x + B sin p1 x + C cos p2 x + E sin p2 x with
p^2 = ((n - 2 beta^2) +- sqrt(n^2 - 4 n beta^2)) / 2; X = X' = 0 at x = 0, a gives a 4 x 4
determinant; the lowest root n is printed as k = n b^2 / pi^2 and P = N b.
Usage: loaded_clamped_buckling.py  (no arguments; the case of check.yaml)"""
import math

import numpy as np


def determinant(n, beta, a):
    root = math.sqrt(n * n - 4 * n * beta * beta)
    p1 = math.sqrt(0.5 * (n - 2 * beta * beta + root))
    p2 = math.sqrt(max(0.5 * (n - 2 * beta * beta - root), 1e-300))

    def rows(x):
        c1, s1, c2, s2 = math.cos(p1 * x), math.sin(p1 * x), math.cos(p2 * x), math.sin(p2 * x)
        return [[c1, s1, c2, s2], [-p1 * s1, p1 * c1, -p2 * s2, p2 * c2]]

    m = np.array(rows(0.0) + rows(a))
    return np.linalg.det(m / np.abs(m).max(axis=0))


def coefficient(a, b):
    beta = math.pi / b
    grid = np.linspace(4 * beta * beta * 1.000001, 40 * beta * beta, 40000)
    values = [determinant(n, beta, a) for n in grid]
    for i in range(len(grid) - 1):
        if values[i] * values[i + 1] < 0:
            lo, hi = grid[i], grid[i + 1]
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if determinant(lo, beta, a) * determinant(mid, beta, a) <= 0:
                    hi = mid
                else:
                    lo = mid
            return 0.5 * (lo + hi) * b * b / math.pi ** 2
    return math.inf


if __name__ == "__main__":
    b, t, e, nu = 200.0, 2.0, 69000.0, 0.33
    d = e * t ** 3 / (12 * (1 - nu * nu))
    for a in (200.0, 400.0):
        k = coefficient(a, b)
        print(f"a/b = {a / b:g}: k = {k:.4f}, P = k pi^2 D / b = {k * math.pi ** 2 * d / b:.1f} N (D = {d:.1f} N mm)")
