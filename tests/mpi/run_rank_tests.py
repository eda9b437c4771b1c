#!/usr/bin/env python3
"""Distributed runs (docs/scaling.md): each case of this folder on 1, 2 and 3 MPI ranks (lamina run
--ranks N, which starts mpirun), full and lean bond storage. Passes when
  - every history column on N ranks equals the one-process column within 1e-10 relative (to the
    column's largest magnitude), the counts in summary.json are equal;
  - each VTU frame is a .pvtu of N pieces whose points add up to the body's nodes;
  - the mpm runs (element decomposition) and the pd ADR runs (the seed's plate on the plate model, a 3D
    bar lattice; forces split; a one-layer plate, forces replicated) are those of one process, bit for bit;
  - a pd explicit, a pd ADR and an mpm run on 2 ranks restarted from a checkpoint repeat the uninterrupted
    history bit for bit;
  - the pd plate model under explicit dynamics (forces split) is that of one process, bit for bit;
  - computations every rank repeats (efg collocation and Lagrange multipliers, mls_fit) are those of one
    process, bit for bit; a solve that runs on one process only (solver: cholmod) exits 2 on 2 ranks;
  - pd buckling on 2 and 3 ranks (SLEPc) gives the one-process (Spectra) load factors within 1e-8;
  - efg (symmetric, and unsymmetric with vci), mpfem (linear and large deformation) and pd linear static
    solved through PETSc on 2 and 3 ranks (MUMPS, CG with GAMG) give the one-process probes within 1e-9
    (MUMPS) / 1e-6 (CG).
Usage: run_rank_tests.py LAMINA CASE_DIR WORK_DIR"""
import csv
import json
import os
import re
import shutil
import subprocess
import sys

lamina, case_dir, work = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
TOLERANCE = 1e-10
failures = []


def run(case, ranks, out, extra=()):
    command = [lamina, "run", case, "-o", out, "--quiet", "--threads", "1"] + list(extra)
    if ranks > 1:
        command += ["--ranks", str(ranks)]
    return subprocess.run(command, capture_output=True, text=True, timeout=600)


def history(folder):
    with open(os.path.join(folder, "history.csv")) as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(x) for x in r] for r in rows[1:]]


def largest_difference(differences):
    """The largest of (name, relative difference) pairs: (difference, name); (0, '') for none."""
    worst, where = 0.0, ""
    for name, d in differences:
        if d > worst:
            worst, where = d, name
    return worst, where


def check_pieces(folder, ranks, nodes, label):
    with open(os.path.join(folder, "result.pvd")) as f:
        frames = re.findall(r'file="([^"]+)"', f.read())
    if not frames:
        failures.append(f"{label}: no frames in result.pvd")
        return
    for frame in frames:
        if not frame.endswith(".pvtu"):
            failures.append(f"{label}: {frame} is not a .pvtu")
            return
        with open(os.path.join(folder, frame)) as f:
            pieces = re.findall(r'Source="([^"]+)"', f.read())
        if len(pieces) != ranks:
            failures.append(f"{label}: {frame} has {len(pieces)} pieces, expected {ranks}")
        points = 0
        for piece in pieces:
            with open(os.path.join(folder, piece)) as f:
                points += int(re.search(r'NumberOfPoints="(\d+)"', f.read(4096)).group(1))
        if points != nodes:
            failures.append(f"{label}: {frame} pieces hold {points} points, the body {nodes}")


source = os.path.dirname(os.path.dirname(os.path.abspath(case_dir)))
pd_variants = {"full": [], "lean": ["--set", "pd.bond_storage=lean", "--set", "pd.explicit.time_step=0.004"]}
# mpm (element decomposition): this folder's dynamic plate and the Sze cantilever / hemisphere
# (quasi-static, mass scaling), on fewer load levels than their validation runs
history_cases = [(os.path.join(case_dir, name), pd_variants if name.startswith(("block", "bar")) else {"default": []})
                 for name in sorted(os.listdir(case_dir)) if name.endswith(".yaml")]
