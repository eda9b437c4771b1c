#!/usr/bin/env python3
"""Write examples/omll_clamped_plate.omll: seed 004's OMLL deck of section 2.2 (clamped square
plate 20 x 20 x 1, centre point load, quarter model 10 x 10 x 1, E = 1e4, nu = 0.3) completed with
the node, boundary and cell lists the thesis elides ("... .."): 11 x 11 x 3 nodes (363), 120
boundary rows (clamped edges x = 0 and y = 0, symmetry planes x = 10 and y = 10), the quarter
load -100 at the plate centre's mid-plane node (10, 10, 0.5), and 10 x 10 x 2 cells (200).

Usage: scripts/make_omll_clamped_plate.py [OUTPUT]   (default examples/omll_clamped_plate.omll)
"""
import os
import sys

NX, NY, NZ = 11, 11, 3
LX, LY, T = 10.0, 10.0, 1.0


def node_id(i, j, k):
    return 1 + i + NX * (j + NY * k)


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    out_path = argv[1] if len(argv) > 1 else os.path.join(here, "..", "examples", "omll_clamped_plate.omll")
    coords = {}
    for k in range(NZ):
        for j in range(NY):
            for i in range(NX):
                coords[node_id(i, j, k)] = (LX * i / (NX - 1), LY * j / (NY - 1), T * k / (NZ - 1))
    boundary = []
    for n, (x, y, z) in sorted(coords.items()):
        clamped = x == 0.0 or y == 0.0
        if clamped:
            flags = (0, 0, 0)
        elif x == LX or y == LY:
            # symmetry planes: 0 = displacement prescribed (zero), 1 = free
            flags = (0 if x == LX else 1, 0 if y == LY else 1, 1)
        else:
            continue
        boundary.append((n, flags))
    load_node = node_id(NX - 1, NY - 1, (NZ - 1) // 2)
    cells = []
    for k in range(NZ - 1):
        for j in range(NY - 1):
            for i in range(NX - 1):
                cells.append([node_id(i, j, k), node_id(i + 1, j, k), node_id(i + 1, j + 1, k), node_id(i, j + 1, k),
                              node_id(i, j, k + 1), node_id(i + 1, j, k + 1), node_id(i + 1, j + 1, k + 1),
                              node_id(i, j + 1, k + 1)])

    lines = []
    w = lines.append
    w("% OMLL deck of seed 004 section 2.2 (clamped square plate, centre point load, quarter model),")
    w("% completed with generated node / boundary / cell lists by scripts/make_omll_clamped_plate.py.")
    w("%   ./lamina run examples/omll_clamped_plate.omll        ./lamina convert examples/omll_clamped_plate.omll")
    w("RESULTFILE PLATE.RES % result file of the original program (lamina writes its result set instead)")
    w("OMLL *** Problem of a Plate(LX=10.0, LY= 10.0, T=1.0) *** % title")
    w("NDM 3 % space dimension")
    w(f"NUMNP {len(coords)} % number of nodes")
    w(f"NUMEV {len(coords)} % number of evaluation points")
    w(f"NDISP {len(boundary)} % number of nodes with prescribed displacements")
    w("NLOAD 1 % number of loaded nodes")
    w("NUMMAT 1 % number of materials")
    w("MATERIAL % material data")
    w("% Generic isotropic linear elastic material: name E nu (and a third value, kept as density)")
    w("ISOELASTIC Generic 10000.0 0.3 6.8")
    w("NODE % node data")
    w("NODE")
    w("# PointID          x              y              z")
    for n, (x, y, z) in sorted(coords.items()):
        w(f"{n:<6d} {x:16.10f} {y:16.10f} {z:16.10f}")
    w("")
    w("BOUNDARY % prescribed displacements")
    w("## Essential boundary conditions at nodes (flag 0: prescribed, 1: free)")
    w("## PointID  material  idx  idy  idz  u  v  w")
    for n, (fx, fy, fz) in boundary:
        w(f"{n:<6d} Generic  {fx:3d} {fy:3d} {fz:3d}      0.000  0.0000  0.0000")
    w("")
    w("LOAD")
    w("% Load boundary in each point: PointID material idx idy idz nx ny nz fx fy fz")
    w(f"{load_node:<6d} Generic      0   0   0      0.0000  0.0000  1.0000  0.0000  0.0000  -100.00")
    w("")
    w("EVPOINT")
    w("COPY ALL Generic  1.0 % all nodes are evaluation points")
    w("ENDEVPOINT")
    w("")
    w("EFGDATA % background cells of the Galerkin method")
    w(f"NCELL {len(cells)} % number of cells")
    w("NINTX 3 % Gauss points in x")
    w("NINTY 3 % Gauss points in y")
    w("NINTZ 3 % Gauss points in z")
    w("CELL NODE % cells by their node numbers")
    for c in cells:
        w("Generic  " + " ".join(f"{n:4d}" for n in c))
    w("ENDEFGDATA")
    w("")
    w("ENDDATA % end of the domain data")
    w("ECHO OFF")
    w("BATCH % batch solution")
    w("CHECK")
    w("MLS % MLS approximation")
    w("BASIS QUADRIC % quadratic basis")
    w("WEIGHTFUNCTION SLS234 3 % quartic spline weight (the parameter is not used)")
    w("SINCHECK % replace influence nodes while the moment matrix is singular")
    w("INFLENCEDOMAIN Fix 2.01 2.01 1.01 % equal support radii at every node")
    w("BAND ON")
    w("EFGM % element-free Galerkin method")
    w("Penalty 1.0e5 % penalty value")
    w("TIMER START")
    w("TANGENT")
    w("SOLVE")
    w("OUTPUT")
    w("PRINT Solving finished.")
    w("TIMER PRINT")
    w("END")
    w("STOP")
    with open(out_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
