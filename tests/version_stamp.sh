#!/bin/bash
# The build's stamp: `millcharge --version` names the commit the source tree
# is at (git describe), and outside a clone cmake/version.cmake writes
# "unknown".
#   version_stamp.sh MILLCHARGE_BINARY SOURCE_DIR
set -euo pipefail
mc=$1
src=$2
said=$("$mc" --version)
if git -C "$src" rev-parse --git-dir > /dev/null 2>&1; then
  want=$(git -C "$src" describe --always --dirty --abbrev=7)
  # The tree may have changed since the build (a file edited): compare the
  # commit, not the dirty mark.
  case "$said" in
    "millcharge "*" (commit ${want%-dirty}"*")") ;;
    *) echo "version_stamp.sh: --version says '$said', the tree is at $want"; exit 1 ;;
  esac
else
  case "$said" in "millcharge "*" (commit unknown)") ;; *) echo "version_stamp.sh: '$said' outside a clone"; exit 1 ;; esac
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake -DSRC="$work" -DOUT="$work/v.h" -P "$src/cmake/version.cmake"
grep -q '#define MC_BUILD_COMMIT "unknown"' "$work/v.h" || { echo "version_stamp.sh: outside a clone: $(cat "$work/v.h")"; exit 1; }
echo "version_stamp.sh: $said; outside a clone: unknown"
