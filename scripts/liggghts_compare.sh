#!/usr/bin/env bash
# millcharge against LIGGGHTS 3.8 (Debian package `liggghts`) on the same mill
# on the same machine (issue 5): the benchmark mill of
# assets/cases/bench_100k.toml cut to 0.5 m (D 1.0 m, 16 lifters, 19-21 mm
# steel balls, J 0.30, 75 % of critical, Hertz with tangential history and
# rolling friction, dt 5 us, about 16,400 balls).
#
#   bash scripts/liggghts_compare.sh [--steps N] [--turn S] [--out DIR] [--ranks "1 2"]
#        [--repeat K] [--damping millcharge|liggghts] [--device SPEC] [--double]
#        [--millcharge BIN] [--reuse] [--no-install] [--busy-flag FILE] [--wait-for FILE]
#
# 1. installs liggghts (and the MPI launcher it depends on) if missing;
# 2. writes the mill for LIGGGHTS (scripts/liggghts/make_mill.py: STL of the
#    shell with its lifters and of the end plates, the balls packed as
#    millcharge packs them, the parameters);
# 3. LIGGGHTS warm-up, once, on the largest rank count: the charge settles
#    with the mill at rest (until its rms speed is below 0.01 sqrt(g D), as
#    millcharge's settle = "auto"), the mill turns --turn seconds; checks that
#    the charge lies in the mill (no ball lost, centre of mass below and to the
#    right of the axis, average coordination > 1); writes a restart;
# 4. millcharge on the same mill: `millcharge run` (settle auto, turn --turn
#    seconds), in float and, with --double, once more in double;
# 5. times --steps steps from each warm-up, --repeat times in turn (the
#    machine's speed drifts): LIGGGHTS from the restart on each rank count
#    (mpirun -np P), particle-updates/s = balls x steps / loop time, from the
#    "Loop time of X on P procs for N steps with M atoms" line; millcharge
#    `bench --from` its run;
# 6. prints a Markdown table (the median of the repeats, and their range)
#    and the state of both charges, with the power each drew over the turn
#    (LIGGGHTS: the torque on its meshes; millcharge: summary.json); logs
#    and JSON stay in --out. scripts/validate.sh reads the same folder.
#
# Defaults: --steps 10000 (0.05 s), --turn 0.25 s, --ranks "1 2", --repeat 1,
# --damping millcharge (LIGGGHTS gets the restitution whose damping
# coefficient is millcharge's calibrated one: both codes then use the same
# gamma_n and gamma_t; `liggghts` passes e = 0.4 as is), --out
# runs/liggghts-compare-DATE, --millcharge build/millcharge (another build,
# e.g. of a clean checkout, may be given). About 12-15 minutes on 2 cores,
# 3 more with --double, about 1.5 more for each further repeat.
# --reuse (with --out of an earlier call) keeps its two warm-ups and only
# times again (a minute or two).
# --busy-flag FILE is created while a heavy run goes on and removed after;
# before each, the script waits (up to 15 minutes) while --wait-for FILE
# exists: for sharing a machine with someone else's benchmarks.
# Relative paths are taken from the repository root.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; }
die() { echo "liggghts_compare.sh: $*" >&2; exit 1; }

steps=10000; turn=0.25; out=""; ranks="1 2"; damping=millcharge; device=""; double=0; install=1; repeat=1
busy_flag=""; wait_for=""; mc=build/millcharge; reuse=0
while [ $# -gt 0 ]; do
  case "$1" in
    --steps) steps="${2:?--steps needs a number}"; shift 2 ;;
    --turn) turn="${2:?--turn needs seconds}"; shift 2 ;;
    --out) out="${2:?--out needs a folder}"; shift 2 ;;
    --ranks) ranks="${2:?--ranks needs a list like \"1 2\"}"; shift 2 ;;
    --damping) damping="${2:?--damping needs millcharge or liggghts}"; shift 2 ;;
    --device) device="${2:?--device needs a spec}"; shift 2 ;;
    --double) double=1; shift ;;
    --repeat) repeat="${2:?--repeat needs a number}"; shift 2 ;;
    --no-install) install=0; shift ;;
    --reuse) reuse=1; shift ;;
    --millcharge) mc="${2:?--millcharge needs the path of a millcharge binary}"; shift 2 ;;
    --busy-flag) busy_flag="${2:?--busy-flag needs a file}"; shift 2 ;;
    --wait-for) wait_for="${2:?--wait-for needs a file}"; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) usage >&2; die "unknown argument '$1'" ;;
  esac
