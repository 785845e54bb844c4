#!/usr/bin/env bash
# A periodic slice against a whole mill five times as long
# (docs/cases.md, "Periodic slices"): the lab mill's cross-section, charge,
# law and speed, a softer contact to keep the runs short, both turned for
# the same time and averaged over the same whole revolutions. Prints the
# power per metre of each, their difference, and the share the whole
# mill's end plates take of its power.
#
#   bash scripts/slice_validation.sh [OUT_DIR] [--set KEY=VALUE]...
#
# OUT_DIR (default runs/slice_validation) gets the two run folders, slice/
# and whole/. Extra --set options go to both runs. About 10 minutes on 2
# CPU cores. Exit status 0 when the slice's power per metre is within 3 %
# of the whole mill's, 3 when not, 1 when a run failed.
set -euo pipefail
cd "$(dirname "$0")/.."

out="runs/slice_validation"
if [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; then out="$1"; shift; fi
bin="${MILLCHARGE:-build/millcharge}"
slice_m="${SLICE_M:-0.12}"   # 4.7 largest balls (25.4 mm), above the 4 a slice needs
whole_m="${WHOLE_M:-0.6}"    # 5 slices
common=(--set contact.stiffness=2e5 --set run.steps_per_contact=10 --set run.duration=7.5
        --set run.warmup=2.0 --set run.snapshot_interval=0 --set run.checkpoint_interval=0 --force --quiet "$@")

mkdir -p "$out"
"$bin" run assets/cases/lab.toml --set mill.ends=periodic --set "mill.length=$slice_m" "${common[@]}" \
  --out "$out/slice" > "$out/slice.log"
"$bin" run assets/cases/lab.toml --set "mill.length=$whole_m" "${common[@]}" --out "$out/whole" > "$out/whole.log"

python3 - "$out" <<'EOF'
import json, sys
out = sys.argv[1]
s = json.load(open(f"{out}/slice/summary.json"))
w = json.load(open(f"{out}/whole/summary.json"))
def per_m(r, k): return r["power_per_metre_W"][k]
print(f"{'':28s} {'slice':>12s} {'whole':>12s}")
for k in ("n_particles", "length_m"):
    print(f"{k:28s} {s[k]:12.4g} {w[k]:12.4g}")
print(f"{'revolutions averaged':28s} {s['average']['revolutions']:12.3f} {w['average']['revolutions']:12.3f}")
for k in ("torque", "dissipation"):
    print(f"{'power per metre, ' + k + ' (W/m)':28s} {per_m(s, k):12.5g} {per_m(w, k):12.5g}")
diff = per_m(s, "torque") / per_m(w, "torque") - 1
print(f"slice against whole, torque power per metre: {100 * diff:+.2f} %")
parts = {p["part"]: p for p in w["liner"]["parts"]}
plates = parts["end plates"]["impact_power_W"] + parts["end plates"]["shear_power_W"]
walls = w["liner"]["impact_power_W"] + w["liner"]["shear_power_W"]
print(f"whole mill's end plates: {plates:.4g} W of impact and shear, {100 * plates / w['power_W']['torque']:.2f} % "
      f"of its power draw, {100 * plates / walls:.1f} % of what the liner takes")
# The end plates' effect on the draw: the whole mill less the slice's power
# per metre over its length.
ends = w["power_W"]["torque"] - per_m(s, "torque") * w["length_m"]
print(f"whole mill's draw beyond the slice's per metre (the ends' effect): {ends:+.4g} W, "
      f"{100 * ends / w['power_W']['torque']:+.2f} %")
sys.exit(0 if abs(diff) <= 0.03 else 3)
EOF
