#!/usr/bin/python3
"""Side-by-side benchmark: lamina's explicit LPS peridynamics against LAMMPS `pair_style peri/lps`.

Same cubic lattice (n^3 particles, spacing a = 1 mm), same horizon (3.015 a), same material
(E = 70 GPa, nu = 0.25), same number of steps, same number of threads (lamina, OpenMP) or ranks
(LAMMPS, MPI; Debian's LAMMPS has no OpenMP package). Each code starts from a small random
velocity field so that bonds deform.

Figure: bond-updates per second = (directed bonds i->j within the horizon) x steps / loop time,
where loop time is the time of the time-step loop only (LAMMPS "Loop time"; lamina's
`explicit_loop_s`), i.e. without reading the input or building the neighbour lists. lamina's loop
also evaluates the strain and kinetic energy every step (LAMMPS: only at thermo output).
Memory: lamina's peak resident memory divided by particles and by directed bonds (an upper bound:
it includes the program, the case and the set-up), with the default bond storage (full at these sizes)
and with `pd.bond_storage: lean` (the neighbour index only; LeanPeridynamicSolid), each with its loop
time; `pd_lean_bytes_per_bond_besides_2kB_per_particle` = (peak - 2048 x particles) / bonds, the issue's
measure (target below 32).

Usage: bench/pd_lps_vs_lammps.py [--lamina build/lamina] [--n 51] [--steps 20] [--threads 1 2] [--no-lammps]
                                 [--storage both|auto|lean]
Ends with one `BENCH <name> <value> <unit>` line per figure (ratios lamina / LAMMPS included).
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


def directed_bonds(n):
    """Number of ordered pairs (i, j), i != j, of an n^3 simple cubic lattice within the horizon."""
    reach = int(HORIZON_FACTOR)
    total = 0
    for dx in range(-reach, reach + 1):
        for dy in range(-reach, reach + 1):
            for dz in range(-reach, reach + 1):
                if (dx, dy, dz) == (0, 0, 0) or dx * dx + dy * dy + dz * dz > HORIZON_FACTOR ** 2:
                    continue
                total += (n - abs(dx)) * (n - abs(dy)) * (n - abs(dz))
    return total


def run_lammps(n, steps, ranks, workdir, nx=None):
    """LAMMPS peri/lps on an nx x n x n lattice (nx = n: the cube) on `ranks` MPI ranks."""
    nx = n if nx is None else nx
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
timestep 1.0e-8
thermo {steps}
run {steps}
"""
    path = os.path.join(workdir, f"in_{nx}x{n}_{ranks}.lps")
    with open(path, "w") as f:
        f.write(deck)
    log = os.path.join(workdir, f"log_{nx}x{n}_{ranks}.lammps")
    cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), "lmp", "-in", path, "-log", log,
           "-screen", "none"]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    subprocess.run(cmd, check=True, env=env, cwd=workdir, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
    text = open(log).read()
    m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
    if not m:
        raise RuntimeError("no loop time in the LAMMPS log " + log)
    return {"loop_s": float(m.group(1)), "atoms": int(m.group(4))}


def run_lamina(lamina, n, steps, threads, workdir, storage="auto", nx=None, ranks=1):
    """lamina explicit run on the same lattice (nx x n x n, nx = n: the cube), written with PRODUCT.md's
    case keys, on `ranks` MPI ranks (lamina run --ranks) of `threads` threads."""
    nx = n if nx is None else nx
    dt = 1.0e-8
    case = f"""title: LPS block for the LAMMPS side-by-side benchmarks
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
  explicit: {{end_time: {steps * dt}, time_step: {dt}, outputs: 1}}
output: {{vtu: false}}
"""
    tag = f"{nx}x{n}_{ranks}r{threads}t_{storage}"
    path = os.path.join(workdir, f"lamina_{tag}.yaml")
    with open(path, "w") as f:
        f.write(case)
    out = os.path.join(workdir, f"lamina_{tag}")
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    command = [lamina, "run", path, "-o", out, "--quiet", "--threads", str(threads)]
    if ranks > 1:
        command += ["--ranks", str(ranks)]
    proc = subprocess.Popen(command, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"lamina exited with {os.waitstatus_to_exitcode(status)}")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    timing = summary["timing"]
    # peak memory: the process (one rank), or the ranks' peaks summed (summary.json memory)
    peak = usage.ru_maxrss * 1024.0 if ranks == 1 else summary["memory"]["peak_bytes"]
    return {"loop_s": timing["stage_explicit_loop_s"] if "stage_explicit_loop_s" in timing
            else timing["explicit_loop_s"], "atoms": summary["counts"]["nodes"], "nodes": summary["counts"]["nodes"],
            "peak_bytes": peak, "bonds": timing.get("bonds", timing.get("stage_bonds"))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--n", type=int, default=51, help="particles per direction (51^3 = 132,651)")
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--no-lammps", action="store_true", help="lamina only (no ratios)")
    parser.add_argument("--storage", choices=["both", "auto", "lean"], default="both",
                        help="lamina runs: the default storage and lean (both), or one of them (a 145^3 cube "
                             "needs lean: the full storage would take about 59 GB)")
    args = parser.parse_args()
    if not args.no_lammps and shutil.which("lmp") is None:
        sys.exit("lmp not found: scripts/install-deps.sh --peers")
    workdir = tempfile.mkdtemp(prefix="lamina_bench_lps_")
    bonds = directed_bonds(args.n)
    print(f"lattice {args.n}^3 = {args.n ** 3} particles, {bonds} directed bonds "
          f"({bonds / args.n ** 3:.1f} per particle), {args.steps} steps", flush=True)
    bench = []
    for threads in args.threads:
        lam = run_lamina(args.lamina, args.n, args.steps, threads, workdir, "lean" if args.storage == "lean" else "auto")
        lean = lam if args.storage == "lean" else run_lamina(args.lamina, args.n, args.steps, threads, workdir, "lean")
        if args.storage == "auto":
            lean = lam
        rate_lam = bonds * args.steps / lam["loop_s"]
        rate_lean = bonds * args.steps / lean["loop_s"]
        line = (f"  {threads} thread(s): lamina {lam['loop_s']:.3f} s ({rate_lam:.3g} bond-updates/s, "
                f"{lam['peak_bytes'] / bonds:.1f} B/bond peak), lean {lean['loop_s']:.3f} s ({rate_lean:.3g} bond-updates/s, "
                f"{lean['peak_bytes'] / bonds:.1f} B/bond peak)")
        bench += [(f"pd_lps_lamina_{threads}thread_bond_updates_per_s", rate_lam, "bond_updates/s"),
                  (f"pd_lps_lamina_lean_{threads}thread_bond_updates_per_s", rate_lean, "bond_updates/s")]
        if not args.no_lammps:
            lmp = run_lammps(args.n, args.steps, threads, workdir)
            if lmp["atoms"] != args.n ** 3 or lam["atoms"] != args.n ** 3:
                print(f"  warning: particle counts LAMMPS {lmp['atoms']}, lamina {lam['atoms']}")
            rate_lmp = bonds * args.steps / lmp["loop_s"]
            line += f"; LAMMPS {lmp['loop_s']:.3f} s ({rate_lmp:.3g} bond-updates/s), ratio {rate_lam / rate_lmp:.2f}"
            bench += [(f"pd_lps_lammps_{threads}proc_bond_updates_per_s", rate_lmp, "bond_updates/s"),
                      (f"pd_lps_speedup_lamina_over_lammps_{threads}", rate_lam / rate_lmp, "ratio"),
                      (f"pd_lps_speedup_lamina_lean_over_lammps_{threads}", rate_lean / rate_lmp, "ratio")]
        print(line, flush=True)
        bench += [("pd_peak_memory_per_particle", lam["peak_bytes"] / lam["atoms"], "bytes"),
                  ("pd_peak_memory_per_bond", lam["peak_bytes"] / bonds, "bytes"),
                  ("pd_lean_peak_memory_per_particle", lean["peak_bytes"] / lean["atoms"], "bytes"),
                  ("pd_lean_peak_memory_per_bond", lean["peak_bytes"] / bonds, "bytes"),
                  ("pd_lean_bytes_per_bond_besides_2kB_per_particle",
                   (lean["peak_bytes"] - 2048.0 * lean["atoms"]) / bonds, "bytes")]
    shutil.rmtree(workdir, ignore_errors=True)
    seen = set()
    for name, value, unit in bench:
        if name in seen:
            continue
        seen.add(name)
        print(f"BENCH {name} {value:.6g} {unit}")


if __name__ == "__main__":
    main()