done
[[ "$steps" =~ ^[1-9][0-9]*$ ]] || die "--steps must be a positive whole number (got '$steps')"
[[ "$repeat" =~ ^[1-9][0-9]*$ ]] || die "--repeat must be a positive whole number (got '$repeat')"
[[ "$turn" =~ ^[0-9]*\.?[0-9]+$ ]] || die "--turn must be seconds, e.g. 0.25 (got '$turn')"
for p in $ranks; do [[ "$p" =~ ^[1-9][0-9]*$ ]] || die "--ranks must list positive whole numbers (got '$ranks')"; done
[ -n "$ranks" ] || die "--ranks is empty"
case "$damping" in millcharge|liggghts) ;; *) die "--damping must be millcharge or liggghts (got '$damping')" ;; esac
[ -n "$out" ] || out="runs/liggghts-compare-$(date +%Y%m%d-%H%M%S)"
if [ "$reuse" = 1 ]; then
  { [ -f "$out/liggghts/turning.restart" ] && [ -d "$out/millcharge-run" ]; } ||
    die "--reuse needs --out of an earlier call, with liggghts/turning.restart and millcharge-run/ in it"
fi
mkdir -p "$out/liggghts"
out="$(cd "$out" && pwd)"
lg="$out/liggghts"
src="$(pwd)/scripts/liggghts"

# ---- 1. install ----
if ! command -v liggghts >/dev/null || ! command -v mpirun >/dev/null; then
  [ "$install" = 1 ] || die "liggghts or mpirun is missing (install the Debian package liggghts, or drop --no-install)"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || die "need root or sudo to install liggghts"
    sudo="sudo"
  fi
  echo "liggghts_compare.sh: installing liggghts" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends liggghts openmpi-bin
  { command -v liggghts && command -v mpirun; } >/dev/null || die "liggghts or mpirun still missing after apt-get install"
fi
command -v python3 >/dev/null || die "python3 is missing (bash scripts/setup.sh installs it)"
[ -x "$mc" ] || die "$mc is missing: run bash scripts/build.sh first (or give --millcharge BIN)"

ncpu=$(nproc)
{
  echo "date: $(date -Is)"
  echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $ncpu CPUs"
  echo "liggghts: $(dpkg-query -W -f='${Version}' liggghts 2>/dev/null || echo '?'), $(mpirun --version 2>/dev/null | head -1)"
  echo "millcharge binary: $mc; this checkout at $(git rev-parse --short HEAD 2>/dev/null || echo '?')$(git diff --quiet HEAD 2>/dev/null || echo ' with uncommitted changes')"
} > "$out/info.txt"
mpi=(mpirun)
[ "$(id -u)" -eq 0 ] && mpi+=(--allow-run-as-root)
maxr=1; for p in $ranks; do [ "$p" -gt "$maxr" ] && maxr=$p; done
[ "$maxr" -gt "$ncpu" ] && mpi+=(--oversubscribe)

busy_on() {
  if [ -n "$wait_for" ]; then
    local waited=0
    while [ -e "$wait_for" ] && [ $waited -lt 900 ]; do
      [ $waited -eq 0 ] && echo "liggghts_compare.sh: waiting while $wait_for exists" >&2
      sleep 20; waited=$((waited + 20))
    done
  fi
  [ -z "$busy_flag" ] || touch "$busy_flag"
}
busy_off() { [ -z "$busy_flag" ] || rm -f "$busy_flag"; }
trap busy_off EXIT
load() { cut -d' ' -f1 /proc/loadavg; }

# ---- 2. the mill ----
balls=$("$mc" check assets/cases/bench_100k.toml --set mill.length=0.5 |
        sed -n 's/.*requested: \([0-9,]*\) balls.*/\1/p' | tr -d ,)
[ -n "$balls" ] || die "could not read the ball count from 'millcharge check'"
if [ "$reuse" = 0 ]; then
  python3 "$src/make_mill.py" --out "$lg" --balls "$balls" --damping "$damping" | tee "$lg/make_mill.txt" >&2
  dt=$(sed -n 's/^variable dt *equal //p' "$lg/params.in")
  turn_steps=$(python3 -c "print(max(1, round($turn / $dt)))")

  # ---- 3. LIGGGHTS warm-up ----
  echo "liggghts_compare.sh: LIGGGHTS warm-up on $maxr rank(s): settle, then turn $turn s ($turn_steps steps)" >&2
  busy_on
  t0=$(date +%s)
  (cd "$lg" && "${mpi[@]}" -np "$maxr" liggghts -in "$src/in.mill_warmup" -var dir "$lg" -var src "$src" \
     -var turn_steps "$turn_steps" -log "$lg/log.warmup" > "$lg/warmup.out" 2>&1) ||
    die "the LIGGGHTS warm-up failed; see $lg/warmup.out"
  busy_off
  echo "liggghts_compare.sh: warm-up took $(( $(date +%s) - t0 )) s" >&2
