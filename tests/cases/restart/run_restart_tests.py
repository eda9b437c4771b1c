#!/usr/bin/env python3
"""Checkpoint / restart tests (docs/restart.md, issue 19).

For each case of this folder (PD explicit, PD post-buckling by ADR, MPM tube crush):
  1. an uninterrupted run (the reference);
  2. the same run killed with SIGKILL at a random point after its first checkpoint, then
     `lamina run CASE -o OUT --restart OUT`: history.csv must equal the reference byte for byte,
     summary.json's probes bit for bit, and the frame count must agree; the killed run's staging
     folder must be gone afterwards.
Once (on the first case):
  3. SIGTERM: exit code 143, status "interrupted" in the committed result set, and a restart from
     it again gives the reference history;
  4. a truncated newest checkpoint is refused with a warning and the older one used (same history);
     both damaged (a flipped bit, truncation) give exit 2 naming the reason; a changed case key
     gives exit 2 naming that key with its line.
Usage: LAMINA=path/to/lamina run_restart_tests.py CASE_DIR WORK_DIR   (seed: RESTART_TEST_SEED)
"""
import glob
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

LAMINA = os.environ.get("LAMINA", "lamina")
THREADS = "1"  # bit-identical restarts hold at the same thread count; 1 keeps CI's parallel tests apart


def lamina_run(case, out, *extra):
    return subprocess.run([LAMINA, "run", case, "-o", out, "--quiet", "--threads", THREADS, *extra],
                          capture_output=True, text=True)