history_cases += [(os.path.join(source, "validation/mpm_cantilever_shear/case.yaml"),
                   {"3_levels": ["--set", "mpm.load_levels=3"]}),
                  (os.path.join(source, "validation/mpm_hemisphere/case.yaml"),
                   {"2_levels": ["--set", "mpm.load_levels=2", "--set", "output.vtu=false"]}),
                  (os.path.join(source, "validation/pd_plate_tension/case.yaml"),
                   {"adr": [], "explicit": ["--set", "pd.analysis=explicit", "--set", "pd.explicit.end_time=2e-5",
                                            "--set", "pd.explicit.outputs=4"]}),
                  (os.path.join(source, "validation/pd_bar_tension/case.yaml"), {"adr": []}),
                  # the one-layer plate (Kirchhoff plate model: forces computed whole on every rank)
                  (os.path.join(source, "validation/pd_plate_one_layer_bending/case.yaml"),
                   {"adr": ["--set", "pd.analysis=quasi_static", "--set", "pd.quasi_static={increments: 1, tolerance: 1e-7}",
                            "--set", "output.vtu=false"],
                    # clamped: held rotations (a penalty on the fitted slopes)
                    "adr_clamped": ["--set", "pd.analysis=quasi_static", "--set", "boundary.0.fix=[x,y,z,rx,ry]",
                                    "--set", "pd.quasi_static={increments: 1, tolerance: 1e-7}", "--set", "output.vtu=false"]})]
for case, variants in history_cases:
    name = os.path.basename(case) if os.path.dirname(case) == case_dir else case.split("/")[-2]
    for variant, extra in variants.items():
        label0 = f"{name}/{variant}"
        one = os.path.join(work, f"{name}_{variant}_1")
        r = run(case, 1, one, extra)
        if r.returncode != 0:
            failures.append(f"{label0} on 1 rank: exit {r.returncode}: {r.stderr.strip()}")
            continue
        columns, reference = history(one)
        with open(os.path.join(one, "summary.json")) as f:
            counts = json.load(f)["counts"]
        for ranks in (2, 3):
            label = f"{label0} on {ranks} ranks"
            out = os.path.join(work, f"{name}_{variant}_{ranks}")
            r = run(case, ranks, out, extra)
            if r.returncode != 0:
                failures.append(f"{label}: exit {r.returncode}: {r.stderr.strip()}")
                continue
            cols, rows = history(out)
            with open(os.path.join(out, "summary.json")) as f:
                summary = json.load(f)
            if cols != columns or len(rows) != len(reference):
                failures.append(f"{label}: history has {len(rows)} rows / columns {cols}, one process {len(reference)} / {columns}")
                continue
            if summary["counts"] != counts or summary.get("ranks") != ranks:
                failures.append(f"{label}: counts {summary['counts']} ranks {summary.get('ranks')}, one process {counts}")
            scales = [max(max(abs(row[c]) for row in reference), 1e-300) for c in range(len(columns))]
            worst, where = largest_difference((column, abs(a[c] - b[c]) / scales[c]) for c, column in enumerate(columns)
                                              for a, b in zip(reference, rows))
            print(f"{label}: largest relative difference to one process {worst:.2e} ({where or '-'})")
            if worst > TOLERANCE:
                failures.append(f"{label}: {where} differs from one process by {worst:.2e} (tolerance {TOLERANCE:g})")
            if os.path.exists(os.path.join(out, "result.pvd")):
                check_pieces(out, ranks, counts["nodes"], label)

