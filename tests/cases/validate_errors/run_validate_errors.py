#!/usr/bin/python3
"""`lamina validate` on malformed validation cases: each folder here must give exit 2 with its
file:line message before anything runs, and write no output folder.
Usage: LAMINA=build/lamina run_validate_errors.py tests/cases/validate_errors"""
import os
import shutil
import subprocess
import sys
import tempfile

EXPECTED = {"malformed_reference": "reference.csv:3: expected 2 cells, found 3"}


def main():
    lamina = os.environ.get("LAMINA", "lamina")
    root = sys.argv[1]
    failures = 0
    for name, message in EXPECTED.items():
        out = tempfile.mkdtemp(prefix="lamina_validate_errors_")
        shutil.rmtree(out)
        r = subprocess.run([lamina, "validate", name, "--dir", root, "-o", out], capture_output=True, text=True, timeout=120)
        ok = r.returncode == 2 and message in r.stderr and not os.path.exists(out)
        print(f"{'PASS' if ok else 'FAIL'} {name}: exit {r.returncode}, stderr {r.stderr.strip()[-200:]!r}")
        failures += not ok
        shutil.rmtree(out, ignore_errors=True)
    print(f"{len(EXPECTED)} cases, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
