#!/bin/bash
# Packs, on the Debian build machine, what a GPU machine without this
# project's packages needs to run millcharge's tests and benchmark there:
# the programs (millcharge, the law probe, the validation checks, the
# tests) and the shared
# libraries they load that are not glibc's or the compiler's own (the
# OpenCL ICD loader above all, plus GLFW, GLEW, the GL dispatch and X
# client libraries the viewer code links), and clinfo.
#
#   bash scripts/gpu_kit.sh          # writes gpu-kit/ (git-ignored), ~5 MB
#
# Then, on the GPU machine, from a copy of this repository with gpu-kit/
# beside its other files: bash scripts/gpu_session.sh (see there). The
# programs need glibc 2.35 and libstdc++ of GCC 11 or later there (Ubuntu
# 22.04, Debian 12 or newer); they keep this build's paths (kernels,
# assets), which gpu_session.sh links to the copy.
set -euo pipefail
cd "$(dirname "$0")/.."

[ -x build/millcharge ] && [ -x build/millcharge_law_probe ] && [ -x build/millcharge_validate ] &&
  [ -x build/tests/millcharge_tests ] || bash scripts/build.sh
command -v clinfo > /dev/null || bash scripts/setup.sh

kit=gpu-kit
rm -rf "$kit"
mkdir -p "$kit/bin" "$kit/lib"
cp build/millcharge build/millcharge_law_probe build/millcharge_validate build/tests/millcharge_tests "$kit/bin/"
cp "$(command -v clinfo)" "$kit/bin/"
progs=(build/millcharge build/millcharge_law_probe build/millcharge_validate build/tests/millcharge_tests "$(command -v clinfo)")
n=0
for f in $(ldd "${progs[@]}" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u); do
  case "$(basename "$f")" in
    # glibc, the dynamic loader and the compiler's runtime come from the
    # machine: a libc of another build than its loader fails.
    libc.so.* | libm.so.* | libdl.so.* | libpthread.so.* | librt.so.* | ld-linux* | libstdc++.so.* | libgcc_s.so.*) continue ;;
  esac
  cp -L "$f" "$kit/lib/"
  n=$((n + 1))
done
# The build's source root, which its compiled-in paths name.
pwd > "$kit/build-root"
git rev-parse --short HEAD > "$kit/commit" 2> /dev/null || true
build/millcharge --version > "$kit/version"  # the commit the programs were built from (dirty if edited)
echo "gpu_kit.sh: $kit/ holds millcharge, millcharge_law_probe, millcharge_validate, millcharge_tests, clinfo and $n libraries ($(du -sh "$kit" | cut -f1)), built in $(cat "$kit/build-root") at $(cat "$kit/commit" 2> /dev/null || echo '?')"
