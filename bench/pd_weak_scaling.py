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
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pd_lps_vs_lammps import run_lamina, run_lammps  # noqa: E402  the same cases and LAMMPS deck

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


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
        one = run_lamina(args.lamina, n, args.steps, 1, workdir, storage)
        two = run_lamina(args.lamina, n, args.steps, 1, workdir, storage, nx=2 * n, ranks=2)
        efficiency = one["loop_s"] / two["loop_s"]
        print(f"  lamina {storage}: 1 rank {one['loop_s']:.3f} s ({one['nodes']} particles), 2 ranks {two['loop_s']:.3f} s "
              f"({two['nodes']} particles): efficiency {efficiency:.3f}", flush=True)
        bench += [(f"pd_weak_lamina_{storage}_1rank_loop_s", one["loop_s"], "s"),
                  (f"pd_weak_lamina_{storage}_2ranks_loop_s", two["loop_s"], "s"),
                  (f"pd_weak_efficiency_lamina_{storage}_2ranks", efficiency, "ratio")]
    if not args.no_lammps:
        one = run_lammps(n, args.steps, 1, workdir)
        two = run_lammps(n, args.steps, 2, workdir, nx=2 * n)
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
