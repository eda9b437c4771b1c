#!/usr/bin/env python3
"""Independent reference for a PD plate lattice "as built": CalculiX S8R linear buckling (*BUCKLE) of
the whole plate the lattice's cells cover, simply supported (w = 0) on the lines of the outer node
columns, a distance c inside the plate's edges, and compressed by a uniform line load on the two
loaded node lines (x = c and x = W - c; total force 1, spread over the full width W, as the PD edge
forces are spread over the outer column's nodes). In-plane rigid motion is held at the centre and at
one point of the x = W - c line. The overhang strips (width c) are part of the plate.

    python3 calculix_as_built.py W c elements name [nu] [pressure q]   # writes name.inp; then: ccx name
    # the case:            200 2.5 80 as_built      -> 10939.3 (P on the 200 mm width)
    # no overhang control: 195 0   78 no_overhang   -> 10361.4 (k = 4 gives 10451.0 on 195 mm)
    # refined case mesh:   200 2.5 160 as_built_fine -> 10939.2

With `pressure q` the step is linear static under a uniform pressure q on the whole plate instead
(validation/pd_plate_bending), and the centre node's displacement is printed:
    # 210 5 84 bend_b20 0.3 pressure 0.001     -> w_centre 0.120775 (SS lines at 0 and 200 of the PD case)
    # 205 2.5 82 bend_b40 0.3 pressure 0.001   -> w_centre 0.125215
    # 200 0 80 bend_plain 0.3 pressure 0.001   -> w_centre 0.129636 (Timoshenko: 0.12851, S8R +0.9 %)
The buckling factor is the total edge force P_cr on the width W. Square mesh of W / elements,
which must put a node line (corner or mid-side) on x, y = c. Material and thickness as the case:
E 69000, nu 0.33, t 2.
"""
import sys


def write(width, overhang, elements, name, young=69000.0, poisson=0.33, thickness=2.0, pressure=None):
    size = width / elements
    lines = 2 * elements + 1                     # corner and mid-side node lines per direction

    def node(i, j):
        return j * lines + i + 1

    def exists(i, j):                            # S8R: no node at an element centre
        return not (i % 2 == 1 and j % 2 == 1)

    support = round(overhang / (size / 2))
    if abs(support * size / 2 - overhang) > 1e-9:
        raise SystemExit("the overhang must fall on a node line (a multiple of half the element size)")
    far = lines - 1 - support
    out = ["*NODE"]
    out += [f"{node(i, j)},{i * size / 2},{j * size / 2},0" for j in range(lines) for i in range(lines) if exists(i, j)]
    out.append("*ELEMENT,TYPE=S8R,ELSET=EALL")
    e = 1
    for jj in range(elements):
        for ii in range(elements):
            i, j = 2 * ii, 2 * jj
            out.append(f"{e},{node(i, j)},{node(i + 2, j)},{node(i + 2, j + 2)},{node(i, j + 2)},"
                       f"{node(i + 1, j)},{node(i + 2, j + 1)},{node(i + 1, j + 2)},{node(i, j + 1)}")
            e += 1
    supported = sorted(node(i, j) for j in range(lines) for i in range(lines)
                       if exists(i, j) and (i in (support, far) or j in (support, far)))
    out.append("*NSET,NSET=SUPPORT")
    out += [str(k) for k in supported]
    out += ["*MATERIAL,NAME=PLATE", "*ELASTIC", f"{young},{poisson}",
            "*SHELL SECTION,ELSET=EALL,MATERIAL=PLATE", f"{thickness}"]
    middle = (lines - 1) // 2
    out += ["*BOUNDARY", "SUPPORT,3,3", f"{node(middle, middle)},1,2", f"{node(far, middle)},2,2"]
    if pressure is not None:
        out += ["*NSET,NSET=CENTRE", str(node(middle, middle)), "*STEP", "*STATIC", "*DLOAD", f"EALL,P,{pressure}",
                "*NODE PRINT,NSET=CENTRE", "U", "*END STEP"]
        with open(name + ".inp", "w") as handle:
            handle.write("\n".join(out) + "\n")
        return
    out += ["*STEP", "*BUCKLE", "2", "*CLOAD"]
    force = {}                                   # consistent quadratic line-load weights, total 1
    for jj in range(elements):
        for j, w in ((2 * jj, 1 / 6), (2 * jj + 1, 4 / 6), (2 * jj + 2, 1 / 6)):
            force[j] = force.get(j, 0.0) + w * size / width
    for j, f in sorted(force.items()):
        out += [f"{node(support, j)},1,{f}", f"{node(far, j)},1,{-f}"]
    out += ["*END STEP"]
    with open(name + ".inp", "w") as handle:
        handle.write("\n".join(out) + "\n")


if __name__ == "__main__":
    if len(sys.argv) not in (5, 6, 8):
        raise SystemExit(__doc__)
    nu = float(sys.argv[5]) if len(sys.argv) > 5 else 0.33
    q = float(sys.argv[7]) if len(sys.argv) == 8 and sys.argv[6] == "pressure" else None
    write(float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4], poisson=nu, pressure=q)
