#!/usr/bin/env python3
"""Independent reference for mpm_hemisphere: CalculiX S8R shells, geometrically nonlinear (NLGEOM),
of the whole hemisphere (R 10, t 0.04, E 6.825e7, nu 0.3, 18-degree hole at the pole) under the four
alternating radial forces of 400 on the equator (outward at theta = 0 and 180 degrees, inward at 90
and 270), 20 equal increments, displacements of the two load points printed every other increment.

The whole hemisphere, not the quarter: symmetry planes on S8R shells need rotational conditions,
which CalculiX turns into rigid knots (with them the quarter came out 85 times too stiff; without
them, too flexible). Rigid motion is held by conditions that the symmetric answer meets without a
reaction: w = 0 at the equator points at 45, 135 and 225 degrees, u_y = 0 at the two outward load
points, u_x = 0 at one inward load point.

    python3 calculix_reference.py 16 hemisphere16   # 16 x 16 S8R per quarter; then: ccx hemisphere16
    python3 calculix_reference.py 24 hemisphere24
Results (reference.csv columns ux_out_ccx / uy_in_ccx are the 24 x 24 run): README.md.
"""
import math
import sys


def write(n, name, radius=10.0, thickness=0.04, young=6.825e7, poisson=0.3, force=400.0):
    azimuth_lines = 2 * 4 * n             # corner and mid-side node lines around the equator (periodic)
    polar_lines = 2 * n + 1               # from the equator (j = 0) to the hole edge

    def node(i, j):
        return j * azimuth_lines + (i % azimuth_lines) + 1

    def exists(i, j):                     # S8R: no node at an element centre
        return not (i % 2 == 1 and j % 2 == 1)

    out = ["*NODE"]
    for j in range(polar_lines):
        phi = math.radians(90 - 72 * j / (polar_lines - 1))
        for i in range(azimuth_lines):
            if exists(i, j):
                theta = 2 * math.pi * i / azimuth_lines
                out.append(f"{node(i, j)},{radius * math.sin(phi) * math.cos(theta):.12g},"
                           f"{radius * math.sin(phi) * math.sin(theta):.12g},{radius * math.cos(phi):.12g}")
    out.append("*ELEMENT,TYPE=S8R,ELSET=EALL")
    element = 1
    for jj in range(n):
        for ii in range(4 * n):
            i, j = 2 * ii, 2 * jj
            out.append(f"{element},{node(i, j)},{node(i + 2, j)},{node(i + 2, j + 2)},{node(i, j + 2)},"
                       f"{node(i + 1, j)},{node(i + 2, j + 1)},{node(i + 1, j + 2)},{node(i, j + 1)}")
            element += 1
    quarter = azimuth_lines // 4
    a, b, a2, b2 = node(0, 0), node(quarter, 0), node(2 * quarter, 0), node(3 * quarter, 0)
    out += ["*NSET,NSET=A", str(a), "*NSET,NSET=B", str(b)]
    out += ["*MATERIAL,NAME=SHELL", "*ELASTIC", f"{young},{poisson}",
            "*SHELL SECTION,ELSET=EALL,MATERIAL=SHELL", f"{thickness}"]
    out += ["*BOUNDARY"] + [f"{node(quarter // 2 + k * quarter, 0)},3,3" for k in range(3)]
    out += [f"{a},2,2", f"{a2},2,2", f"{b},1,1"]
    out += ["*STEP,NLGEOM,INC=1000", "*STATIC,DIRECT", "0.05,1.0", "*CLOAD",
            f"{a},1,{force}", f"{a2},1,{-force}", f"{b},2,{-force}", f"{b2},2,{force}",
            "*NODE PRINT,NSET=A,FREQUENCY=2", "U", "*NODE PRINT,NSET=B,FREQUENCY=2", "U", "*END STEP"]
    with open(name + ".inp", "w") as handle:
        handle.write("\n".join(out) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    write(int(sys.argv[1]), sys.argv[2])
