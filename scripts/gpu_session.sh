#!/bin/bash
# One GPU session in one command that ends by itself within its budget
# (default 540 s: a lent machine's 15 minutes hold this call, its start, and
# time to run it again), run from a copy of
# the repository that holds gpu-kit/ (made here by scripts/gpu_kit.sh; with
# the device tool, name gpu-kit in `carry`):
#
#   bash scripts/gpu_session.sh [--budget S] [--device SPEC] [--dry-run]
#
# Steps, in this order, each under its own time limit, each writing its
# figures under $OUT (else runs/gpu-DATE) as soon as it ends, so a session
# cut short still returns what it measured:
#   devices     clinfo, `millcharge devices`, nvidia-smi      -> devices.txt
#   kernels     the kernels built once (float and double), the driver's
#               build log (-cl-nv-verbose on NVIDIA), each kernel's
#               private and local memory, and, where ptxas is on the
#               machine, each kernel's registers, stack and spills
#               (scripts/ptx_report.sh)                        -> kernels.log
#               the program binaries (PTX on NVIDIA: run
#               scripts/ptx_report.sh on them where ptxas is)  -> program.tar.gz
#   tests       kernel against CPU reference, books, poison;
#               then the clumps against the CPU reference, a
#               step of its own (its reference is slow)        -> tests.log
#   validation  the analytic validation checks                 -> validation.jsonl
#   bench       rows lab (and lab with the status word read every step),
#               tile-10k, tile-1M (its stage split in its JSON), the lab
#               mill's charge as rock clumps, mill D,
#               few steps each; a row whose budget is gone is
#               skipped, and the ledger says so                -> bench.jsonl
#   whole run   seed mill D's slice run start to end (settle,
#               turn, books, pictures): its summary.json as one
#               more line of bench.jsonl ("row": "mill D slice,
#               whole run"), its console in the ledger
#   law probe   the contact law's cost per pair                -> law_probe.txt
#   life        seed mill D's slice over its liner's life (`millcharge
#               life`, 4 worn stages until the lifters are 50 mm high):
#               life.csv and each stage's wall time in the ledger; last,
#               on what the budget has left (--life: this step alone,
#               after devices, on the whole budget)
# session.log is the ledger: each step's budget, the seconds it took, its
# exit status, or why it was skipped, and what the steps printed on
# stderr. Eight files in all (the device tool returns eight).
# --dry-run runs the same plan with this checkout's build/ on PoCL's CPU
# device (no kit, no driver search), to see the plan, the budgets and the
# files on a machine without a GPU.
set -uo pipefail
root=$(pwd)
kit=$root/gpu-kit
budget=540; device=gpu; dry=0; life_only=0
while [ $# -gt 0 ]; do
  case "$1" in
    --budget) budget="${2:?--budget needs seconds}"; shift 2 ;;
    --device) device="${2:?--device needs a spec}"; shift 2 ;;
    --dry-run) dry=1; device=cpu; shift ;;
    --life) life_only=1; shift ;;
    *) echo "gpu_session.sh: unknown argument '$1' (use --budget, --device, --dry-run, --life)" >&2; exit 2 ;;
  esac
done
out=${OUT:-$root/runs/gpu-$(date +%Y%m%d-%H%M%S)}
mkdir -p "$out"
ledger=$out/session.log
start=$(date +%s)
left() { echo $((budget - ($(date +%s) - start))); }
exec 3>&2  # the terminal, whatever a step's stderr is sent to
log() { echo "$*" >> "$ledger"; echo "$*" >&3; }

# step NAME SECONDS COMMAND...: runs COMMAND under the smaller of SECONDS
# and what is left of the budget (less 10 s for the ledger), or skips it.
step() {
  local name=$1 want=$2; shift 2
  local have=$(($(left) - 10))
  local limit=$((want < have ? want : have))
  if [ "$limit" -lt 15 ]; then
    log "step $name: skipped, $have s of the budget left (wanted $want s)"
    return 0
  fi
  local t0=$(date +%s) rc=0
  timeout --kill-after=5 "$limit" "$@" || rc=$?
  local used=$(($(date +%s) - t0))
  case $rc in
    0) log "step $name: done in $used s (limit $limit s)" ;;
    124 | 137) log "step $name: stopped at its limit of $limit s; what it wrote is kept" ;;
    *) log "step $name: exit $rc after $used s (limit $limit s)" ;;
  esac
  return 0
}