# checkpoint / restart on 2 ranks: a run with checkpoints, its newest checkpoint removed, --restart from
# the older one: the history of the uninterrupted run, bit for bit, frames (.pvtu and pieces) kept
restart_cases = [(os.path.join(case_dir, "block_initial_velocity.yaml"), ["--set", "output.checkpoint.every=3"]),
                 (os.path.join(case_dir, "mpm_plate_dynamic.yaml"), ["--set", "output.checkpoint.every=3"]),
                 (os.path.join(source, "validation/pd_plate_tension/case.yaml"),  # ADR, force decomposition
                  ["--set", "output.checkpoint.every=1", "--set", "pd.quasi_static.increments=4"])]
for case, extra in restart_cases:
    name = os.path.basename(case) if os.path.dirname(case) == case_dir else case.split("/")[-2]
    label = f"{name} restart on 2 ranks"
    full = os.path.join(work, name + "_checkpointed")
    r = run(case, 2, full, extra)
    checkpoints = sorted(f for f in os.listdir(full) if f.startswith("checkpoint_")) if r.returncode == 0 else []
    if len(checkpoints) < 2:
        failures.append(f"{label}: exit {r.returncode}, checkpoints {checkpoints}: {r.stderr.strip()}")
        continue
    part = os.path.join(work, name + "_restarted")
    shutil.copytree(full, part)
    os.remove(os.path.join(part, checkpoints[-1]))
    r = run(case, 2, part, extra + ["--restart", part])
    if r.returncode != 0:
        failures.append(f"{label}: exit {r.returncode}: {r.stderr.strip()}")
        continue
    same = open(os.path.join(full, "history.csv")).read() == open(os.path.join(part, "history.csv")).read()
    frames = sorted(f for f in os.listdir(part) if f.startswith("frame_")) == sorted(f for f in os.listdir(full) if f.startswith("frame_"))
    print(f"{label}: history {'identical' if same else 'DIFFERENT'}, frames {'complete' if frames else 'MISSING'}")
    if not same or not frames:
        failures.append(f"{label}: the restarted run differs (history identical: {same}, frames complete: {frames})")

# what runs on one process only (an explicit solver: cholmod): exit 2 with the reason, no output folder
for case in ("validation/efg_bar_clamped/case.yaml",):
    out = os.path.join(work, "refused_" + case.split("/")[1])
    refused = run(os.path.join(source, case), 2, out, ["--set", "solver.type=cholmod"])
    if refused.returncode != 2 or "one process" not in refused.stderr:
        failures.append(f"{case} on 2 ranks: exit {refused.returncode}, stderr {refused.stderr.strip()!r}; expected exit 2 "
                        "naming one process")
    elif os.path.exists(out):
        failures.append(f"{case} on 2 ranks: an output folder was written")
    else:
        print(f"{case} on 2 ranks: exit 2:", refused.stderr.strip().splitlines()[-1])

# computations every rank repeats whole (replicated: efg strong forms and Lagrange multipliers, mls_fit):
# the one-process result, bit for bit
replicated_cases = [("validation/efg_bar_clamped/case.yaml", ["--set", "efg.formulation=collocation"]),
                    ("validation/efg_bar_clamped/case.yaml", ["--set", "efg.essential_bc=lagrange"]),
                    ("validation/mls_fit_quadratic/case.yaml", [])]
for k, (case, extra) in enumerate(replicated_cases):
    label = f"{case} {' '.join(extra[1::2])} on 2 ranks (replicated)"
    one, two = os.path.join(work, f"replicated_{k}_1"), os.path.join(work, f"replicated_{k}_2")
    r1, r2 = run(os.path.join(source, case), 1, one, extra), run(os.path.join(source, case), 2, two, extra)
    if r1.returncode != 0 or r2.returncode != 0:
        failures.append(f"{label}: exit {r1.returncode} / {r2.returncode}: {r1.stderr.strip()} {r2.stderr.strip()}")
        continue
    same = open(os.path.join(one, "history.csv")).read() == open(os.path.join(two, "history.csv")).read()
    print(f"{label}: history {'identical' if same else 'DIFFERENT'}")
    if not same:
        failures.append(f"{label}: the history differs from one process")

