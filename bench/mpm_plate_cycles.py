#!/usr/bin/python3
"""MPM element-cycle benchmark: a 100 x 100-element Belytschko-Tsay shell plate (CPDI2 domains) in
explicit dynamics, 200 steps at a fixed time step, on 1 and 2 threads, with the default shell element
(physical stabilisation; `--springs`: the seed's coefficient springs, the element measured before 2026-12-07).

Figure: element-cycles per second = elements x steps / (sum of the step's stage times: element
stresses and forces, P2G, grid update, G2P, gather, position update and grid re-binning, loads);
the time per stage is printed too. Set-up (mesh, grid, masses) is not included.

Usage: bench/mpm_plate_cycles.py [--lamina build/lamina] [--elements 100] [--steps 200] [--threads 1 2] [--springs]
Ends with one `BENCH <name> <value> <unit>` line per figure.
"""
import argparse
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def plate_case(elements_x, elements_y, steps, dt, springs=False):
    """The benchmark plate: elements_x x elements_y Belytschko-Tsay elements of 0.01 x 0.01 x 0.01, clamped
    at x = 0, a linear initial velocity, `steps` explicit steps of dt. The default shell element (physical
    stabilisation); springs=True: the seed's coefficient springs (shell.hourglass 0.1) instead."""
    hourglass = ", hourglass: 0.1" if springs else ""
    return f"""title: MPM plate for the element-cycle benchmarks
method: mpm
materials: [{{name: p, model: linear_elastic, E: 1.0e6, nu: 0.3, density: 1.0}}]
geometry: {{type: plate, min: [0, 0], max: [{elements_x / 100}, {elements_y / 100}], thickness: 0.01}}
discretization: {{elements: [{elements_x}, {elements_y}]}}
boundary: [{{select: {{set: xmin}}, fix: [x, y, z, rx, ry, rz]}}]
loads: [{{select: all, initial_velocity: [0, 0, "0.1*x"]}}]
shell: {{thickness_points: 3{hourglass}}}
mpm: {{analysis: dynamic, end_time: {steps * dt}, output_points: 1, time_step: {{fixed: {dt}}}}}
output: {{vtu: false}}
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--elements", type=int, default=100)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--springs", action="store_true",
                        help="the seed's coefficient springs (shell.hourglass: 0.1) instead of the default element")
    args = parser.parse_args()
    dt = 1.0e-6  # below the shell's stable step for 0.01 x 0.01 x 0.01 elements, E = 1e6, rho = 1
    workdir = tempfile.mkdtemp(prefix="lamina_bench_mpm_")
    case = os.path.join(workdir, "plate.yaml")
    with open(case, "w") as f:
        f.write(plate_case(args.elements, args.elements, args.steps, dt, args.springs))
    elements = args.elements ** 2
    bench = []
    for threads in args.threads:
        out = os.path.join(workdir, f"out_{threads}")
        subprocess.run([args.lamina, "run", case, "-o", out, "--quiet"], check=True,
                       env=dict(os.environ, OMP_NUM_THREADS=str(threads)))
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        timing = summary["timing"]
        stages = {k[len("stage_"):-2]: v for k, v in timing.items() if k.startswith("stage_") and k.endswith("_s")}
        loop = sum(stages.values())
        steps = summary["counts"]["steps"]
        rate = elements * steps / loop
        print(f"{threads} thread(s): {steps} steps, loop {loop:.3f} s, {rate:.3g} element-cycles/s; per stage: "
              + ", ".join(f"{k} {v:.3f} s" for k, v in sorted(stages.items())), flush=True)
        bench.append((f"mpm_element_cycles_per_s_{threads}thread", rate, "element_cycles/s"))
        for k, v in sorted(stages.items()):
            bench.append((f"mpm_stage_{k}_{threads}thread", v / steps * 1e3, "ms/step"))
    for name, value, unit in bench:
        print(f"BENCH {name} {value:.6g} {unit}")


if __name__ == "__main__":
    main()