fi
settled=$(grep '^SETTLED' "$lg/warmup.out" | tail -1)
turned=$(grep '^TURNED' "$lg/warmup.out" | tail -1)
[ -n "$turned" ] || die "the LIGGGHTS warm-up printed no TURNED line; see $lg/warmup.out"
echo "liggghts_compare.sh: $settled" >&2
echo "liggghts_compare.sh: $turned" >&2
python3 - "$turned" "$balls" <<'PY' || die "the LIGGGHTS charge is not a charge lying in the mill (see $lg/warmup.out); not timing it"
import sys
f = sys.argv[1].split()
v = {f[i]: float(f[i + 1]) for i in range(1, len(f) - 1, 2)}
n = int(sys.argv[2])
bad = []
if int(v["atoms"]) != n: bad.append(f"{int(v['atoms'])} of {n} balls left")
if not v["com_y"] < -0.2: bad.append(f"centre of mass y {v['com_y']:.3f} m is not in the lower part")
if not v["com_x"] > 0.01: bad.append(f"centre of mass x {v['com_x']:.4f} m: the charge was not dragged up the rising side")
if not v["contacts/ball"] > 1.0: bad.append(f"average coordination {v['contacts/ball']:.2f} is not above 1")
if bad:
    print("liggghts_compare.sh: " + "; ".join(bad), file=sys.stderr)
    sys.exit(1)
PY

# ---- 4. millcharge warm-ups ----
dev=(); [ -z "$device" ] || dev=(--device "$device")
precisions=(float); [ "$double" = 1 ] && precisions+=(double)
for prec in "${precisions[@]}"; do
  run_dir="$out/millcharge-run"; [ "$prec" = float ] || run_dir="$out/millcharge-run-$prec"
  if [ "$reuse" = 1 ] && [ -f "$run_dir/summary.json" ]; then continue; fi
  echo "liggghts_compare.sh: millcharge run ($prec): settle, then turn $turn s" >&2
  busy_on
  t0=$(date +%s)
  "$mc" run assets/cases/bench_100k.toml --set mill.length=0.5 --set run.duration="$turn" \
    --set run.warmup=0 --precision "$prec" "${dev[@]}" --out "$run_dir" --force --quiet > "$run_dir.log" 2>&1 ||
    die "millcharge run ($prec) failed; see $run_dir.log"
  busy_off
  echo "liggghts_compare.sh: millcharge run ($prec) took $(( $(date +%s) - t0 )) s" >&2
done

# ---- 5. timed steps ----
thermo_every=$(( steps / 2 )); [ "$thermo_every" -ge 1 ] || thermo_every=1
rm -f "$lg"/timed.*.out "$lg"/log.timed.* "$out"/millcharge-bench-*.json "$out"/millcharge-bench-*.log
for ((k = 1; k <= repeat; k++)); do
  for p in $ranks; do
    echo "liggghts_compare.sh: [$k/$repeat] LIGGGHTS, $p rank(s), $steps steps (load before: $(load))" >&2
    busy_on
    (cd "$lg" && "${mpi[@]}" -np "$p" liggghts -in "$src/in.mill_timed" -var dir "$lg" -var src "$src" \
       -var steps "$steps" -var thermo_every "$thermo_every" -log "$lg/log.timed.$p.$k" > "$lg/timed.$p.$k.out" 2>&1) ||
      die "the timed LIGGGHTS run on $p rank(s) failed; see $lg/timed.$p.$k.out"
    busy_off
  done
  for prec in "${precisions[@]}"; do
    run_dir="$out/millcharge-run"; [ "$prec" = float ] || run_dir="$out/millcharge-run-$prec"
    echo "liggghts_compare.sh: [$k/$repeat] millcharge bench --from, $steps steps, $prec (load before: $(load))" >&2
    busy_on
    "$mc" bench --from "$run_dir" --steps "$steps" --precision "$prec" "${dev[@]}" --quiet \
      > "$out/millcharge-bench-$prec.$k.json" 2> "$out/millcharge-bench-$prec.$k.log" ||
      die "millcharge bench ($prec) failed; see $out/millcharge-bench-$prec.$k.log"
    busy_off
  done
