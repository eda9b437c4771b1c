#!/usr/bin/env bash
# Build lamina with AddressSanitizer + UndefinedBehaviorSanitizer (GCC) in its own build folder
# and run, under both sanitizers:
#   full (default): every unit-test program, the invalid-input corpus (tests/cases/invalid) and
#                   `lamina validate --fast`;
#   --quick:        the CI subset: only lamina, test_io and test_geometry are built; those two
#                   test programs and the invalid-input corpus are run.
# The full run also runs the checkpoint / restart tests (tests/cases/restart).
# Any sanitizer report fails the step it happens in (the sanitizers stop the program); the script
# runs every step, prints a summary and exits 1 if one of them failed.
#
# Usage: scripts/sanitize.sh [--quick]
# Environment:
#   LAMINA_SANITIZE_BUILD_DIR  build folder (default: build-asan in the source tree)
#   LAMINA_SANITIZE_JOBS       parallel compile jobs (default: nproc)
#   LAMINA_SANITIZE_KEEP       1: keep the validation report folder (default: removed on success)
#
# The build is RelWithDebInfo with -O1 -g and without -DNDEBUG (assert and Eigen's index checks
# are live); the Release-only -O3 -march flags of CMakeLists.txt are not used.
set -uo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
quick=0
for argument in "$@"; do
  case "$argument" in
    --quick) quick=1 ;;
    -h|--help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "sanitize.sh: unknown argument '$argument' (see --help)" >&2; exit 2 ;;
  esac
done
build="${LAMINA_SANITIZE_BUILD_DIR:-$root/build-asan}"
case "$build" in /*) ;; *) build="$PWD/$build" ;; esac
jobs="${LAMINA_SANITIZE_JOBS:-$(nproc)}"

# Sanitizer run-time options (inherited by every lamina process the tests start).
#  ASan: leaks are reported at exit (detect_leaks=1), including memory of the OpenMP (libgomp)
#        code, which gives no false reports; the one suppression (scripts/lsan.supp) is for
#        libgmsh's own leaks in test_geometry. exitcode 86 tells a sanitizer stop apart from
#        lamina's own exit codes 0-3.
#        max_allocation_size_mb + allocator_may_return_null: a runaway allocation throws
#        std::bad_alloc, as the corpus runner's 4 GiB address-space limit does for a normal build
#        (that limit cannot be used with ASan, which reserves terabytes of shadow address space).
#  UBSan: stop at the first report, with a stack trace (the build also has -fno-sanitize-recover).
lsan_suppressions="$root/scripts/lsan.supp"
export ASAN_OPTIONS="detect_leaks=1:exitcode=86:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:max_allocation_size_mb=4096:allocator_may_return_null=1:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:exitcode=86"
export LSAN_OPTIONS="suppressions=$lsan_suppressions:print_suppressions=1"  # see the file for why
export LAMINA_CORPUS_MEMORY_LIMIT=0  # tests/cases/run_invalid_corpus.py: no RLIMIT_AS (see above)

# -Wno-maybe-uninitialized: with -fsanitize=address GCC 12 reports false -Wmaybe-uninitialized
# warnings inside libstdc++ (<regex>, std::function); the normal build keeps the warning.
sanitizers="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -Wno-maybe-uninitialized"
start_all=$(date +%s)
failed=()
results=()

step() {  # step NAME COMMAND...: run, time, record
  local name="$1"; shift
  local start=$(date +%s)
  echo "==== sanitize: $name"
  "$@"
  local code=$?
  local seconds=$(( $(date +%s) - start ))
  if [ "$code" = 0 ]; then
    results+=("PASS  $name  (${seconds} s)")
  else
    results+=("FAIL  $name  (exit $code, ${seconds} s)")
    failed+=("$name")
  fi
  echo "==== sanitize: $name: exit $code, ${seconds} s"
  return "$code"
}

summary() {
  echo
  echo "==== sanitize.sh$([ "$quick" = 1 ] && echo " --quick") summary ($build, $(( $(date +%s) - start_all )) s)"
  printf '  %s\n' "${results[@]}"
  if [ "${#failed[@]}" -gt 0 ]; then
    echo "  failed: ${failed[*]}"
    exit 1
  fi
  echo "  clean"
  exit 0
}

# The Python module is left out: an ASan-built extension needs the interpreter started with libasan preloaded.
configure() {
  CC=gcc CXX=g++ cmake -S "$root" -B "$build" -G Ninja \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
    -DCMAKE_CXX_FLAGS="$sanitizers" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DLAMINA_BUILD_TESTS=ON -DLAMINA_BUILD_BENCH=OFF -DLAMINA_BUILD_FUZZ=OFF -DLAMINA_BUILD_PYTHON=OFF
}

if [ "$quick" = 1 ]; then
  targets=(lamina test_io test_geometry)
else
  targets=(all)
fi
build_targets() { cmake --build "$build" --parallel "$jobs" --target "${targets[@]}"; }

step configure configure || summary
step "build (${targets[*]})" build_targets || summary

run_tests() {  # every test program of the build (or the quick ones), one after the other
  local code=0 program
  local programs=()
  if [ "$quick" = 1 ]; then
    programs=("$build/tests/test_io" "$build/tests/test_geometry")
  else
    for program in "$build"/tests/test_*; do
      [ -x "$program" ] && [ -f "$program" ] && programs+=("$program")
    done
  fi
  [ "${#programs[@]}" -gt 0 ] || { echo "no test programs in $build/tests"; return 1; }
  for program in "${programs[@]}"; do
    echo "---- $(basename "$program")"
    (cd "$build/tests" && "$program" --gtest_brief=1)
    local status=$?
    if [ "$status" != 0 ]; then
      echo "---- $(basename "$program"): FAILED (exit $status)"
      code=1
    fi
  done
  return $code
}
step "unit tests" run_tests

step "invalid-input corpus" env LAMINA="$build/lamina" /usr/bin/python3 "$root/tests/cases/run_invalid_corpus.py" "$root/tests/cases/invalid"

# checkpoint / restart (docs/restart.md): the checkpoint writer and reader, SIGKILL / SIGTERM and restart
# (full mode only: the runs are about 30 x slower under the sanitizers, ~10 minutes)
if [ "$quick" = 0 ]; then
  restart_out="$(mktemp -d "${TMPDIR:-/tmp}/lamina-sanitize-restart-XXXXXX")"
  step "checkpoint / restart" env LAMINA="$build/lamina" /usr/bin/python3 "$root/tests/cases/restart/run_restart_tests.py" \
    "$root/tests/cases/restart" "$restart_out" && rm -rf "$restart_out"
fi

if [ "$quick" = 0 ]; then
  validation_out="$(mktemp -d "${TMPDIR:-/tmp}/lamina-sanitize-validate-XXXXXX")"
  validate_fast() { (cd "$root" && "$build/lamina" validate --fast -o "$validation_out"); }
  if step "validate --fast" validate_fast; then
    [ "${LAMINA_SANITIZE_KEEP:-0}" = 1 ] && echo "validation report: $validation_out" || rm -rf "$validation_out"
  else
    echo "validation report kept: $validation_out"
  fi
fi

summary
