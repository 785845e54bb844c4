#!/usr/bin/env bash
# Sets up, builds and runs the test suite (Catch2 under ctest) on the OpenCL
# device MILLCHARGE_DEVICE picks (default: a GPU if present, else PoCL's CPU).
# The tiers run with the rest; `ctest -L rusticl` (or viewer) in build/ runs
# one. The last line repeats ctest's count of the tests that passed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
cd build
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
ctest --output-on-failure --timeout 900 "$@" 2>&1 | tee "$log" || status=$?
count=$(grep -E '[0-9]+% tests passed' "$log" | tail -1)
echo "test.sh: ${count:-ctest printed no count (status $status)}"
exit "$status"