if [ "$dry" = 1 ]; then
  bin=$root/build
  [ -x "$bin/millcharge" ] && [ -x "$bin/tests/millcharge_tests" ] || bash scripts/build.sh >&2
  tests_bin=$bin/tests/millcharge_tests
  clinfo_bin=$(command -v clinfo || echo true)
  log "gpu_session.sh: dry run on --device $device with build/, budget $budget s"
else
  [ -x "$kit/bin/millcharge" ] || { echo "gpu_session.sh: no $kit/bin/millcharge: run scripts/gpu_kit.sh on the build machine and carry gpu-kit" >&2; exit 1; }
  # The OpenCL driver, where a container's driver mount puts it first: the
  # library path, /usr/local/nvidia, then the loader's cache, then a search
  # of a few folders that gives up after 20 s.
  lib=${MC_OPENCL_LIB:-}
  if [ -z "$lib" ]; then
    IFS=: read -r -a dirs <<< "${LD_LIBRARY_PATH:-}"
    for d in "${dirs[@]}" /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64; do
      [ -n "$d" ] && [ -e "$d/libnvidia-opencl.so.1" ] && { lib=$d/libnvidia-opencl.so.1; break; }
    done
  fi
  [ -n "$lib" ] || lib=$(ldconfig -p 2> /dev/null | awk '/libnvidia-opencl\.so\.1 /{print $NF; exit}')
  [ -n "$lib" ] || lib=$(timeout 20 find /usr /opt /lib -name 'libnvidia-opencl.so.1' -print 2> /dev/null | head -1)
  [ -n "$lib" ] || { echo "gpu_session.sh: no libnvidia-opencl.so.1 on this machine (set MC_OPENCL_LIB to the driver's OpenCL library)" | tee -a "$ledger" >&2; exit 1; }
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
  bin=$kit/bin
  tests_bin=$kit/bin/millcharge_tests
  clinfo_bin=$kit/bin/clinfo
  log "gpu_session.sh: OpenCL library $lib; kit built at $(cat "$kit/commit" 2> /dev/null || echo '?'); budget $budget s"
  log "gpu_session.sh: $("$kit/bin/millcharge" --version 2>&1)"
fi
mc=$bin/millcharge

export clinfo_bin mc
step devices 30 bash -c '"$clinfo_bin" -l; "$mc" devices; command -v nvidia-smi > /dev/null &&
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv; true' > "$out/devices.txt" 2>&1
platform=$("$mc" devices 2>> "$ledger" | grep -i -m1 nvidia || true)
scratch=$(mktemp -d)  # not under $OUT: only the eight files go back

# Seed mill D's slice over its liner's life: the table and each stage's
# cost go into the ledger (the device tool returns eight files).
life_step() {
  local study=$scratch/mill-d-life
  step "life, mill D slice" "$1" "$mc" life assets/cases/mill_d_slice.toml --device "$device" --stages 4 \
    --until-height 50 --quiet --out "$study" > "$scratch/life.log" 2>&1
  grep -E "^(life|speed|millcharge: )" "$scratch/life.log" >> "$ledger"
  [ -f "$study/life.csv" ] && { echo "life.csv:"; cat "$study/life.csv"; } >> "$ledger"
}
finish() {
  rm -rf "$scratch"
  find "$out" -maxdepth 1 -type f -empty -delete  # what skipped steps left
  log "gpu_session.sh: $(($(date +%s) - start)) s of $budget s; files: $(cd "$out" && ls | tr '\n' ' ')"
  exit 0
}
if [ "$life_only" = 1 ]; then
  life_step $((budget - 20))
  finish
fi

# The kernels, built once in each precision with the driver's log kept
# (NVIDIA's compiler prints some kernels' registers and spills under
# -cl-nv-verbose, not all), and the program binaries with each kernel's
# figures (MILLCHARGE_PROGRAM_DUMP).
export MILLCHARGE_BUILD_LOG=$out/kernels.log MILLCHARGE_PROGRAM_DUMP=$scratch/program
[ -n "$platform" ] && export MILLCHARGE_CL_OPTIONS="${MILLCHARGE_CL_OPTIONS:+$MILLCHARGE_CL_OPTIONS }-cl-nv-verbose"
step kernels 60 "$mc" bench assets/cases/lab.toml --device "$device" --steps 20 --warmup 0 --books on --quiet \
  > /dev/null 2>> "$out/kernels.log"
