#!/usr/bin/python3
"""Weak scaling of lamina's distributed explicit runs on this machine: PD (LAMMPS `peri/lps` beside it)
and MPM, in one run.

One rank x 1 thread runs a body, 2 ranks x 1 thread a body twice as large (the same work per rank):
efficiency = loop time on 1 rank / loop time on 2 ranks (1.0 = perfect). lamina is started with
`lamina run --ranks 2 --threads 1` (mpirun underneath), LAMMPS with `mpirun -np 2 lmp`.
- PD: an n x n x n LPS block against 2n x n x n, the lattice, material and steps of
  bench/pd_lps_vs_lammps.py; both storage modes (full: the default at these sizes; lean); loop time = the
  time-step loop (lamina's explicit_loop_s on rank 0, LAMMPS' "Loop time").
- MPM: the plate of bench/mpm_plate_cycles.py, m x m/2 elements against m x m (node-block decomposition:
  elements, P2G, grid update, G2P, grid location and the node sums divide; nodal forces and velocities
  are all-gathered every step); loop time = the sum of the step's
  stage times on rank 0.

Each configuration runs --repeat times (default 3) and its shortest loop time counts, lamina's and LAMMPS'
alike: the two cores also serve the operating system, and a single short run varies by 10-20 % here.

Usage: bench/weak_scaling.py [--lamina build/lamina] [--n 41] [--steps 20] [--mpm-elements 100]
                             [--mpm-steps 1000] [--repeat 3] [--no-lammps]
Ends with `BENCH <name> <value> <unit>` lines.
"""
import argparse
import json
import os
import subprocess
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mpm_plate_cycles import plate_case  # noqa: E402  the same MPM plate
from pd_lps_vs_lammps import run_lamina, run_lammps  # noqa: E402  the same cases and LAMMPS deck

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run_mpm(lamina, elements_x, elements_y, steps, ranks, workdir):
    path = os.path.join(workdir, f"mpm_{elements_x}x{elements_y}.yaml")
    with open(path, "w") as f:
        f.write(plate_case(elements_x, elements_y, steps, 1.0e-6))
    out = os.path.join(workdir, f"mpm_{elements_x}x{elements_y}_{ranks}")
    command = [lamina, "run", path, "-o", out, "--quiet", "--threads", "1"] + (["--ranks", str(ranks)] if ranks > 1 else [])
    subprocess.run(command, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        timing = json.load(f)["timing"]
    stages = {k: v for k, v in timing.items() if k.startswith("stage_") and k.endswith("_s")}
    return {"loop_s": sum(stages.values()), "element_s": timing.get("stage_element_s", 0.0)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--n", type=int, default=41, help="particles per direction per rank (41^3 = 68,921)")
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--mpm-elements", type=int, default=100, help="MPM plate: m x m/2 elements per rank")
    parser.add_argument("--mpm-steps", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3, help="runs per configuration; the shortest loop time counts")
    parser.add_argument("--no-lammps", action="store_true")
    args = parser.parse_args()
    if not args.no_lammps and shutil.which("lmp") is None:
        sys.exit("lmp not found: scripts/install-deps.sh --peers")
    workdir = tempfile.mkdtemp(prefix="lamina_bench_weak_")

    def fastest(run):
        return min((run() for _ in range(max(1, args.repeat))), key=lambda r: r["loop_s"])

    n = args.n
    print(f"weak scaling: {n}^3 = {n ** 3} particles per rank, {args.steps} steps, 1 thread per rank, "
          f"shortest of {args.repeat} runs", flush=True)
    bench = []
    for storage in ("full", "lean"):
        one = fastest(lambda: run_lamina(args.lamina, n, args.steps, 1, workdir, storage))
        two = fastest(lambda: run_lamina(args.lamina, n, args.steps, 1, workdir, storage, nx=2 * n, ranks=2))
        efficiency = one["loop_s"] / two["loop_s"]
        print(f"  lamina {storage}: 1 rank {one['loop_s']:.3f} s ({one['nodes']} particles), 2 ranks {two['loop_s']:.3f} s "
              f"({two['nodes']} particles): efficiency {efficiency:.3f}", flush=True)
        bench += [(f"pd_weak_lamina_{storage}_1rank_loop_s", one["loop_s"], "s"),
                  (f"pd_weak_lamina_{storage}_2ranks_loop_s", two["loop_s"], "s"),
                  (f"pd_weak_efficiency_lamina_{storage}_2ranks", efficiency, "ratio")]
    if not args.no_lammps:
        one = fastest(lambda: run_lammps(n, args.steps, 1, workdir))
        two = fastest(lambda: run_lammps(n, args.steps, 2, workdir, nx=2 * n))
        efficiency = one["loop_s"] / two["loop_s"]
        print(f"  LAMMPS peri/lps: 1 rank {one['loop_s']:.3f} s, 2 ranks {two['loop_s']:.3f} s: efficiency {efficiency:.3f}",
              flush=True)
        lamina_full = [v for k, v, u in bench if k == "pd_weak_lamina_full_2ranks_loop_s"][0]
        bench += [("pd_weak_lammps_1rank_loop_s", one["loop_s"], "s"), ("pd_weak_lammps_2ranks_loop_s", two["loop_s"], "s"),
                  ("pd_weak_efficiency_lammps_2ranks", efficiency, "ratio"),
                  ("pd_weak_speedup_lamina_full_over_lammps_2ranks", two["loop_s"] / lamina_full, "ratio")]
    m = args.mpm_elements
    one = fastest(lambda: run_mpm(args.lamina, m, m // 2, args.mpm_steps, 1, workdir))
    two = fastest(lambda: run_mpm(args.lamina, m, 2 * (m // 2), args.mpm_steps, 2, workdir))
    efficiency = one["loop_s"] / two["loop_s"]
    print(f"  lamina mpm: 1 rank {one['loop_s']:.3f} s ({m * (m // 2)} elements; element stage {one['element_s']:.3f} s), "
          f"2 ranks {two['loop_s']:.3f} s (element stage {two['element_s']:.3f} s): efficiency {efficiency:.3f}", flush=True)
    bench += [("mpm_weak_lamina_1rank_loop_s", one["loop_s"], "s"), ("mpm_weak_lamina_2ranks_loop_s", two["loop_s"], "s"),
              ("mpm_weak_efficiency_lamina_2ranks", efficiency, "ratio")]
    shutil.rmtree(workdir, ignore_errors=True)
    for name, value, unit in bench:
        print(f"BENCH {name} {value:.6g} {unit}")


if __name__ == "__main__":
    main()
