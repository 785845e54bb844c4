#!/usr/bin/env bash
# Sets up, builds and runs the default job headless: the laboratory drum.
# Extra arguments go to `millcharge run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
exec ./build/millcharge run "$@"
