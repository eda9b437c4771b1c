#!/usr/bin/python3
"""Side-by-side benchmark: lamina EFG against CalculiX C3D20R on the clamped plate R1a.

Problem (../shared/references R1a): quarter of a clamped 20 x 20 x 1 plate, E = 1e4, nu = 0.3,
400 total as pressure on the 1 x 1 centre patch of the top face; quantity uz(10, 10, 0.5),
converged value -1.03190.

Measured in one run of this script, on this machine:
  1. lamina at 41 x 41 x 5 nodes on 1 and 2 threads: setup, assembly, solve, total wall time, peak
     resident memory (of the lamina process), assembly rate in Gauss points per second;
  2. time to 1 % and to 0.2 % accuracy: the wall time of the coarsest discretisation of a refinement
     sequence from which every finer member has uz(10, 10, 0.5) within the tolerance of the reference,
     for lamina (Galerkin EFG, the validation case's options, 3-5 node layers) and for CalculiX 2.20
     (ccx, C3D20R structured mesh, graded so element edges fall on the patch boundary), both with the
     same thread count; their ratio (issue 20 targets: at most 0.7 to 1 %, at most 1.0 to 0.2 %);
  3. (--large N ...) lamina at N x N x 5 nodes with box kappa 2.0: assembly, solve and peak memory with
     CHOLMOD and with conjugate gradients preconditioned by hypre BoomerAMG and by PETSc GAMG.

Usage: bench/efg_clamped_plate_vs_calculix.py [--lamina build/lamina] [--threads 2] [--quick]
                                              [--large N ...] [--skip-parts 1,2]
Ends with one `BENCH <name> <value> <unit>` line per figure.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

REFERENCE = -1.03190
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASE = os.path.join(ROOT, "validation", "efg_clamped_plate", "case.yaml")


def run_measured(cmd, env, cwd=None):
    """Runs cmd, returns (wall seconds, peak RSS in MiB of that child, stdout+stderr)."""
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    output = b""
    # read everything, then reap with wait4 to get this child's own resource usage
    output = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        sys.stderr.write(output.decode(errors="replace"))
        raise RuntimeError(f"{cmd[0]} exited with {proc.returncode}")
    return wall, usage.ru_maxrss / 1024.0, output.decode(errors="replace")


def thread_env(threads):
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = str(threads)
    env["OPENBLAS_NUM_THREADS"] = str(threads)
    env["CCX_NPROC_EQUATION_SOLVER"] = str(threads)
    env["CCX_NPROC_STIFFNESS"] = str(threads)
    return env


# ----------------------------------------------------------------------------------------- lamina
def run_lamina(lamina, nodes, threads, workdir, kappa=None, solver=None):
    """kappa: box support factor instead of the case's (3.0); solver: the case's `solver` value (a YAML flow map)."""
    out = os.path.join(workdir, f"lamina_{nodes[0]}x{nodes[1]}x{nodes[2]}_{threads}t_k{kappa}")
    cmd = [lamina, "run", CASE, "-o", out, "--set", f"discretization.nodes=[{nodes[0]}, {nodes[1]}, {nodes[2]}]",
           "--set", "output.vtu=false"]
    if kappa is not None:
        cmd += ["--set", f"efg.support.kappa={kappa}"]
    if solver is not None:
        cmd += ["--set", f"solver={solver}"]
    wall, rss, _ = run_measured(cmd, thread_env(threads))
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    timing = summary["timing"]
    return {
        "wall_s": wall,
        "rss_mib": rss,
        "w": summary["probes"]["w_centre"],
        "setup_s": timing.get("stage_setup_s", 0.0) + timing.get("stage_neighbours_s", 0.0)
        + timing.get("stage_pattern_s", 0.0),
        "assembly_s": timing.get("stage_assembly_s", float("nan")),
        "solve_s": timing.get("stage_solve_total_s", float("nan")),
        "gauss_points_per_s": timing.get("stage_gauss_points_per_second", float("nan")),
        "dofs": summary["counts"]["dofs"],
    }


# --------------------------------------------------------------------------------------- CalculiX
def graded(outer, inner):
    """Element edge coordinates on [0, 10]: `outer` elements on [0, 9.5], `inner` on [9.5, 10]."""
    return [9.5 * i / outer for i in range(outer)] + [9.5 + 0.5 * i / inner for i in range(inner + 1)]


def write_calculix_deck(path, outer, inner, layers):
    xs = graded(outer, inner)
    zs = [i / layers for i in range(layers + 1)]
    n = len(xs) - 1

    def fine(coords):  # corner and mid-edge positions
        out = []
        for a, b in zip(coords[:-1], coords[1:]):
            out += [a, 0.5 * (a + b)]
        return out + [coords[-1]]

    fx, fz = fine(xs), fine(zs)
    ids = {}
    lines = ["*HEADING", "R1a clamped plate quarter model, C3D20R", "*NODE"]
    for k, z in enumerate(fz):
        for j, y in enumerate(fx):
            for i, x in enumerate(fx):
                if (i % 2) + (j % 2) + (k % 2) > 1:
                    continue
                ids[(i, j, k)] = len(ids) + 1
                lines.append(f"{ids[(i, j, k)]}, {x:.12g}, {y:.12g}, {z:.12g}")
    lines.append("*ELEMENT, TYPE=C3D20R, ELSET=PLATE")
    patch = []
    eid = 0
    for ek in range(layers):
        for ej in range(n):
            for ei in range(n):
                eid += 1
                i, j, k = 2 * ei, 2 * ej, 2 * ek
                c = [(i, j, k), (i + 2, j, k), (i + 2, j + 2, k), (i, j + 2, k),
                     (i, j, k + 2), (i + 2, j, k + 2), (i + 2, j + 2, k + 2), (i, j + 2, k + 2)]
                m = [(i + 1, j, k), (i + 2, j + 1, k), (i + 1, j + 2, k), (i, j + 1, k),
                     (i + 1, j, k + 2), (i + 2, j + 1, k + 2), (i + 1, j + 2, k + 2), (i, j + 1, k + 2),
                     (i, j, k + 1), (i + 2, j, k + 1), (i + 2, j + 2, k + 1), (i, j + 2, k + 1)]
                conn = [ids[p] for p in c + m]
                lines.append(f"{eid}, " + ", ".join(str(v) for v in conn[:15]) + ",")
                lines.append(", ".join(str(v) for v in conn[15:]))
                if ek == layers - 1 and xs[ei] >= 9.5 - 1e-9 and xs[ej] >= 9.5 - 1e-9:
                    patch.append(eid)

    def nset(name, predicate):
        members = [ids[key] for key in ids if predicate(fx[key[0]], fx[key[1]], fz[key[2]])]
        lines.append(f"*NSET, NSET={name}")
        for s in range(0, len(members), 12):
            lines.append(", ".join(str(v) for v in members[s:s + 12]))

    nset("CLAMP", lambda x, y, z: x < 1e-9 or y < 1e-9)
    nset("SYMX", lambda x, y, z: x > 10 - 1e-9)
    nset("SYMY", lambda x, y, z: y > 10 - 1e-9)
    nset("PROBE", lambda x, y, z: x > 10 - 1e-9 and y > 10 - 1e-9 and abs(z - 0.5) < 1e-9)
    lines.append("*ELSET, ELSET=PATCH")
    for s in range(0, len(patch), 12):
        lines.append(", ".join(str(v) for v in patch[s:s + 12]))
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", "1.0e4, 0.3",
              "*SOLID SECTION, ELSET=PLATE, MATERIAL=STEEL",
              "*STEP", "*STATIC",
              "*BOUNDARY", "CLAMP, 1, 3", "SYMX, 1, 1", "SYMY, 2, 2",
              "*DLOAD", "PATCH, P2, 400.",
              "*NODE PRINT, NSET=PROBE", "U", "*END STEP"]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return len(ids) * 3


def run_calculix(outer, inner, layers, threads, workdir):
    name = f"r1a_{outer}_{inner}_{layers}"
    dofs = write_calculix_deck(os.path.join(workdir, name + ".inp"), outer, inner, layers)
    wall, rss, _ = run_measured(["ccx", "-i", name], thread_env(threads), cwd=workdir)
    w = None
    with open(os.path.join(workdir, name + ".dat")) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 4:
                try:
                    w = float(parts[3])
                except ValueError:
                    pass
    if w is None:
        raise RuntimeError(f"no displacement in {name}.dat")
    return {"wall_s": wall, "rss_mib": rss, "w": w, "dofs": dofs}


def run_sequence(label, sequence, runner):
    """Runs every member of a refinement sequence (coarse to fine) once; returns [(params, result, error)]."""
    rows = []
    for params in sequence:
        r = runner(params)
        err = abs(r["w"] / REFERENCE - 1.0)
        rows.append((params, r, err))
    return rows


def repeat_short_runs(sequences, rounds=6):
    """Runs every member under one second `rounds` more times and keeps its shortest wall time (the results
    are deterministic). The rounds alternate between the codes' sequences, so both see the same states of a
    shared machine: single sub-second runs vary by 10-30 % here, and with three runs of each code in a row
    the 1 % ratio read 0.65 and 0.88 in two consecutive runs of this script."""
    for _ in range(rounds):
        for rows, runner in sequences:
            for params, r, _ in rows:
                if r["wall_s"] < 1.0:
                    r["wall_s"] = min(r["wall_s"], runner(params)["wall_s"])


def print_sequence(label, rows):
    for params, r, err in rows:
        print(f"  {label} {params}: dofs {r['dofs']}, w = {r['w']:.5f}, error {100 * err:.3f} %, "
              f"wall {r['wall_s']:.2f} s, peak {r['rss_mib']:.0f} MiB", flush=True)


def time_to_accuracy(rows, tolerance):
    """The coarsest member from which every finer member of the sequence is within `tolerance` (a lucky
    crossing of the reference by one coarse member does not count); (result, params) or (None, None)."""
    found = (None, None)
    for params, r, err in reversed(rows):
        if err >= tolerance:
            break
        found = (r, params)
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="21x21x5 instead of 41x41x5 for part 1")
    parser.add_argument("--large", type=int, nargs="*", default=[], metavar="N",
                        help="part 3: N x N x 5 nodes, box kappa 2, with CHOLMOD and with CG (hypre, GAMG)")
    parser.add_argument("--solvers", default="cholmod,cg_hypre,cg_gamg", help="part 3's solvers (comma-separated)")
    parser.add_argument("--skip-parts", default="", help="comma-separated parts not to run (1, 2)")
    args = parser.parse_args()
    skip = {part.strip() for part in args.skip_parts.split(",") if part.strip()}
    if "2" not in skip and shutil.which("ccx") is None:
        sys.exit("ccx not found: apt install calculix-ccx")
    workdir = tempfile.mkdtemp(prefix="lamina_bench_r1a_")
    nodes = (21, 21, 5) if args.quick else (41, 41, 5)
    bench = []

    # the validation case's support (box kappa 3, radius 3.1 h) and the seed's recommended box support (kappa 2.0,
    # radius 2.1 h, the seed's s + delta): the assembly work grows with the square of the
    # number of neighbours per Gauss point (about 200 and 64 in the plate's interior)
    for kappa, suffix in ((None, ""), (2.0, "_kappa2")) if "1" not in skip else ():
        label = "box kappa 3 (validation case)" if kappa is None else f"box kappa {kappa} (seed's recommended support)"
        print(f"1. lamina EFG, R1a at {nodes[0]}x{nodes[1]}x{nodes[2]} nodes, {label}", flush=True)
        for threads in sorted({1, args.threads}):
            r = run_lamina(args.lamina, nodes, threads, workdir, kappa)
            tag = f"efg_r1a_{nodes[0]}x{nodes[1]}x{nodes[2]}{suffix}_{threads}thread"
            bench += report_run(f"{threads} thread(s)", r, tag)
            bench += [(f"{tag}_setup", r["setup_s"], "s"),
                      (f"{tag}_assembly_rate", r["gauss_points_per_s"], "gauss_points/s"),
                      (f"{tag}_assembly_rate_over_200k", r["gauss_points_per_s"] / 2.0e5, "ratio")]

    if "2" not in skip:
        bench += time_to_accuracy_part(args, workdir)
    bench += large_part(args, workdir)
    shutil.rmtree(workdir, ignore_errors=True)
    for name, value, unit in bench:
        print(f"BENCH {name} {value:.6g} {unit}")


def report_run(label, r, tag):
    """Prints one lamina run's figures; returns its BENCH rows (assembly, solve, wall, peak memory, error)."""
    error = 100.0 * (r["w"] / REFERENCE - 1.0)
    print(f"  {label}: dofs {r['dofs']}, setup {r['setup_s']:.2f} s, assembly {r['assembly_s']:.2f} s, "
          f"solve {r['solve_s']:.2f} s, wall {r['wall_s']:.2f} s, peak {r['rss_mib']:.0f} MiB, "
          f"{r['gauss_points_per_s']:.0f} Gauss points/s, w = {r['w']:.5f} ({error:+.3f} %)", flush=True)
    return [(f"{tag}_assembly", r["assembly_s"], "s"), (f"{tag}_solve", r["solve_s"], "s"),
            (f"{tag}_wall", r["wall_s"], "s"), (f"{tag}_peak_memory", r["rss_mib"], "MiB"),
            (f"{tag}_error_percent", error, "%")]


