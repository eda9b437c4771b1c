#!/usr/bin/env python3
"""Parameter study from Python: the MPFEM Timoshenko cantilever on four particle grids.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/parameter_study.py [OUTDIR]

Loads examples/mpfem_cantilever.yaml as a dict, runs it on 9 x 3 ... 65 x 17 particles, and plots the
tip-deflection error against the exact 0.0089 (Timoshenko & Goodier; L = 48, D = 12, P = 1000) on
log-log axes (OUTDIR/parameter_study.png, default out/parameter_study). It doubles as a test (CTest
python_example): it exits 1 unless the error falls at every refinement and is below 1 % on the finest grid.
"""
import copy
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import lamina

here = Path(__file__).resolve().parent
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out") / "parameter_study"
exact = 0.0089  # tip deflection of the Timoshenko beam (the example's header)

base = lamina.load(here.parent / "mpfem_cantilever.yaml")
base["output"] = {"vtu": False}
grids = [[9, 3], [17, 5], [33, 9], [65, 17]]
rows = []
for nx, ny in grids:
    case = copy.deepcopy(base)
    case["discretization"]["particles"] = [nx, ny]
    result = lamina.run(case, threads=1, output=out / f"particles_{nx}x{ny}")
    w = result.probes["tip_deflection"]
    rows.append((nx * ny, 48.0 / (nx - 1), w, abs(w - exact) / exact))
    print(f"{nx:3d} x {ny:2d} particles: tip deflection {w:.6g}, error {100 * rows[-1][3]:.3f} %")

spacing = [r[1] for r in rows]
error = [r[3] for r in rows]
figure, axes = plt.subplots(figsize=(5, 4))
axes.loglog(spacing, error, "o-", label="lamina mpfem")
axes.loglog(spacing, [error[0] * (h / spacing[0]) ** 2 for h in spacing], "k--", lw=0.8, label="slope 2")
axes.set_xlabel("particle spacing along the beam")
axes.set_ylabel("|w_tip - w_exact| / w_exact")
axes.set_title("Timoshenko cantilever, MPFEM")
axes.grid(True, which="both", lw=0.3)
axes.legend()
figure.tight_layout()
out.mkdir(parents=True, exist_ok=True)
figure.savefig(out / "parameter_study.png", dpi=120)
print(f"plot: {out / 'parameter_study.png'}")

ok = all(b < a for a, b in zip(error, error[1:])) and error[-1] < 0.01
print("PASS" if ok else "FAIL: the error must fall at every refinement and end below 1 %")
sys.exit(0 if ok else 1)