def start(case, out):
    return subprocess.Popen([LAMINA, "run", case, "-o", out, "--quiet", "--threads", THREADS],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def wait_for_checkpoint(proc, out):
    """Seconds until the running process' staging folder holds a checkpoint (None if it ended first)."""
    pattern = f"{out}.partial-{proc.pid}/checkpoint_*.bin"
    begin = time.time()
    while proc.poll() is None:
        if glob.glob(pattern):
            return time.time() - begin
        time.sleep(0.002)
    return None


def probes(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)["probes"]


def read(path):
    with open(path, "rb") as f:
        return f.read()


def frames(folder):
    return sorted(os.path.basename(p) for p in glob.glob(os.path.join(folder, "frame_*.vtu")))


failures = []


def check(condition, message):
    print(("ok    " if condition else "FAIL  ") + message)
    if not condition:
        failures.append(message)
    return condition


def same_as_reference(folder, reference, what):
    check(read(os.path.join(folder, "history.csv")) == read(os.path.join(reference, "history.csv")),
          f"{what}: history.csv identical to the uninterrupted run")
    check(probes(folder) == probes(reference), f"{what}: summary.json probes identical")
    check(frames(folder) == frames(reference), f"{what}: the same {len(frames(reference))} VTU frames")


def killed_and_restarted(case, work, name, rng):
    reference = os.path.join(work, name + "_reference")
    t0 = time.time()
    r = lamina_run(case, reference)
    duration = time.time() - t0
    if not check(r.returncode == 0, f"{name}: uninterrupted run ({duration:.1f} s) exit 0 [{r.stderr.strip()[-300:]}]"):
        return None
    out = os.path.join(work, name)
    for attempt in range(6):
        shutil.rmtree(out, ignore_errors=True)
        proc = start(case, out)
        first = wait_for_checkpoint(proc, out)
        if first is None:
            proc.wait()
            continue
        delay = rng.uniform(0.0, max(0.0, 0.8 * (duration - first))) * (0.5 ** attempt)
        time.sleep(delay)
        if proc.poll() is not None:
            continue  # finished before the kill: try again, earlier
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        staging = f"{out}.partial-{proc.pid}"
        killed = sorted(glob.glob(os.path.join(staging, "checkpoint_*.bin")))
        print(f"      {name}: SIGKILL {first + delay:.2f} s into the run (checkpoints {[os.path.basename(k) for k in killed]})")
        r = lamina_run(case, out, "--restart", out)
        check(r.returncode == 0, f"{name}: restart after SIGKILL exit 0 [{r.stderr.strip()[-300:]}]")
        same_as_reference(out, reference, f"{name} (SIGKILL + restart)")
        check(not os.path.exists(staging), f"{name}: the killed run's staging folder was removed")
        return reference
    check(False, f"{name}: could not kill the run after a checkpoint (it finished first every time)")
    return reference


def signals_and_damage(case, work, name, reference):
    # SIGTERM: a checkpoint, exit 143, the interrupted result set committed
    out = os.path.join(work, name + "_sigterm")
    shutil.rmtree(out, ignore_errors=True)
    proc = start(case, out)
    if wait_for_checkpoint(proc, out) is not None:
        proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate()
    if check(proc.returncode == 143, f"{name}: SIGTERM gives exit 143 (found {proc.returncode}) [{err.strip()[-200:]}]"):
        with open(os.path.join(out, "summary.json")) as f:
            check(json.load(f)["status"] == "interrupted", f"{name}: summary.json status 'interrupted'")
        r = lamina_run(case, out, "--restart", out)
        check(r.returncode == 0, f"{name}: restart after SIGTERM exit 0 [{r.stderr.strip()[-300:]}]")
        same_as_reference(out, reference, f"{name} (SIGTERM + restart)")

    # damaged checkpoints: the reference folder holds the newest two
    damaged = os.path.join(work, name + "_damaged")
    shutil.rmtree(damaged, ignore_errors=True)
    shutil.copytree(reference, damaged)
    older, newest = sorted(glob.glob(os.path.join(damaged, "checkpoint_*.bin")))[-2:]
    with open(newest, "r+b") as f:
        f.truncate(os.path.getsize(newest) // 2)
    r = lamina_run(case, damaged, "--restart", damaged)
    log = read(os.path.join(damaged, "log.txt")).decode() if r.returncode == 0 else ""
    check(r.returncode == 0 and "checkpoint refused" in log and "truncated" in log,
          f"{name}: a truncated newest checkpoint is refused with a warning, the older one used "
          f"[{r.stderr.strip()[-200:]}]")
    same_as_reference(damaged, reference, f"{name} (restart from the older checkpoint)")

    for label, damage in (("a flipped bit", "flip"), ("truncation", "truncate")):
        folder = os.path.join(work, f"{name}_{damage}")
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(reference, folder)
        for path in glob.glob(os.path.join(folder, "checkpoint_*.bin")):
            data = bytearray(read(path))
            if damage == "flip":
                data[len(data) * 2 // 3] ^= 0x10
            else:
                data = data[: len(data) - 9]
            with open(path, "wb") as f:
                f.write(data)
        r = lamina_run(case, folder, "--restart", folder)
        reason = "checksum" if damage == "flip" else "truncated"
        check(r.returncode == 2 and reason in r.stderr and "--restart" in r.stderr,
              f"{name}: every checkpoint damaged by {label}: exit 2 saying '{reason}' (exit {r.returncode}) "
              f"[{r.stderr.strip()[-200:]}]")

    # a result frame the checkpoint lists deleted since: exit 2 naming the missing frame
    vtus = sorted(glob.glob(os.path.join(reference, "frame_*.vtu")))
    if vtus:
        folder = os.path.join(work, name + "_lost_frame")
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(reference, folder)
        os.remove(os.path.join(folder, "frame_00000.vtu"))
        r = lamina_run(case, folder, "--restart", folder)
        check(r.returncode == 2 and "frame_00000.vtu" in r.stderr and "--restart" in r.stderr
              and not glob.glob(folder + ".partial-*"),
              f"{name}: a deleted result frame gives exit 2 naming it, no staging left (exit {r.returncode}) "
              f"[{r.stderr.strip()[-200:]}]")

    # a changed case value (the case file edited): exit 2 naming the key with its line
    folder = os.path.join(work, name + "_mismatch")
    shutil.rmtree(folder, ignore_errors=True)
    shutil.copytree(reference, folder)
    edited = os.path.join(work, name + "_edited.yaml")
    lines = read(case).decode().splitlines(keepends=True)
    line = next(k for k, text in enumerate(lines) if re.search(r"\bE: [0-9.e+-]+", text))
    lines[line] = re.sub(r"\bE: ([0-9.e+-]+)", lambda m: f"E: {float(m.group(1)) * 1.01:g}", lines[line])
    with open(edited, "w") as f:
        f.writelines(lines)
    r = lamina_run(edited, folder, "--restart", folder)
    check(r.returncode == 2 and f"{edited}:{line + 1}:" in r.stderr and "materials.0.E" in r.stderr,
          f"{name}: an edited material gives exit 2 naming materials.0.E at line {line + 1} [{r.stderr.strip()[-250:]}]")
    r = lamina_run(case, folder, "--restart", os.path.join(work, "no_such_folder"))
    check(r.returncode == 2 and "no checkpoint" in r.stderr, f"{name}: a folder without checkpoints gives exit 2 "
          f"[{r.stderr.strip()[-200:]}]")


def longer_end_time(case, work, name, reference):
    """A finished explicit run continued to a later end time (pd.explicit.end_time is a restart key)."""
    folder = os.path.join(work, name + "_extended")
    shutil.rmtree(folder, ignore_errors=True)
    r = lamina_run(case, folder, "--set", "pd.explicit.end_time=80")
    r2 = lamina_run(case, folder, "--restart", folder) if r.returncode == 0 else r
    if not check(r2.returncode == 0, f"{name}: run to t = 80, restarted to the case's t = 160: exit 0 [{r2.stderr.strip()[-200:]}]"):
        return
    last = read(os.path.join(folder, "history.csv")).decode().strip().splitlines()[-1].split(",")
    ref = read(os.path.join(reference, "history.csv")).decode().strip().splitlines()[-1].split(",")
    check(float(last[1]) == 160.0, f"{name}: the continued run ends at t = {last[1]}")
    # the same physics at (within round-off) the same step: the final probes agree to 1e-9
    agree = all(abs(float(a) - float(b)) <= 1e-9 * max(abs(float(b)), 1e-12) for a, b in zip(last[3:5], ref[3:5]))
    check(agree, f"{name}: its final energy and tip displacement {last[3:5]} agree with the single run {ref[3:5]}")


def main():
    case_dir, work = sys.argv[1], sys.argv[2]
    seed = int(os.environ.get("RESTART_TEST_SEED", str(int(time.time()))))
    print(f"restart tests, seed {seed} (RESTART_TEST_SEED={seed} repeats the kill points)")
    rng = random.Random(seed)
    os.makedirs(work, exist_ok=True)
    cases = sorted(glob.glob(os.path.join(case_dir, "*.yaml")))
    for k, case in enumerate(cases):
        name = os.path.splitext(os.path.basename(case))[0]
        reference = killed_and_restarted(case, work, name, rng)
        if reference and k == 0:
            signals_and_damage(case, work, name, reference)
        if reference and name == "pd_explicit":
            longer_end_time(case, work, name, reference)
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
