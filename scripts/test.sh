#!/usr/bin/env bash
# Build (Release) and run the whole default test suite: unit tests, the invalid-input corpus,
# result-file checks, examples, and `lamina validate --fast`. This is the README's test command.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/lamina" info >/dev/null          # installs dependencies (as root), configures and builds
build="${LAMINA_BUILD_DIR:-$root/build}"
cd "$build"
ctest --output-on-failure --parallel "$(nproc)" --timeout 900
