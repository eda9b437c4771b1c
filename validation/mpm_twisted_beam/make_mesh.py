#!/usr/bin/python3
"""Writes the MacNeal-Harder (1985) twisted-beam shell meshes as Gmsh msh 2.2 files beside this script.

Mid-surface: x = L a, (y, z) = w (s - 1/2) (cos(theta), sin(theta)), theta = (pi/2) a, a = x / L in [0, 1],
s in [0, 1] across the width; L = 12, w = 1.1 (90-degree pretwist). Quadrilaterals nl (along) x nw
(across), counter-clockwise about the normal (-sin(theta), cos(theta)) x ... ; physical groups
`root` (x = 0, line), `tip` (x = L, line) and `beam` (the quads).

Run: /usr/bin/python3 validation/mpm_twisted_beam/make_mesh.py   (writes twisted_12x2.msh, twisted_24x4.msh,
twisted_48x8.msh)
"""
import math
import os
import sys

L, W = 12.0, 1.1
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # validation/msh22.py
from msh22 import write_msh22  # noqa: E402


def write(nl, nw):
    nodes = []
    for j in range(nl + 1):
        a = j / nl
        th = 0.5 * math.pi * a
        for i in range(nw + 1):
            y = W * (i / nw - 0.5)
            nodes.append((L * a, y * math.cos(th), y * math.sin(th)))
    nid = lambda i, j: j * (nw + 1) + i + 1
    elements = []
    for i in range(nw):  # root line, tip line
        elements.append((1, 1, (nid(i, 0), nid(i + 1, 0))))
    for i in range(nw):
        elements.append((1, 2, (nid(i, nl), nid(i + 1, nl))))
    for j in range(nl):
        for i in range(nw):
            elements.append((3, 3, (nid(i, j), nid(i, j + 1), nid(i + 1, j + 1), nid(i + 1, j))))
    path = os.path.join(HERE, f"twisted_{nl}x{nw}.msh")
    write_msh22(path, [(1, 1, "root"), (1, 2, "tip"), (2, 3, "beam")], nodes, elements)
    print("wrote", path)


if __name__ == "__main__":
    for nl, nw in ((12, 2), (24, 4), (48, 8)):
        write(nl, nw)
