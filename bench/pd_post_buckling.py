#!/usr/bin/python3
"""PD post-buckling benchmark (issue 4, criterion 6b): the full load path of the seed's plate lattice
(validation/pd_plate_post_buckling: 300 x 200 x 2 mm, 10 x 10 x 1 mm cells, 2 layers, 45 increments to
45 kN by adaptive dynamic relaxation, imperfection from the linear buckling mode) on 2 threads
(and any other thread counts asked for).

Figures per thread count: wall time of the whole run (set-up, buckling-mode imperfection, every
increment and output), the total ADR iteration count (failed attempts included) and the time per
iteration; the targets: the whole path in under 60 s on 2 threads (issue 4), under 30 s (issue 15).

Usage: bench/pd_post_buckling.py [--lamina build/lamina] [--threads 2] [--increments 45]
Ends with one `BENCH <name> <value> <unit>` line per figure.
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lamina", default=os.path.join(ROOT, "build", "lamina"))
    parser.add_argument("--threads", type=int, nargs="+", default=[2])
    parser.add_argument("--increments", type=int, default=45)
    args = parser.parse_args()
    case = os.path.join(ROOT, "validation", "pd_plate_post_buckling", "case.yaml")
    lines = []
    for threads in args.threads:
        out = tempfile.mkdtemp(prefix=f"lamina_bench_pd_post_buckling_{threads}_")
        start = time.perf_counter()
        subprocess.run([args.lamina, "run", case, "-o", out, "--quiet", "--threads", str(threads),
                        "--set", f"pd.quasi_static.increments={args.increments}", "--set", "output.vtu=false"],
                       check=True)
        wall = time.perf_counter() - start
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        probes = summary["probes"]
        iterations = probes["total_iterations"]
        print(f"threads {threads}: wall {wall:.1f} s, {iterations:.0f} ADR iterations, "
              f"{1e3 * wall / max(iterations, 1):.3f} ms per iteration; events at "
              + ", ".join(f"{probes.get(f'stiffness_change_{k}_load', 0) / 1e3:.2f} kN" for k in (1, 2, 3))
              + f"; linear buckling {probes.get('linear_buckling_load', 0) / 1e3:.2f} kN")
        lines.append(f"BENCH pd_post_buckling_wall_{threads}t {wall:.2f} s")
        lines.append(f"BENCH pd_post_buckling_iterations_{threads}t {iterations:.0f} iterations")
        lines.append(f"BENCH pd_post_buckling_time_per_iteration_{threads}t {1e3 * wall / max(iterations, 1):.4f} ms")
        lines.append(f"BENCH pd_post_buckling_wall_vs_60s_{threads}t {wall / 60.0:.3f} ratio")
        lines.append(f"BENCH pd_post_buckling_wall_vs_30s_{threads}t {wall / 30.0:.3f} ratio")  # issue 15 target
    for line in lines:
        print(line)


if __name__ == "__main__":
    main()
