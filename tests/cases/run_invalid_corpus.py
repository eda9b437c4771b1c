#!/usr/bin/env python3
"""Run lamina on the corpus of malformed case files and check that each one is rejected.

Usage:
    LAMINA=/path/to/lamina run_invalid_corpus.py DIR [FILE ...]

Every DIR/*.yaml (or just the FILEs given) starts with comment lines stating the expectation:

    # expect-line: 7                     a stderr line contains "<file name>:7:" (file:LINE:COLUMN)
    # expect: materials.0.nu             substring that must appear in stderr (any number of these)
    # expect-min-errors: 3               at least 3 "error:" lines (one line per problem)
    # expect-max-errors: 1               at most 1 "error:" line (no follow-on errors)
    # args: --set mls_fit.basis=cubic    extra command-line arguments (shell-style quoting)

Other comment lines are free text. For each file the runner executes

    $LAMINA run FILE -o TMP/out --quiet ARGS      and      $LAMINA check FILE ARGS

(in an empty temporary working directory) and requires, for both commands: exit code 2 (1 is an
internal error, a signal is a crash), no "internal error" on stderr, at least one "error:" line,
every expectation met, nothing written into the working directory (no output folder, no staging
folder), and a run time under 10 s. It prints one PASS/FAIL line per file, a summary, and exits
non-zero if any file fails or if the corpus has fewer than 40 files.
"""

import os
import re
import resource
import shlex
import signal
import subprocess
import sys
import tempfile
import time

TIMEOUT_S = 10.0
MIN_FILES = 40
# Address-space limit of each lamina process (a runaway allocation fails fast). Override in bytes
# with LAMINA_CORPUS_MEMORY_LIMIT; 0 = none (an AddressSanitizer build reserves terabytes of
# address space for its shadow memory and cannot start under the limit; scripts/sanitize.sh
# caps single allocations with ASAN_OPTIONS=max_allocation_size_mb instead).
MEMORY_LIMIT = int(os.environ.get("LAMINA_CORPUS_MEMORY_LIMIT", 4 << 30))


def parse_header(path):
    """The expectations in the leading comment block of a corpus file."""
    spec = {"line": None, "expect": [], "args": [], "min_errors": 1, "max_errors": None}
    with open(path, "rb") as f:
        raw = f.read()
    for line in raw.decode("utf-8", errors="replace").splitlines():
        if not line.startswith("#"):
            break
        m = re.match(r"#\s*([a-z-]+)\s*:\s?(.*)$", line)
        if not m:
            continue
        key, value = m.group(1), m.group(2).rstrip()
        if key == "expect-line":
            spec["line"] = int(value)
        elif key == "expect":
            spec["expect"].append(value)
        elif key == "args":
            spec["args"] += shlex.split(value)
        elif key == "expect-min-errors":
            spec["min_errors"] = int(value)
        elif key == "expect-max-errors":
            spec["max_errors"] = int(value)
    return spec


def limit_resources():
    if MEMORY_LIMIT > 0:
        try:
            resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
        except (ValueError, OSError):
            pass
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))


def run_lamina(lamina, argv, cwd):
    """(exit code or None on timeout, stderr text, seconds)."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    start = time.monotonic()
    proc = subprocess.Popen([lamina] + argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=env, preexec_fn=limit_resources, start_new_session=True)
    try:
        _, err = proc.communicate(timeout=TIMEOUT_S)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        _, err = proc.communicate()
        code = None
    return code, err.decode("utf-8", errors="replace"), time.monotonic() - start


def describe_exit(code):
    if code is None:
        return f"timed out after {TIMEOUT_S:.0f} s"
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = str(-code)
        return f"crashed (signal {name})"
    if code == 1:
        return "internal error (exit 1)"
    if code == 0:
        return "accepted the case (exit 0)"
    if code == 3:
        return "ran and failed the analysis (exit 3) instead of rejecting the input"
    return f"exit {code}"


def check_output(spec, name, code, err):
    """Problems with one command's result (empty list = as expected)."""
    problems = []
    if code != 2:
        problems.append(describe_exit(code))
        if code is None or code < 0:
            return problems
    if code is not None and code > 128:
        problems.append(f"crashed (exit {code})")
    if "internal error" in err:
        problems.append("stderr reports an internal error")
    error_lines = [l for l in err.splitlines() if l.startswith("error:")]
    if len(error_lines) < spec["min_errors"]:
        problems.append(f"{len(error_lines)} 'error:' line(s), expected at least {spec['min_errors']}")
    if spec["max_errors"] is not None and len(error_lines) > spec["max_errors"]:
        problems.append(f"{len(error_lines)} 'error:' lines, expected at most {spec['max_errors']} (follow-on errors)")
    if spec["line"] is not None:
        pattern = re.compile(re.escape(name) + ":" + str(spec["line"]) + r":")
        if not any(pattern.search(l) for l in err.splitlines()):
            problems.append(f"no line with '{name}:{spec['line']}:'")
    for text in spec["expect"]:
        if text not in err:
            problems.append(f"missing '{text}'")
    return problems


def leftovers(directory):
    return sorted(os.listdir(directory))


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    lamina = os.environ.get("LAMINA")
    if not lamina or not os.access(lamina, os.X_OK):
        print(f"run_invalid_corpus: set LAMINA to the lamina binary (got {lamina!r})")
        return 2
    lamina = os.path.abspath(lamina)
    directory = os.path.abspath(argv[1])
    whole_corpus = len(argv) == 2
    if whole_corpus:
        files = sorted(os.path.join(directory, f) for f in os.listdir(directory) if f.endswith(".yaml"))
    else:
        files = [os.path.abspath(f if os.path.exists(f) else os.path.join(directory, f)) for f in argv[2:]]

    failures = []
    for path in files:
        name = os.path.basename(path)
        spec = parse_header(path)
        reasons = []
        details = []
        with tempfile.TemporaryDirectory(prefix="lamina-invalid-") as tmp:
            commands = [("run", ["run", path, "-o", os.path.join(tmp, "out"), "--quiet"] + spec["args"]),
                        ("check", ["check", path] + spec["args"])]
            for label, command in commands:
                code, err, seconds = run_lamina(lamina, command, tmp)
                problems = check_output(spec, name, code, err)
                left = leftovers(tmp)
                if left:
                    problems.append("wrote " + ", ".join(left))
                    for entry in left:
                        subprocess.run(["rm", "-rf", os.path.join(tmp, entry)])
                if problems:
                    reasons.append(f"{label}: " + "; ".join(problems))
                    details.append(f"    $ lamina {shlex.join(command)}   (exit {code}, {seconds:.2f} s)")
                    details += ["    | " + l for l in err.splitlines()[:12]]
        if reasons:
            failures.append(name)
            print(f"FAIL {name}: " + " | ".join(reasons))
            for line in details:
                print(line)
        else:
            print(f"PASS {name}")
        sys.stdout.flush()

    passed = len(files) - len(failures)
    print(f"\n{len(files)} case files, {passed} passed, {len(failures)} failed")
    if failures:
        print("failed: " + ", ".join(failures))
    if whole_corpus and len(files) < MIN_FILES:
        print(f"the corpus needs at least {MIN_FILES} files, found {len(files)}")
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
