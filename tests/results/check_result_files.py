#!/usr/bin/python3
"""Result-file contract test (PRODUCT.md section 2): runs lamina on an example and checks
summary.json, history.csv, result.pvd and every VTU frame, which must open in VTK (Debian's
python3-vtk9) with the right point count and fields. Also checks that an invalid run never
touches an existing result set, and that --set overrides reach the run.
usage: check_result_files.py LAMINA SOURCE_DIR WORK_DIR"""
import csv
import json
import os
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import vtk
from vtk.util.numpy_support import vtk_to_numpy

lamina, source, work = sys.argv[1], sys.argv[2], sys.argv[3]
failures = []


def check(condition, message):
    print(("PASS " if condition else "FAIL ") + message)
    if not condition:
        failures.append(message)


shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
case = os.path.join(source, "examples", "mls_fit_sine.yaml")
out = os.path.join(work, "run")
run = subprocess.run([lamina, "run", case, "-o", out, "--quiet", "--set", "discretization.nodes=[8,7,6]"],
                     capture_output=True, text=True)
check(run.returncode == 0, f"lamina run exits 0 (got {run.returncode}: {run.stderr.strip()[:200]})")
nodes = 8 * 7 * 6

summary = json.load(open(os.path.join(out, "summary.json")))
for key in ("case", "method", "status", "probes", "counts", "timing", "lamina_version"):
    check(key in summary, f"summary.json has '{key}'")
check(summary["status"] == "ok", "summary status is ok")
check(summary["counts"]["nodes"] == nodes, f"--set discretization.nodes reached the run ({summary['counts']['nodes']} nodes)")
for probe in ("u_centre", "dudx_centre", "errU", "errDU", "errDDU"):
    check(probe in summary["probes"], f"summary probes has {probe}")

with open(os.path.join(out, "history.csv")) as handle:
    rows = list(csv.reader(handle))
check(rows[0][:3] == ["step", "time", "load_factor"], "history.csv starts with step,time,load_factor")
check("u_centre" in rows[0] and "errU" in rows[0], "history.csv has one column per probe")
check(len(rows) >= 2, "history.csv has at least one row")
last = dict(zip(rows[0], rows[-1]))
check(abs(float(last["errU"]) - summary["probes"]["errU"]) <= 1e-9 * max(1.0, abs(summary["probes"]["errU"])),
      "history.csv last row matches summary.json")

pvd = ElementTree.parse(os.path.join(out, "result.pvd")).getroot()
datasets = pvd.findall(".//DataSet")
check(len(datasets) >= 1, f"result.pvd lists {len(datasets)} frame(s)")
for dataset in datasets:
    path = os.path.join(out, dataset.get("file"))
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    check(grid.GetNumberOfPoints() == nodes, f"{dataset.get('file')} opens in VTK with {grid.GetNumberOfPoints()} points")
    check(grid.GetNumberOfCells() == nodes, f"{dataset.get('file')} has one vertex cell per node")
    data = grid.GetPointData()
    names = [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]
    for field in ("field_mls", "field_exact", "gradient_mls", "volume"):
        check(field in names, f"VTU has point field {field}")
    volume = vtk_to_numpy(data.GetArray("volume")).sum()
    check(abs(volume - 8.0) < 1e-10 * 8.0, f"VTU node volumes sum to the body volume ({volume})")
    gradient = data.GetArray("gradient_mls")
    check(gradient is not None and gradient.GetNumberOfComponents() == 3, "gradient_mls has 3 components")

check(os.path.exists(os.path.join(out, "log.txt")) and "resolved case" in open(os.path.join(out, "log.txt")).read(),
      "log.txt holds the resolved case")

# An invalid run must not touch the existing result set.
before = sorted(os.listdir(out))
stamp = os.path.getmtime(os.path.join(out, "summary.json"))
bad = subprocess.run([lamina, "run", case, "-o", out, "--quiet", "--set", "mls_fit.basis=cubic"],
                     capture_output=True, text=True)
check(bad.returncode == 2, f"invalid --set value exits 2 (got {bad.returncode})")
check("mls_fit.basis" in bad.stderr, "the message names the key path")
check(sorted(os.listdir(out)) == before and os.path.getmtime(os.path.join(out, "summary.json")) == stamp,
      "an invalid run leaves the previous result set untouched")
check(not any(name.startswith("run.partial") for name in os.listdir(work)), "no staging folder is left behind")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