done

# ---- 6. table ----
python3 - "$out" "$repeat" "$ranks" "${precisions[@]}" <<'PY'
import csv, json, math, re, statistics, sys
out, repeat, ranks, precs = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4:]
rows = []
def row(code, par, balls, n, walls, cns):
    w = statistics.median(walls)
    ups = [balls * n / x for x in walls]
    spread = f" ({min(ups):.3g}-{max(ups):.3g})" if len(ups) > 1 else ""
    rows.append((code, par, balls, n, w, f"{balls * n / w:.3g}{spread}", statistics.median(cns)))
for p in ranks:
    walls, cns = [], []
    for k in range(1, repeat + 1):
        name = f"{out}/liggghts/timed.{p}.{k}.out"
        text = open(name).read()
        m = re.search(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text)
        if not m:
            sys.exit(f"liggghts_compare.sh: no 'Loop time' line in {name}")
        procs, n, atoms = int(m.group(2)), int(m.group(3)), int(m.group(4))
        walls.append(float(m.group(1)))
        end = re.search(r"TIMED_END atoms (\d+) com_x (\S+) com_y (\S+) contacts/ball (\S+)", text)
        if not end or int(end.group(1)) != atoms:
            sys.exit(f"liggghts_compare.sh: {name}: balls were lost, or no TIMED_END line")
        cns.append(float(end.group(4)))
    row("LIGGGHTS 3.8 (double)", f"{procs} MPI rank{'s' if procs > 1 else ''}", atoms, n, walls, cns)
for prec in precs:
    js = [json.load(open(f"{out}/millcharge-bench-{prec}.{k}.json")) for k in range(1, repeat + 1)]
    j = js[0]
    row(f"millcharge ({j['precision']})", f"{j['device_type'].upper()} ({j['platform']}), {j['compute_units']} compute units",
        j["n_particles"], j["steps"],
        [x["wall_s"] for x in js], [x["contacts_per_ball"] for x in js])
med = " (median of %d)" % repeat if repeat > 1 else ""
print(f"| code | ranks / threads | balls | steps | wall s{med} | particle-updates/s{med} | contacts per ball |")
print("|---|---|---|---|---|---|---|")
for code, par, balls, n, wall, ups, cn in rows:
    print(f"| {code} | {par} | {balls:,} | {n:,} | {wall:.2f} | {ups} | {cn:.2f} |")

# The charge each code timed: settle time, then at the end of the turn.
def fields(line):
    f = line.split()
    return {f[i]: float(f[i + 1]) for i in range(1, len(f) - 1, 2)}
warm = open(f"{out}/liggghts/warmup.out").read().splitlines()
st = fields([l for l in warm if l.startswith("SETTLED")][-1])
tu = fields([l for l in warm if l.startswith("TURNED")][-1])
lg_turn = tu["time"] - st["time"]
summ = json.load(open(f"{out}/millcharge-run/summary.json"))
last = list(csv.DictReader(open(f"{out}/millcharge-run/timeseries.csv")))[-1]
mc_vrms = math.sqrt(2 * float(last["kinetic_J"]) / summ["charge_mass_kg"])
print()
print("| code | settled after (s) | turned (s) | rms speed (m/s) | centre of mass angle (deg) | power over the turn (W) |")
print("|---|---|---|---|---|---|")
rest = float(re.search(r"variable rest_speed +equal (\S+)", open(f"{out}/liggghts/params.in").read()).group(1))
lg_note = "" if st["vrms"] < rest else " (not settled)"
mc_note = "" if summ["settled"] else " (not settled)"
lg_power = f"{tu['power_W']:.1f}" if "power_W" in tu else "not measured"
print(f"| LIGGGHTS | {st['time']:.2f}{lg_note} | {lg_turn:.2f} | {tu['vrms']:.2f} | "
      f"{math.degrees(math.atan2(tu['com_y'], tu['com_x'])) % 360:.1f} | {lg_power} |")
print(f"| millcharge | {summ['settle_s']:.2f}{mc_note} | {summ['turning_s']:.2f} | {mc_vrms:.2f} | "
      f"{float(last['com_angle_deg']) % 360:.1f} | {summ['power_W']['torque']:.1f} |")
PY
echo "liggghts_compare.sh: logs in $out" >&2
