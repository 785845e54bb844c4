#!/usr/bin/env bash
# The benchmark table: `millcharge bench` on the lab mill, the 100k benchmark
# mill and seed mill D (1.28 M balls), and the scaling sets (the benchmark
# mill cut to 10k and stretched to 1M balls: same cross-section, same work
# per ball). Prints a Markdown table on stdout and keeps each JSON line in
# runs/bench-DATE/. Usage:
#   bash scripts/bench.sh [--device SPEC] [--only ROWS] [--steps N]
# ROWS (default all): lab,10k-settled,tile-10k,tile-100k,tile-1M,10k,100k,1M,D.
# lab, 10k, 100k, 1M and D warm up 0.25 s of simulated time first (the
# packed charge falls into a dense bed); on 2 CPU cores mill D takes most of
# an hour, and the 1M row's warm-up as long. The other rows first run the
# 10k mill until its charge has settled and turned 0.05 s (`millcharge run`,
# a few minutes on 2 cores), then time the steps after that from the run's
# checkpoint (`bench --from`): 10k-settled as it is; tile-10k, tile-100k
# and tile-1M with its balls laid anew 1, 10 and 100 times along the axis
# of a mill as many times as long (`--tile`: the same settled charge, the
# same state per ball, no warm-up), which shows the cost per ball from 10k
# to 1M balls. Each row times the steps with the energy books (spectra,
# liner sums) on and off in turn, from the same state. MILLCHARGE_FORCES=
# grouped in the environment times the grouped force kernel instead (the
# device column says so).
set -euo pipefail
cd "$(dirname "$0")/.."
device=""; only="lab,10k-settled,tile-10k,tile-100k,tile-1M,10k,100k,1M,D"; steps=""
while [ $# -gt 0 ]; do
  case "$1" in
    --device) device="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    *) echo "bench.sh: unknown argument $1 (use --device, --only, --steps)" >&2; exit 2 ;;
  esac
done
[ -x build/millcharge ] || bash scripts/build.sh >&2
out="runs/bench-$(date +%Y%m%d-%H%M%S)"
dev=(); [ -n "$device" ] && dev+=(--device "$device")
args=("${dev[@]}"); [ -n "$steps" ] && args+=(--steps "$steps")
declare -A case_of=(
  [lab]="assets/cases/lab.toml"
  [10k-settled]="--from $out/settled-10k"
  [tile-10k]="--from $out/settled-10k --tile 1"
  [tile-100k]="--from $out/settled-10k --tile 10"
  [tile-1M]="--from $out/settled-10k --tile 100"
  [10k]="assets/cases/bench_100k.toml --set mill.length=0.305"
  [100k]="assets/cases/bench_100k.toml"
  [1M]="assets/cases/bench_100k.toml --set mill.length=30.5"
  [D]="assets/cases/mill_d.toml"
)
IFS=',' read -r -a rows <<< "$only"
for r in "${rows[@]}"; do
  [ -n "${case_of[$r]:-}" ] || {
    echo "bench.sh: no row '$r' (lab, 10k-settled, tile-10k, tile-100k, tile-1M, 10k, 100k, 1M, D)" >&2; exit 2; }
done
mkdir -p "$out"
for r in "${rows[@]}"; do
  echo "bench.sh: $r" >&2
  if [[ ( "$r" == 10k-settled || "$r" == tile-* ) && ! -f "$out/settled-10k/checkpoint.bin" ]]; then
    build/millcharge run assets/cases/bench_100k.toml --set mill.length=0.305 --set run.duration=0.05 \
      --set run.warmup=0 "${dev[@]}" --out "$out/settled-10k" --quiet > "$out/settled-10k.log"
  fi
  # shellcheck disable=SC2086
  build/millcharge bench ${case_of[$r]} "${args[@]}" > "$out/$r.json"
done
python3 - "$out" "${rows[@]}" <<'PY'
import json, sys
out, rows = sys.argv[1], sys.argv[2:]
print("| case | balls | device | precision | steps/s | particle-updates/s | its ten parts: slowest–fastest | without the energy books | books' cost (medians of parts) | contacts/ball | B/ball | binning | contacts | forces | motion | reductions |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    j = json.load(open(f"{out}/{r}.json"))
    s = j["stages"]
    p = j["part_updates_per_s"]
    dev = j['device'] + ("" if j.get('forces_kernel', 'ball') == 'ball' else f", {j['forces_kernel']} forces")
    off = j.get('books_off') or {}
    cost = j.get('books_cost') or {}
    off_rate = f"{off['particle_updates_per_s']:.3g}" if off else "–"
    cost_text = f"{100*cost['median_parts']:+.1f} %" if cost else "–"
    print(f"| {r} ({j['case']}) | {j['n_particles']:,} | {dev} | {j['precision']} | {j['steps_per_s']:.1f} | "
          f"{j['particle_updates_per_s']:.3g} | {p['min']:.3g}–{p['max']:.3g} | {off_rate} | {cost_text} | "
          f"{j['contacts_per_ball']:.2f} | {j['bytes_per_ball']:.0f} | "
          + " | ".join(f"{100*s[k]:.0f} %" for k in ("binning", "contacts", "forces", "motion", "reductions")) + " |")
PY
echo "bench.sh: JSON lines in $out" >&2
