#!/bin/bash
# Registers, stack and spills of each kernel of an NVIDIA program binary
# (the PTX text that MILLCHARGE_PROGRAM_DUMP writes, docs/gpu.md), from
# the CUDA toolkit's ptxas, with the fused multiply-adds each kernel holds
# (none while the kernels keep FP_CONTRACT OFF and call no fma()):
#
#   bash scripts/ptx_report.sh program-float.ptx [sm_90]
#
# Runs wherever ptxas is (the GPU machine, or the build machine on a PTX
# file the GPU session brought back). One line a kernel, then ptxas's own.
set -euo pipefail
ptx=${1:?usage: ptx_report.sh PROGRAM.ptx [sm_NN]}
sm=${2:-sm_90}
[ -f "$ptx" ] || { echo "ptx_report.sh: no file $ptx" >&2; exit 2; }
ptxas_bin=$(command -v ptxas || ls /usr/local/cuda/bin/ptxas 2> /dev/null || true)
[ -n "$ptxas_bin" ] || { echo "ptx_report.sh: no ptxas here (the CUDA toolkit's); run it where one is" >&2; exit 2; }
raw=$(mktemp)
trap 'rm -f "$raw"' EXIT
"$ptxas_bin" -v --gpu-name "$sm" "$ptx" -o /dev/null > "$raw" 2>&1 || { cat "$raw" >&2; exit 1; }
echo "# $ptx on $sm ($("$ptxas_bin" --version | tail -1))"
echo "# kernel registers stack_bytes spill_store_bytes spill_load_bytes fma_in_ptx"
awk -v ptx="$ptx" '
  BEGIN {
    while ((getline line < ptx) > 0) {
      if (line ~ /\.entry /) { k = line; sub(/.*\.entry[ \t]+/, "", k); sub(/\(.*/, "", k) }
      else if (k != "" && line ~ /fma\.rn\.f(32|64)/) fma[k]++
    }
  }
  /Function properties for/ { k = $NF; next }
  /bytes stack frame/ { stack[k] = $1; st[k] = $5; ld[k] = $9; next }
  /Compiling entry function/ { e = $0; sub(/.*function .?/, "", e); sub(/.? for.*/, "", e); k = e; next }
  /Used [0-9]+ registers/ { for (i = 1; i <= NF; i++) if ($(i + 1) ~ /^registers/) reg[k] = $i; names[k] = 1 }
  END { for (n in names) printf "%s %s %s %s %s %d\n", n, reg[n], stack[n], st[n], ld[n], fma[n] }
' "$raw" | sort
echo "# ptxas -v:"
cat "$raw"
