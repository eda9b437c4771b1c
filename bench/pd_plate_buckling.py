#!/usr/bin/python3
"""PD linear buckling benchmark (issue 15, criterion 4): a simply supported square plate
200 x 200 x 2 mm under uniaxial compression on a 2-layer lattice of about 10,000 nodes (71 x 71
columns, dx = 2.857 mm) at horizon 3 dx, default model (the director plate model), 2 threads; peer:
CalculiX 2.20 (ccx) *BUCKLE with S8R shells on a mesh with the same number of displacement dofs
(41 x 41 elements, 5,125 nodes x 6 dofs), measured in the same run.

Figures: wall time of the whole lamina run (set-up, zero-energy check, assembly, linear solve,
eigen solve, output) and its stages, the first load factor of both codes against the classical
4 pi^2 D / b = 10190 N, and the wall-time ratio lamina / ccx. Target: lamina under 30 s on 2 threads.

Usage: bench/pd_plate_buckling.py [--lamina build/lamina] [--threads 2] [--columns 71] [--no-ccx]
Ends with one `BENCH <name> <value> <unit>` line per figure.
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
E, NU, T, B = 69000.0, 0.33, 2.0, 200.0
REFERENCE = 4 * math.pi ** 2 * E * T ** 3 / (12 * (1 - NU ** 2)) / B


def thread_env(threads):
    env = dict(os.environ)
    for key in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "CCX_NPROC_EQUATION_SOLVER", "CCX_NPROC_STIFFNESS"):
        env[key] = str(threads)
    return env


def lamina_case(columns):
    dx = B / (columns - 1)
    f = (B + dx) / B
    return f"""title: bench square SS plate, {columns} x {columns} columns, 2 layers
method: pd
units: N, mm, MPa
materials:
  - {{name: al, model: linear_elastic, E: {E}, nu: {NU}}}
geometry: {{type: plate, min: [{-dx / 2}, {-dx / 2}], max: [{B + dx / 2}, {B + dx / 2}], thickness: {T}}}
discretization: {{spacing: [{dx}, {dx}, 1], horizon: {3 * dx}}}
boundary:
  - {{select: {{where: "x < {dx / 4} or x > {B - dx / 4} or y < {dx / 4} or y > {B - dx / 4}"}}, fix: [z]}}
  - {{select: {{nearest: [100, 100, -0.5]}}, fix: [x]}}
  - {{select: {{nearest: [0, 0, -0.5]}}, fix: [y]}}
  - {{select: {{nearest: [{B}, 0, -0.5]}}, fix: [y]}}
loads:
  - {{select: {{where: "x > {B - dx / 4}"}}, force: [{-f}, 0, 0]}}
  - {{select: {{where: "x < {dx / 4}"}}, force: [{f}, 0, 0]}}
pd: {{analysis: buckling, buckling: {{modes: 1}}}}
probes:
  - {{name: P1, field: eigenvalue, component: 1}}
