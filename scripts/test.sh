#!/usr/bin/env bash
# Sets up, builds and runs the test suite (Catch2 under ctest) on the OpenCL
# device MILLCHARGE_DEVICE picks (default: a GPU if present, else PoCL's CPU).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
cd build
ctest --output-on-failure --timeout 900 "$@"