step "kernels, double" 60 "$mc" bench assets/cases/lab.toml --device "$device" --precision double --steps 20 \
  --warmup 0 --books on --quiet > /dev/null 2>> "$out/kernels.log"
unset MILLCHARGE_BUILD_LOG MILLCHARGE_PROGRAM_DUMP
for f in "$scratch"/program/kernels-*.txt; do [ -f "$f" ] && cat "$f" >> "$out/kernels.log"; done
for f in "$scratch"/program/program-*.ptx; do
  [ -f "$f" ] && bash scripts/ptx_report.sh "$f" >> "$out/kernels.log" 2>> "$ledger"
done
[ -d "$scratch/program" ] && tar -czf "$out/program.tar.gz" -C "$scratch" program 2>> "$ledger"

# Kernel against reference (forces, contacts, motion), the books, the
# poison test; a test process stops at the first fault a GPU makes sticky.
# The clumps' reference runs on one CPU core: a step of its own.
step tests 150 env MILLCHARGE_DEVICE="$device" "$tests_bin" "[forces],[contacts],[motion],[books],[poison]" \
  --durations yes > "$out/tests.log" 2>&1
step "tests, clumps' reference" 120 env MILLCHARGE_DEVICE="$device" "$tests_bin" "[bodies][reference]" \
  --durations yes >> "$out/tests.log" 2>&1

vlog=$scratch/validation.err
step validation 60 "$bin/millcharge_validate" --device "$device" > "$out/validation.jsonl" 2> "$vlog"
tail -2 "$vlog" >> "$ledger"

# Bench rows from small to large, each JSON line appended as it ends.
bench_row() {  # NAME SECONDS ARGS... (ROW_ENV: VAR=VALUE for this row)
  local name=$1 want=$2; shift 2
  step "bench $name" "$want" env ${ROW_ENV:-} bash -c '"$@" >> "'"$out"'/bench.jsonl"' _ "$mc" bench "$@" \
    --device "$device" --quiet
}
settled=$scratch/settled-10k
step "settle 10k" 60 "$mc" run assets/cases/bench_100k.toml --set mill.length=0.305 --set run.duration=0.05 \
  --set run.warmup=0 --set run.snapshot_interval=0 --device "$device" --out "$settled" --quiet > /dev/null 2>> "$ledger"
bench_row lab 40 assets/cases/lab.toml --steps 2000 --warmup 0.05
# The same with the status word read every step (a GPU reads it every 4).
ROW_ENV=MILLCHARGE_STATUS_EVERY=1 bench_row "lab, status read every step" 40 assets/cases/lab.toml --steps 2000 \
  --warmup 0.05
if [ -f "$settled/checkpoint.bin" ]; then
  bench_row tile-10k 40 --from "$settled" --tile 1 --steps 2000
  bench_row tile-1M 90 --from "$settled" --tile 100 --steps 200
else
  log "bench tile-10k, tile-1M: skipped, the settled 10k charge was not made"
fi
# Clumps: the lab mill's charge as 12-sphere rocks (32,568 spheres).
bench_row "lab, rock clumps" 40 assets/cases/lab.toml --set charge.size.0.shape=rock --steps 500 --warmup 0.05
# A whole run, as a user runs it: seed mill D's slice (60,498 balls) from
# packing to pictures. Its summary goes into bench.jsonl as one line.
whole=$scratch/mill-d-slice
step "whole run, mill D slice" 90 "$mc" run assets/cases/mill_d_slice.toml --device "$device" --out "$whole" \
  > "$scratch/whole.log" 2>&1
grep -E "^(power draw|per metre|charge angles|morrell|wrote|millcharge: )" "$scratch/whole.log" >> "$ledger"
if [ -f "$whole/summary.json" ]; then
  { printf '{"row":"mill D slice, whole run","summary":'; tr -d '\n' < "$whole/summary.json"; echo '}'; } >> "$out/bench.jsonl"
else
  tail -5 "$scratch/whole.log" >> "$ledger"
fi
bench_row D 120 assets/cases/mill_d.toml --steps 100 --warmup 0.05
step "law probe" 30 "$bin/millcharge_law_probe" --device "$device" > "$out/law_probe.txt" 2>&1
life_step 240
finish
