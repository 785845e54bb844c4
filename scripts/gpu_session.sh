#!/bin/bash
# Runs the tests and the benchmark on a GPU machine that lacks this
# project's packages, from a copy of the repository that holds gpu-kit/
# (made here by scripts/gpu_kit.sh; with the device tool, name gpu-kit in
# `carry`):
#
#   bash scripts/gpu_session.sh [--tests] [--validate] [--bench ROWS] [--steps N] [--device SPEC]
#
# --tests runs millcharge_tests (all but the viewer's) on the GPU;
# --validate runs the validation checks there (millcharge_validate, as
# scripts/validate.sh does; validation.jsonl, and validation.md when
# python3 is there); --bench
# runs scripts/bench.sh for ROWS (its row names, e.g.
# lab,tile-10k,tile-100k,tile-1M,100k,D) and the law probe. With neither,
# it only lists the devices. It finds NVIDIA's OpenCL library
# (libnvidia-opencl.so.1; MC_OPENCL_LIB names another driver's), points an
# ICD file of its own at it, and puts gpu-kit/lib on the library path, so
# nothing is installed. The build's compiled-in root (gpu-kit/build-root)
# is linked to this copy when it does not exist here. Logs go to $OUT
# when it is set (the device tool's folder), else to runs/gpu-DATE:
# devices.txt, tests.log, validation.jsonl, validation.md, bench.md and
# bench.jsonl.
set -uo pipefail
root=$(pwd)
kit=$root/gpu-kit
tests=0; validate=0; rows=""; steps=""; device=gpu
while [ $# -gt 0 ]; do
  case "$1" in
    --tests) tests=1; shift ;;
    --validate) validate=1; shift ;;
    --bench) rows="${2:?--bench needs rows, e.g. lab,100k,D}"; shift 2 ;;
    --steps) steps="${2:?--steps needs a number}"; shift 2 ;;
    --device) device="${2:?--device needs a spec}"; shift 2 ;;
    *) echo "gpu_session.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[ -x "$kit/bin/millcharge" ] || { echo "gpu_session.sh: no $kit/bin/millcharge: run scripts/gpu_kit.sh on the build machine and carry gpu-kit" >&2; exit 1; }
out=${OUT:-$root/runs/gpu-$(date +%Y%m%d-%H%M%S)}
mkdir -p "$out"

# The OpenCL driver: an ICD file of our own naming it.
lib=${MC_OPENCL_LIB:-}
[ -n "$lib" ] || lib=$(ldconfig -p 2> /dev/null | awk '/libnvidia-opencl\.so\.1 /{print $NF; exit}')
[ -n "$lib" ] || lib=$(find / \( -path /proc -o -path /sys -o -path "$root" \) -prune -o -name 'libnvidia-opencl.so.1' -print 2> /dev/null | head -1)
[ -n "$lib" ] || { echo "gpu_session.sh: no libnvidia-opencl.so.1 on this machine (set MC_OPENCL_LIB to the driver's OpenCL library)" >&2; exit 1; }
icd=$(mktemp -d)
echo "$lib" > "$icd/gpu.icd"
export OCL_ICD_VENDORS=$icd
export LD_LIBRARY_PATH=$kit/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}

# The programs where the build's paths expect them.
build_root=$(cat "$kit/build-root")
if [ "$build_root" != "$root" ]; then
  if [ ! -e "$build_root" ]; then
    mkdir -p "$(dirname "$build_root")" && ln -s "$root" "$build_root"
  elif [ "$(cd "$build_root" && pwd -P)" != "$(pwd -P)" ]; then
    echo "gpu_session.sh: $build_root exists and is not this copy: the kernels and assets it holds will be used" >&2
  fi
fi
mkdir -p build/tests
cp "$kit/bin/millcharge" build/millcharge
cp "$kit/bin/millcharge_law_probe" build/millcharge_law_probe
cp "$kit/bin/millcharge_validate" build/millcharge_validate
cp "$kit/bin/millcharge_tests" build/tests/millcharge_tests

{
  echo "OpenCL library: $lib; kit built at $(cat "$kit/commit" 2> /dev/null || echo '?')"
  "$kit/bin/clinfo" -l
  build/millcharge devices
  command -v nvidia-smi > /dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv
} 2>&1 | tee "$out/devices.txt"
status=0
if [ "$tests" = 1 ]; then
  echo "gpu_session.sh: tests on --device $device" >&2
  MILLCHARGE_DEVICE=$device build/tests/millcharge_tests --durations yes > "$out/tests.log" 2>&1 || status=1
  tail -4 "$out/tests.log"
fi
if [ "$validate" = 1 ]; then
  echo "gpu_session.sh: validation checks on --device $device" >&2
  vstatus=0
  build/millcharge_validate --device "$device" > "$out/validation.jsonl" 2> "$out/validation.err" || vstatus=$?
  # 3: every check ran and a row fails, which the report shows.
  [ "$vstatus" = 0 ] || [ "$vstatus" = 3 ] || status=1
  if command -v python3 > /dev/null && [ "$vstatus" != 1 ]; then
    python3 scripts/validation_report.py --rows "$out/validation.jsonl" \
      --command "bash scripts/gpu_session.sh --validate --device $device" \
      --machine "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) CPUs" \
      --date "$(date -u +%Y-%m-%d)" --commit "$(cat "$kit/commit" 2> /dev/null || echo '?')" \
      --liggghts-note "not run on the GPU machine" > "$out/validation.md" || status=1
  fi
  tail -2 "$out/validation.err"
fi
if [ -n "$rows" ]; then
  args=(--device "$device" --only "$rows")
  [ -n "$steps" ] && args+=(--steps "$steps")
  bash scripts/bench.sh "${args[@]}" > "$out/bench.md" 2> "$out/bench.err" || status=1
  cat "$out/bench.md"
  build/millcharge_law_probe --device "$device" 2>&1 | tee "$out/law_probe.txt" || status=1
  dir=$(sed -n 's/^bench.sh: JSON lines in //p' "$out/bench.err" | tail -1)
  [ -n "$dir" ] && cat "$dir"/*.json > "$out/bench.jsonl"
  tail -3 "$out/bench.err" >&2
fi
exit $status
