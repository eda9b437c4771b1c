#!/usr/bin/python3
"""Writes the MacNeal-Harder (1985) straight-cantilever shell meshes as Gmsh msh 2.2 files beside this script.

Beam L = 6 along x, width 0.2 along y (mid-surface in the plane z = 0), six quadrilaterals along and one
across, in the paper's three shapes (MacNeal & Harder 1985, figure 2):
  rectangular:   element boundaries at x = 0, 1, ..., 6, perpendicular to the axis;
  trapezoidal:   the five interior boundaries inclined at 45 degrees, alternately (offset +-0.1 at the
                 edges y = +-0.1, i.e. the boundary spans 0.2 along x across the 0.2 width);
  parallelogram: the five interior boundaries all inclined at 45 degrees the same way.
Root (x = 0) and tip (x = 6) stay perpendicular. Physical groups `root` (line, x = 0), `tip` (line,
x = 6) and `beam` (the quadrilaterals, counter-clockwise about +z).

Run: /usr/bin/python3 validation/mpm_straight_cantilever/make_mesh.py
"""
import os
import sys

L, W, N = 6.0, 0.2, 6
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # validation/msh22.py
from msh22 import write_msh22  # noqa: E402


def boundary_offset(shape, k):
    """x offset of the top edge (y = +W/2) of interior boundary k (the bottom edge gets the opposite)."""
    if k in (0, N) or shape == "rectangular":
        return 0.0
    if shape == "parallelogram":
        return 0.5 * W
    return 0.5 * W if k % 2 else -0.5 * W  # trapezoidal


def write(shape):
    n = N
    nodes = []
    for k in range(n + 1):
        off = boundary_offset(shape, k)
        for y in (-0.5 * W, 0.5 * W):
            nodes.append((L / N * k + (off if y > 0 else -off), y, 0.0))
    nid = lambda k, j: 2 * k + j + 1
    elements = [(1, 1, (nid(0, 0), nid(0, 1))), (1, 2, (nid(n, 0), nid(n, 1)))]
    for k in range(n):
        elements.append((3, 3, (nid(k, 0), nid(k + 1, 0), nid(k + 1, 1), nid(k, 1))))
    name = f"{shape}_{n}x1.msh"
    write_msh22(os.path.join(HERE, name), [(1, 1, "root"), (1, 2, "tip"), (2, 3, "beam")], nodes, elements)
    print("wrote", name)


if __name__ == "__main__":
    for shape in ("rectangular", "trapezoidal", "parallelogram"):
        write(shape)