# static methods through PETSc (solver: mumps, the default on several ranks, or cg): the probes of the
# one-process CHOLMOD run within the solver's accuracy
static_cases = [("validation/efg_clamped_plate/case.yaml", []), ("validation/efg_bar_clamped/case.yaml", []),
                ("validation/mpfem_cantilever/case.yaml", []),
                ("validation/mpfem_cook_hyperelastic/case.yaml", ["--set", "mpfem.large_deformation.increments=4"]),
                ("validation/pd_plate_tension/case.yaml", ["--set", "pd.analysis=linear_static"])]
for case, extra in static_cases:
    name = case.split("/")[1]
    one = os.path.join(work, name + "_cholmod")
    r = run(os.path.join(source, case), 1, one, extra)
    if r.returncode != 0:
        failures.append(f"{case} on 1 rank: exit {r.returncode}: {r.stderr.strip()}")
        continue
    with open(os.path.join(one, "summary.json")) as f:
        reference = json.load(f)["probes"]
    for ranks, solver, tolerance in ((2, "mumps", 1e-9), (2, "cg", 1e-6), (3, "mumps", 1e-9)):
        if solver == "cg" and ("hyperelastic" in name or "bar_clamped" in name):
            continue  # a Newton tangent away from equilibrium may be indefinite; efg with vci: unsymmetric (MUMPS LU)
        out = os.path.join(work, f"{name}_{solver}_{ranks}")
        r = run(os.path.join(source, case), ranks, out, extra + ["--set", f"solver.type={solver}"])
        label = f"{case} on {ranks} ranks ({solver})"
        if r.returncode != 0:
            failures.append(f"{label}: exit {r.returncode}: {r.stderr.strip()}")
            continue
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        probes = summary["probes"]
        scale = max(abs(v) for v in reference.values())
        worst, where = largest_difference((key, abs(probes[key] - value) / max(abs(value), 1e-12 * scale))
                                          for key, value in reference.items())
        print(f"{label}: largest relative probe difference to CHOLMOD {worst:.2e} ({where})")
        if worst > tolerance:
            failures.append(f"{label}: {where} differs from CHOLMOD by {worst:.2e} (tolerance {tolerance:g})")
        if os.path.exists(os.path.join(out, "result.pvd")):
            check_pieces(out, ranks, summary["counts"]["nodes"], label)

# pd buckling on several ranks: SLEPc Krylov-Schur (MUMPS Cholesky of K0) against Spectra / CHOLMOD on one
# process; the eigen solvers' tolerance is 1e-10 on the residual, so the load factors agree to about 1e-9
case = "validation/pd_plate_buckling_linear/case.yaml"
one = os.path.join(work, "buckling_1")
r = run(os.path.join(source, case), 1, one)
if r.returncode != 0:
    failures.append(f"{case} on 1 rank: exit {r.returncode}: {r.stderr.strip()}")
else:
    with open(os.path.join(one, "summary.json")) as f:
        reference = json.load(f)["probes"]
    for ranks in (2, 3):
        out = os.path.join(work, f"buckling_{ranks}")
        r = run(os.path.join(source, case), ranks, out)
        label = f"{case} on {ranks} ranks (SLEPc)"
        if r.returncode != 0:
            failures.append(f"{label}: exit {r.returncode}: {r.stderr.strip()}")
            continue
        with open(os.path.join(out, "summary.json")) as f:
            probes = json.load(f)["probes"]
        worst, where = largest_difference((key, abs(probes[key] - value) / max(abs(value), 1e-300))
                                          for key, value in reference.items())
        print(f"{label}: largest relative probe difference to Spectra {worst:.2e} ({where})")
        if worst > 1e-8:
            failures.append(f"{label}: {where} differs from Spectra by {worst:.2e} (tolerance 1e-8)")

for f in failures:
    print("FAIL", f)
sys.exit(1 if failures else 0)