def large_part(args, workdir):
    """Part 3: the largest sizes (box kappa 2.0, the seed's recommended support) with a direct and two
    preconditioned iterative solvers (docs/case_file.md, `solver`)."""
    bench = []
    solvers = (("cholmod", "{type: cholmod}"), ("cg_hypre", "{type: cg, preconditioner: hypre, tolerance: 1e-10}"),
               ("cg_gamg", "{type: cg, preconditioner: gamg, tolerance: 1e-10}"))
    for n in args.large:
        print(f"3. lamina EFG, R1a at {n}x{n}x5 nodes, box kappa 2.0, {args.threads} thread(s)", flush=True)
        for name, solver in solvers:
            if name not in args.solvers.split(","):
                continue
            try:
                r = run_lamina(args.lamina, (n, n, 5), args.threads, workdir, 2.0, solver)
            except RuntimeError as error:
                print(f"  {name}: failed ({error})", flush=True)
                continue
            tag = f"efg_r1a_{n}x{n}x5_kappa2_{name}_{args.threads}thread"
            bench += report_run(name, r, tag) + [(f"{tag}_dofs", r["dofs"], "dofs")]
            shutil.rmtree(os.path.join(workdir, f"lamina_{n}x{n}x5_{args.threads}t_k2.0"), ignore_errors=True)
    return bench


