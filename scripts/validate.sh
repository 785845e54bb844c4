#!/usr/bin/env bash
# Rebuilds docs/validation.md: millcharge against published and analytic
# values (../shared/reference/VERIFICATION.md), one row per check with the
# reference, millcharge's value, the error and pass/fail.
#
#   bash scripts/validate.sh [--device SPEC] [--liggghts DIR | --no-liggghts]
#                            [--only GROUP,...] [--out FILE]
#
# 1. sets up and builds (scripts/setup.sh, scripts/build.sh);
# 2. runs build/millcharge_validate, which runs the checks the tests assert
#    on (tests/checks.cpp) and prints one JSON line per row: Chung & Ooi
#    tests 1-4, sliding to rolling, a ball leaving a turning shell, the
#    elastic box's energy, the power balance of both laws, the lab mill
#    against Morrell's C-model and its power against speed. About 5-10
#    minutes on 2 CPU cores;
# 3. the same mill in LIGGGHTS: with --liggghts DIR, the results of an
#    earlier `scripts/liggghts_compare.sh --out DIR`; else, when `liggghts`
#    and `mpirun` are installed, runs that script (about 15 more minutes);
#    else (or with --no-liggghts) the row says why it was not run;
# 4. writes the table, with the command, the machine, the OpenCL device and
#    the date, to docs/validation.md (or --out FILE), replacing it only when
#    every check ran.
#
# --device SPEC runs the checks on another OpenCL device (as `millcharge
# devices` lists them; e.g. RUSTICL_ENABLE=llvmpipe ... --device rusticl).
# --only GROUP,... runs some groups (millcharge_validate --list names them);
# it needs --out, so that docs/validation.md is only ever a whole report.
# Exit status: 0 when every row passes, 3 when the report was written but a
# row fails, 1 when a check could not run (nothing written), 2 on bad
# arguments.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; }
die() { echo "validate.sh: $*" >&2; exit "${2:-1}"; }

device=""; liggghts_dir=""; no_liggghts=0; only=""; out="docs/validation.md"; out_given=0
args=("$@")
while [ $# -gt 0 ]; do
  case "$1" in
    --device) device="${2:?--device needs a spec, e.g. cpu or rusticl}"; shift 2 ;;
    --liggghts) liggghts_dir="${2:?--liggghts needs the --out folder of scripts/liggghts_compare.sh}"; shift 2 ;;
    --no-liggghts) no_liggghts=1; shift ;;
    --only) only="${2:?--only needs groups, e.g. chung-ooi,single}"; shift 2 ;;
    --out) out="${2:?--out needs a file}"; out_given=1; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) usage >&2; die "unknown argument '$1'" 2 ;;
  esac
done
[ -z "$only" ] || [ "$out_given" = 1 ] || die "--only writes a partial report: give --out FILE too (docs/validation.md is always a whole one)" 2
[ -z "$liggghts_dir" ] || [ -d "$liggghts_dir" ] || die "--liggghts $liggghts_dir: no such folder" 2

bash scripts/setup.sh >&2
bash scripts/build.sh >&2

work="runs/validate-$(date +%Y%m%d-%H%M%S)"
mkdir -p "$work"
validate_args=(); [ -z "$device" ] || validate_args+=(--device "$device"); [ -z "$only" ] || validate_args+=(--only "$only")
echo "validate.sh: running build/millcharge_validate ${validate_args[*]} (rows in $work/rows.jsonl)" >&2
status=0
./build/millcharge_validate "${validate_args[@]}" > "$work/rows.jsonl" || status=$?
case "$status" in
  0|3) ;;
  *) die "millcharge_validate stopped with status $status before every check ran; nothing written (rows so far in $work/rows.jsonl)" ;;
esac

# ---- the same mill in LIGGGHTS ----
liggghts_note=""
if [ -n "$only" ]; then
  liggghts_note="skip"
elif [ -n "$liggghts_dir" ]; then
  :
elif [ "$no_liggghts" = 1 ]; then
  liggghts_note="not run (validate.sh --no-liggghts)"
elif command -v liggghts >/dev/null && command -v mpirun >/dev/null; then
  liggghts_dir="$work/liggghts"
  echo "validate.sh: LIGGGHTS is installed: scripts/liggghts_compare.sh --out $liggghts_dir (about 15 minutes)" >&2
  lc_args=(--no-install --out "$liggghts_dir"); [ -z "$device" ] || lc_args+=(--device "$device")
  bash scripts/liggghts_compare.sh "${lc_args[@]}" > "$work/liggghts.md" ||
    die "scripts/liggghts_compare.sh failed (see $liggghts_dir); nothing written"
else
  liggghts_note="not run: \`liggghts\` is not installed on this machine (Debian package \`liggghts\`; \`bash scripts/liggghts_compare.sh --out DIR\` installs it and runs the comparison, then \`bash scripts/validate.sh --liggghts DIR\` reports it)"
fi

machine="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) CPUs"
commit="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
git diff --quiet HEAD 2>/dev/null || commit="$commit with uncommitted changes"
command_line="bash scripts/validate.sh${args[*]:+ ${args[*]}}"

mkdir -p "$(dirname "$out")"
tmp="$(mktemp "$out.XXXXXX")"
trap 'rm -f "$tmp"' EXIT
python3 scripts/validation_report.py --rows "$work/rows.jsonl" --command "$command_line" \
  --machine "$machine" --date "$(date -u +%Y-%m-%d)" --commit "$commit" \
  ${liggghts_dir:+--liggghts "$liggghts_dir"} ${liggghts_note:+--liggghts-note "$liggghts_note"} > "$tmp" ||
  die "could not write the report; nothing written"
mv "$tmp" "$out"
trap - EXIT
failed=$(grep -c '| \*\*FAIL\*\* |$' "$out" || true)
if [ "$failed" != 0 ]; then
  echo "validate.sh: wrote $out; $failed row(s) FAIL" >&2
  exit 3
fi
echo "validate.sh: wrote $out; every row passes" >&2
