#!/usr/bin/env bash
# Fuzzes the case reader (fuzz/fuzz_case_file.cpp) with libFuzzer, ASan and
# UBSan for a bounded time:
#   scripts/fuzz.sh [SECONDS]        (default 120)
# Builds build-fuzz with clang++ (MILLCHARGE_FUZZ=ON), seeds a working corpus
# in build-fuzz/corpus from assets/cases/*.toml, tests/data/bad_cases/* and
# fuzz/corpus/* (earlier findings and seeds with "#set" lines), then runs.
# A crash, a sanitizer report, an unexpected exception, a hang (-timeout) or a
# giant allocation (-malloc_limit_mb) is written to build-fuzz/findings/ and
# the script exits non-zero. Fix the bug, then copy the input into
# fuzz/corpus/ (and, as a case file with a "# expect:" line, into
# tests/data/bad_cases/) so it stays fixed.
# Environment: CXX (default clang++-14 or clang++), FUZZ_JOBS (default 1).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-120}
jobs=${FUZZ_JOBS:-1}
cxx=${CXX:-$(command -v clang++-14 || command -v clang++ || true)}
if [[ -z "$cxx" ]]; then
  echo "fuzz.sh: clang++ not found (apt-get install clang-14 libclang-rt-14-dev)" >&2
  exit 2
fi
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$cxx" \
  -DMILLCHARGE_FUZZ=ON -DMILLCHARGE_TESTS=OFF >/dev/null
cmake --build build-fuzz --target fuzz_case_file -j"$(nproc 2>/dev/null || echo 2)"

corpus=build-fuzz/corpus
findings=build-fuzz/findings
mkdir -p "$corpus" "$findings"
cp -n assets/cases/*.toml tests/data/bad_cases/* "$corpus"/ 2>/dev/null || true
cp -n fuzz/corpus/* "$corpus"/ 2>/dev/null || true

before=$(ls "$findings" | wc -l)
status=0
build-fuzz/fuzz_case_file "$corpus" -dict=fuzz/case.dict -max_total_time="$seconds" -timeout=10 \
  -rss_limit_mb=2048 -malloc_limit_mb=512 -max_len=8192 $([[ $jobs -gt 1 ]] && echo "-jobs=$jobs -workers=$jobs") \
  -artifact_prefix="$findings/" -print_final_stats=1 || status=$?
after=$(ls "$findings" | wc -l)
if [[ $status -ne 0 || $after -gt $before ]]; then
  echo "fuzz.sh: the fuzzer found a bug (exit $status); inputs in $findings/:" >&2
  ls -1 "$findings" >&2
  exit 1
fi
echo "fuzz.sh: no crash in ${seconds} s"
