#!/usr/bin/env bash
# Sets up, builds and runs the default job headless: the lab mill
# (assets/cases/lab.toml), writing runs/lab-DATE-TIME/
# Extra arguments go to `millcharge run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
exec ./build/millcharge run "$@"
