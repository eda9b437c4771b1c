#!/usr/bin/python3
"""Writes the MacNeal-Harder (1985) curved-beam shell mesh as a Gmsh msh 2.2 file beside this script.

A quarter ring in the plane z = 0, inner radius 4.12, outer radius 4.32, from the root on the x axis
(theta = 0) to the tip on the y axis (theta = 90 degrees): n quadrilaterals along the arc and m across the
width, counter-clockwise about +z; the paper's mesh is 6 x 1 (each a slightly tapered trapezoid), and
12 x 2, 24 x 4 refine it. Physical
groups `root` (line, theta = 0), `tip` (line, theta = 90 degrees) and `beam` (the quadrilaterals).

Run: /usr/bin/python3 validation/mpm_curved_cantilever/make_mesh.py   (writes curved_6x1.msh, curved_12x2.msh, curved_24x4.msh)
"""
import math
import os
import sys

R_IN, R_OUT = 4.12, 4.32
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # validation/msh22.py
from msh22 import write_msh22  # noqa: E402


def write(n, m):
    nodes = []
    for k in range(n + 1):
        th = 0.5 * math.pi * k / n
        for j in range(m + 1):
            r = R_IN + (R_OUT - R_IN) * j / m
            nodes.append((r * math.cos(th), r * math.sin(th), 0.0))
    nid = lambda k, j: (m + 1) * k + j + 1
    elements = [(1, 1, (nid(0, j), nid(0, j + 1))) for j in range(m)]
    elements += [(1, 2, (nid(n, j), nid(n, j + 1))) for j in range(m)]
    for k in range(n):
        for j in range(m):
            elements.append((3, 3, (nid(k, j + 1), nid(k, j), nid(k + 1, j), nid(k + 1, j + 1))))
    name = f"curved_{n}x{m}.msh"
    write_msh22(os.path.join(HERE, name), [(1, 1, "root"), (1, 2, "tip"), (2, 3, "beam")], nodes, elements)
    print("wrote", name)


if __name__ == "__main__":
    for n, m in ((6, 1), (12, 2), (24, 4)):
        write(n, m)