"""


def run_lamina(lamina, columns, threads, workdir):
    path = os.path.join(workdir, "plate.yaml")
    with open(path, "w") as f:
        f.write(lamina_case(columns))
    out = os.path.join(workdir, "out")
    start = time.perf_counter()
    subprocess.run([lamina, "run", path, "-o", out, "--quiet", "--threads", str(threads)], check=True,
                   env=thread_env(threads))
    wall = time.perf_counter() - start
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return wall, summary


def ccx_deck(elements):
    """S8R shells, simply supported (w = 0 on the edges), uniform edge compression of total 1 N."""
    n = 2 * elements + 1
    h = B / (2 * elements)
    ids = {}
    lines = ["*HEADING", "square SS plate buckling, S8R", "*NODE"]
    for j in range(n):
        for i in range(n):
            if i % 2 == 1 and j % 2 == 1:
                continue  # no centre node in S8R
            ids[(i, j)] = len(ids) + 1
            lines.append(f"{ids[(i, j)]}, {i * h}, {j * h}, 0")
    lines.append("*ELEMENT, TYPE=S8R, ELSET=PLATE")
    e = 0
    for ej in range(elements):
        for ei in range(elements):
            i, j = 2 * ei, 2 * ej
            e += 1
            c = [ids[(i, j)], ids[(i + 2, j)], ids[(i + 2, j + 2)], ids[(i, j + 2)],
                 ids[(i + 1, j)], ids[(i + 2, j + 1)], ids[(i + 1, j + 2)], ids[(i, j + 1)]]
            lines.append(f"{e}, " + ", ".join(map(str, c)))
    edge = [k for (i, j), k in ids.items() if i in (0, n - 1) or j in (0, n - 1)]
    lines += ["*NSET, NSET=EDGE"] + [", ".join(map(str, edge[k:k + 16])) for k in range(0, len(edge), 16)]
    # consistent nodal forces of a uniform edge load on quadratic edges: 1/6, 4/6, 1/6 per element side
    load = {}
    for j in range(n):
        for side, sign in ((0, 1.0), (n - 1, -1.0)):
            if (side, j) not in ids:
                continue
            weight = (4.0 if j % 2 == 1 else (1.0 if j in (0, n - 1) else 2.0)) / (6.0 * elements)
            load[ids[(side, j)]] = sign * weight
    centre = ids[(elements if elements % 2 == 0 else elements - 1, elements if elements % 2 == 0 else elements - 1)]
    lines += ["*MATERIAL, NAME=AL", "*ELASTIC", f"{E}, {NU}", "*SHELL SECTION, ELSET=PLATE, MATERIAL=AL", f"{T}",
              "*BOUNDARY", "EDGE, 3, 3", f"{centre}, 1, 2", f"{ids[(n - 1, 0)]}, 2, 2",
              "*STEP", "*BUCKLE", "4", "*CLOAD"]
    lines += [f"{k}, 1, {v}" for k, v in load.items()]
    lines += ["*END STEP"]
    return "\n".join(lines) + "\n", 6 * len(ids)


def run_ccx(elements, threads, workdir):
    deck, dofs = ccx_deck(elements)
    with open(os.path.join(workdir, "plate.inp"), "w") as f:
        f.write(deck)
    start = time.perf_counter()
    subprocess.run(["ccx", "-i", "plate"], cwd=workdir, env=thread_env(threads), check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    factor = None
    with open(os.path.join(workdir, "plate.dat")) as f:
        lines = f.read().splitlines()
    for k, line in enumerate(lines):
        if "MODE NO" in line:
            for rest in lines[k + 1:]:
                parts = rest.split()
                if len(parts) == 2:
                    factor = float(parts[1])
                    break
            break
    return wall, factor, dofs


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--columns", type=int, default=71)
    parser.add_argument("--elements", type=int, default=41)
    parser.add_argument("--no-ccx", action="store_true")
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="lamina_bench_pd_buckling_")
    wall, summary = run_lamina(args.lamina, args.columns, args.threads, work)
    p1 = summary["probes"]["P1"]
    timing = summary.get("timing", {})
    nodes = summary["counts"]["nodes"]
    print(f"lamina: {nodes} nodes, {args.threads} threads: wall {wall:.2f} s, P1 = {p1:.1f} N "
          f"({100 * (p1 / REFERENCE - 1):+.2f} % of 4 pi^2 D / b = {REFERENCE:.1f} N); stages: "
          + ", ".join(f"{k} {v:.3g}" for k, v in sorted(timing.items())))
    lines = [f"BENCH pd_plate_buckling_nodes {nodes} nodes",
             f"BENCH pd_plate_buckling_wall_{args.threads}t {wall:.2f} s",
             f"BENCH pd_plate_buckling_wall_vs_30s_{args.threads}t {wall / 30.0:.3f} ratio",
             f"BENCH pd_plate_buckling_p1_error {100 * (p1 / REFERENCE - 1):.3f} %"]
    if not args.no_ccx and shutil.which("ccx"):
        cwall, factor, dofs = run_ccx(args.elements, args.threads, work)
        print(f"ccx: S8R {args.elements} x {args.elements}, {dofs} dofs: wall {cwall:.2f} s, P1 = {factor:.1f} N "
              f"({100 * (factor / REFERENCE - 1):+.2f} %)")
        lines += [f"BENCH pd_plate_buckling_ccx_wall_{args.threads}t {cwall:.2f} s",
                  f"BENCH pd_plate_buckling_ccx_p1_error {100 * (factor / REFERENCE - 1):.3f} %",
                  f"BENCH pd_plate_buckling_wall_ratio_lamina_over_ccx {wall / cwall:.3f} ratio"]
    shutil.rmtree(work, ignore_errors=True)
    for line in lines:
        print(line)


if __name__ == "__main__":
    main()
