#!/usr/bin/python3
"""Writes the seed's square tube with a crush trigger as a Gmsh msh 2.2 file beside this script.

Seed 000 section 4.3 meshes the tube with ~5 mm quads, "the curved surfaces of the folding region with
two rows of elements", and "a turn-around region at the front end to excite the intended dynamic
buckling mode"; it does not give that region's shape. This mesh takes the classic crush initiator of
the symmetric (compact) folding mode: over the first fold length (2 H = 30 mm, H = 0.99 (b^2 t)^(1/3)
= 15.2 mm the Wierzbicki-Abramowicz half-wavelength) the four flat faces are pushed in and out
alternately, by d(s, z) = A cos(pi s / w) sin(pi z / 2H) along their normal (s across the flat part of
width w = 50 mm, A = 0.1 mm = t / 10). The corners are not moved.

Mid-surface: 60 x 60 mm, corner radius 5 mm, 300 mm along z (z = 0 the held end); 10 quads of 5 mm on
each flat face and 2 on each corner arc (48 around), 60 rings of 5 mm. Physical groups `end0` (z = 0),
`end1` (z = 300) and `tube`. Quads counter-clockwise about the outward normal.

Run: /usr/bin/python3 validation/mpm_tube_crush/make_trigger_mesh.py [amplitude_mm]   (writes tube_trigger_5mm.msh)
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))  # validation/msh22.py
from msh22 import write_msh22  # noqa: E402

HALF_WIDTH, CORNER, LENGTH, RINGS = 30.0, 5.0, 300.0, 60
ON_FACE, ON_CORNER = 10, 2
FOLD_LENGTH = 30.0  # 2 H


def section():
    """Nodes of one ring, counter-clockwise: (x, y), outward normal, face sign (+1 / -1, 0 on corners), s."""
    flat = HALF_WIDTH - CORNER
    ring = []
    for k in range(4):
        c, s = math.cos(0.5 * math.pi * k), math.sin(0.5 * math.pi * k)
        rotate = lambda p: (c * p[0] - s * p[1], s * p[0] + c * p[1])  # noqa: E731
        for i in range(ON_FACE):
            across = -flat + 2.0 * flat * i / ON_FACE
            ring.append((rotate((HALF_WIDTH, across)), rotate((1.0, 0.0)), (-1) ** k, across))
        for j in range(ON_CORNER):
            angle = 0.5 * math.pi * j / ON_CORNER
            point = (flat + CORNER * math.cos(angle), flat + CORNER * math.sin(angle))
            ring.append((rotate(point), rotate((math.cos(angle), math.sin(angle))), 0, 0.0))
    return ring


def write(amplitude, path):
    ring = section()
    flat = HALF_WIDTH - CORNER
    nodes = []
    for jz in range(RINGS + 1):
        z = LENGTH * jz / RINGS
        for (p, normal, sign, across) in ring:
            d = 0.0
            if sign and z < FOLD_LENGTH:
                d = amplitude * sign * math.cos(0.5 * math.pi * across / flat) * math.sin(math.pi * z / FOLD_LENGTH)
            nodes.append((p[0] + d * normal[0], p[1] + d * normal[1], z))
    n = len(ring)
    nid = lambda i, j: j * n + (i % n) + 1  # noqa: E731
    elements = [(1, 1, (nid(i, 0), nid(i + 1, 0))) for i in range(n)]
    elements += [(1, 2, (nid(i, RINGS), nid(i + 1, RINGS))) for i in range(n)]
    elements += [(3, 3, (nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1))) for j in range(RINGS) for i in range(n)]
    write_msh22(path, [(1, 1, "end0"), (1, 2, "end1"), (2, 3, "tube")], nodes, elements)
    print("wrote", path)


if __name__ == "__main__":
    write(float(sys.argv[1]) if len(sys.argv) > 1 else 0.1, os.path.join(HERE, "tube_trigger_5mm.msh"))