def time_to_accuracy_part(args, workdir):
    """Part 2: time to 1 % and 0.2 % for lamina and CalculiX."""
    bench = []
    print(f"2. time to 1 % and to 0.2 % accuracy on {args.threads} thread(s) (reference {REFERENCE})", flush=True)
    # refinement sequences, coarse to fine (dofs increasing), each an in-plane refinement at a through-thickness
    # resolution that is not the limit: lamina 4 node layers (3 layers stop at -1.2 %: 11 x 11 x 3 -1.23 %,
    # 13 x 13 x 3 -1.16 %), then 5; CalculiX 2 C3D20R layers (1 layer stops at -1.8 %: 8 x 2 x 1), then 3
    lamina_sequence = [(5, 5, 4), (6, 6, 4), (7, 7, 4), (9, 9, 4), (11, 11, 4), (16, 16, 4), (21, 21, 4), (21, 21, 5),
                       (31, 31, 5), (41, 41, 5)]
    ccx_sequence = [(2, 1, 2), (4, 1, 2), (6, 1, 2), (8, 1, 2), (8, 2, 2), (12, 2, 2), (16, 3, 3), (24, 4, 3)]
    lamina_runner = lambda p: run_lamina(args.lamina, p, args.threads, workdir)
    ccx_runner = lambda p: run_calculix(p[0], p[1], p[2], args.threads, workdir)
    lamina_rows = run_sequence("lamina", lamina_sequence, lamina_runner)
    ccx_rows = run_sequence("ccx", ccx_sequence, ccx_runner)
    repeat_short_runs([(lamina_rows, lamina_runner), (ccx_rows, ccx_runner)])
    print_sequence("lamina", lamina_rows)
    print_sequence("ccx", ccx_rows)
    for tolerance, tag in ((0.01, "1pct"), (0.002, "0p2pct")):
        lam, _ = time_to_accuracy(lamina_rows, tolerance)
        ccx, _ = time_to_accuracy(ccx_rows, tolerance)
        if lam is None or ccx is None:
            print(f"  a sequence did not stay within {100 * tolerance:g} % (see above)")
            continue
        print(f"  {100 * tolerance:g} %: lamina {lam['wall_s']:.3f} s ({lam['dofs']} dofs), CalculiX {ccx['wall_s']:.3f} s "
              f"({ccx['dofs']} dofs), ratio {lam['wall_s'] / ccx['wall_s']:.2f}", flush=True)
        bench += [(f"efg_r1a_time_to_{tag}_lamina", lam["wall_s"], "s"),
                  (f"efg_r1a_time_to_{tag}_calculix", ccx["wall_s"], "s"),
                  (f"efg_r1a_time_to_{tag}_ratio_lamina_over_calculix", lam["wall_s"] / ccx["wall_s"], "ratio"),
                  (f"efg_r1a_dofs_to_{tag}_lamina", lam["dofs"], "dofs"),
                  (f"efg_r1a_dofs_to_{tag}_calculix", ccx["dofs"], "dofs")]
    return bench


if __name__ == "__main__":
    main()
