#!/usr/bin/env bash
# Sets up, builds and runs the test suite (Catch2 under ctest) on the OpenCL
# device MILLCHARGE_DEVICE picks (default: a GPU if present, else PoCL's CPU).
# The tiers run with the rest; `ctest -L rusticl` (or viewer) in build/ runs
# one. The last line repeats ctest's count of the tests that passed.
#
# ctest runs as many tests at once as the machine has cores
# (MILLCHARGE_TEST_JOBS to change it), each with one PoCL thread: the
# suite's mills are small, and on them a second PoCL thread costs more in
# waking and waiting than it computes (a test of 170 balls: 103 s with two
# threads, 79 s with one, on the 2-core CI machine). A device other than
# PoCL ignores POCL_MAX_PTHREAD_COUNT.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
cd build
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
jobs=${MILLCHARGE_TEST_JOBS:-$(nproc)}
export POCL_MAX_PTHREAD_COUNT=${POCL_MAX_PTHREAD_COUNT:-1}
ctest --output-on-failure --timeout 1500 -j "$jobs" "$@" 2>&1 | tee "$log" || status=$?
count=$(grep -E '[0-9]+% tests passed' "$log" | tail -1)
echo "test.sh: ${count:-ctest printed no count (status $status)}"
exit "$status"
