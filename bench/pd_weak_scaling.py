#!/usr/bin/python3
"""Weak scaling of distributed PD explicit dynamics, lamina beside LAMMPS `peri/lps`, on this machine.

One rank x 1 thread runs an n x n x n LPS block, 2 ranks x 1 thread a 2n x n x n block (the same
particles per rank): efficiency = loop time on 1 rank / loop time on 2 ranks (1.0 = perfect). lamina is
started with `lamina run --ranks 2 --threads 1` (mpirun underneath), LAMMPS with `mpirun -np 2 lmp`.
Same lattice (spacing 1 mm, horizon 3.015 spacings), material and step count as bench/pd_lps_vs_lammps.py;
loop time = the time-step loop only (lamina's explicit_loop_s on rank 0, LAMMPS' "Loop time"). Both
storage modes of lamina are measured (full: the default at these sizes; lean: pd.bond_storage: lean).

Usage: bench/pd_weak_scaling.py [--lamina build/lamina] [--n 41] [--steps 20] [--no-lammps]
Ends with `BENCH <name> <value> <unit>` lines.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SPACING = 1.0e-3
HORIZON_FACTOR = 3.015
E, NU, DENSITY = 70.0e9, 0.25, 2700.0
DT = 1.0e-8


def run_lamina(lamina, nx, n, steps, ranks, storage, workdir):
    case = f"""title: LPS block for the weak-scaling benchmark
method: pd
materials: [{{name: m, model: linear_elastic, E: {E}, nu: {NU}, density: {DENSITY}}}]
geometry: {{type: box, min: [0, 0, 0], max: [{nx * SPACING}, {n * SPACING}, {n * SPACING}]}}
discretization: {{spacing: [{SPACING}, {SPACING}, {SPACING}], horizon_factor: {HORIZON_FACTOR}}}
loads:
  - select: all
    initial_velocity: ["1e-3*sin(12345*x + 54321*y)", "1e-3*sin(23456*y + 65432*z)", "1e-3*sin(34567*z + 76543*x)"]
pd:
  influence: one
  surface_correction: none
  bond_storage: {storage}
  analysis: explicit
  explicit: {{end_time: {steps * DT}, time_step: {DT}, outputs: 1}}
output: {{vtu: false}}
"""
    path = os.path.join(workdir, f"lamina_{nx}_{ranks}_{storage}.yaml")
    with open(path, "w") as f:
        f.write(case)
    out = os.path.join(workdir, f"lamina_{nx}_{ranks}_{storage}")
    command = [lamina, "run", path, "-o", out, "--quiet", "--threads", "1"] + (["--ranks", str(ranks)] if ranks > 1 else [])
    subprocess.run(command, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    timing = summary["timing"]
    return {"loop_s": timing["stage_explicit_loop_s"], "nodes": summary["counts"]["nodes"], "bonds": timing["stage_bonds"]}


def run_lammps(nx, n, steps, ranks, workdir):
    bulk = E / (3 * (1 - 2 * NU))
    shear = E / (2 * (1 + NU))
    deck = f"""units si
boundary s s s
atom_style peri
atom_modify map array
lattice sc {SPACING}
region box block 0 {nx - 1} 0 {n - 1} 0 {n - 1}
create_box 1 box
create_atoms 1 region box
pair_style peri/lps
pair_coeff * * {bulk:.6e} {shear:.6e} {HORIZON_FACTOR * SPACING:.6e} 10.0 0.0
set group all density {DENSITY}
set group all volume {SPACING ** 3:.6e}
velocity all create 1.0e-3 87287 dist gaussian mom yes
fix 1 all nve
neighbor {0.5 * SPACING} bin
neigh_modify every 100000 delay 100000 check no
timestep {DT}
thermo {steps}
run {steps}
"""
    path = os.path.join(workdir, f"in_{nx}_{ranks}.lps")
    with open(path, "w") as f:
        f.write(deck)
    log = os.path.join(workdir, f"log_{nx}_{ranks}.lammps")
    command = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), "lmp", "-in", path, "-log", log,
               "-screen", "none"]
    subprocess.run(command, check=True, env=dict(os.environ, OMP_NUM_THREADS="1"), cwd=workdir,
                   stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", open(log).read())
    if not m:
        raise RuntimeError("no loop time in " + log)
    return {"loop_s": float(m.group(1)), "nodes": int(m.group(4))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--n", type=int, default=41, help="particles per direction per rank (41^3 = 68,921)")
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--no-lammps", action="store_true")
    args = parser.parse_args()
    if not args.no_lammps and shutil.which("lmp") is None:
        sys.exit("lmp not found: scripts/install-deps.sh --peers")
    workdir = tempfile.mkdtemp(prefix="lamina_bench_weak_")
    n = args.n
    print(f"weak scaling: {n}^3 = {n ** 3} particles per rank, {args.steps} steps, 1 thread per rank", flush=True)
    bench = []
    for storage in ("full", "lean"):
        one = run_lamina(args.lamina, n, n, args.steps, 1, storage, workdir)
        two = run_lamina(args.lamina, 2 * n, n, args.steps, 2, storage, workdir)
        efficiency = one["loop_s"] / two["loop_s"]
        print(f"  lamina {storage}: 1 rank {one['loop_s']:.3f} s ({one['nodes']} particles), 2 ranks {two['loop_s']:.3f} s "
              f"({two['nodes']} particles): efficiency {efficiency:.3f}", flush=True)
        bench += [(f"pd_weak_lamina_{storage}_1rank_loop_s", one["loop_s"], "s"),
                  (f"pd_weak_lamina_{storage}_2ranks_loop_s", two["loop_s"], "s"),
                  (f"pd_weak_efficiency_lamina_{storage}_2ranks", efficiency, "ratio")]
    if not args.no_lammps:
        one = run_lammps(n, n, args.steps, 1, workdir)
        two = run_lammps(2 * n, n, args.steps, 2, workdir)
        efficiency = one["loop_s"] / two["loop_s"]
        print(f"  LAMMPS peri/lps: 1 rank {one['loop_s']:.3f} s, 2 ranks {two['loop_s']:.3f} s: efficiency {efficiency:.3f}",
              flush=True)
        lamina_full = [v for k, v, u in bench if k == "pd_weak_lamina_full_2ranks_loop_s"][0]
        bench += [("pd_weak_lammps_1rank_loop_s", one["loop_s"], "s"), ("pd_weak_lammps_2ranks_loop_s", two["loop_s"], "s"),
                  ("pd_weak_efficiency_lammps_2ranks", efficiency, "ratio"),
                  ("pd_weak_speedup_lamina_full_over_lammps_2ranks", two["loop_s"] / lamina_full, "ratio")]
    shutil.rmtree(workdir, ignore_errors=True)
    for name, value, unit in bench:
        print(f"BENCH {name} {value:.6g} {unit}")


if __name__ == "__main__":
    main()
