#!/usr/bin/python3
"""Writes square-plate shell meshes (unit square in the plane z = 0) as Gmsh msh 2.2 files beside this script.

n x n quadrilaterals, regular or distorted: every interior node moved by a random offset of up to 25 % of
the spacing along x and along y (Python's random, seed 1: the files are reproducible). Physical groups
`edge` (the boundary lines) and `plate` (the quadrilaterals, counter-clockwise about +z).

Run: /usr/bin/python3 validation/mpm_plate_distorted_mesh/make_mesh.py   (writes regular_8x8.msh,
distorted_8x8.msh, distorted_16x16.msh, distorted_32x32.msh)
"""
import os
import sys
import random

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # validation/msh22.py
from msh22 import write_msh22  # noqa: E402


def write(name, n, distortion):
    random.seed(1)
    h = 1.0 / n
    nodes = []
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = i * h, j * h
            if distortion and 0 < i < n and 0 < j < n:
                x += random.uniform(-distortion, distortion) * h
                y += random.uniform(-distortion, distortion) * h
            nodes.append((x, y, 0.0))
    nid = lambda i, j: j * (n + 1) + i + 1
    elements = []
    for i in range(n):
        for line in ((nid(i, 0), nid(i + 1, 0)), (nid(i, n), nid(i + 1, n)), (nid(0, i), nid(0, i + 1)),
                     (nid(n, i), nid(n, i + 1))):
            elements.append((1, 1, line))
    for j in range(n):
        for i in range(n):
            elements.append((3, 2, (nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1))))
    write_msh22(os.path.join(HERE, name), [(1, 1, "edge"), (2, 2, "plate")], nodes, elements)
    print("wrote", name)


if __name__ == "__main__":
    write("regular_8x8.msh", 8, 0.0)
    for n in (8, 16, 32):
        write(f"distorted_{n}x{n}.msh", n, 0.25)
