#!/bin/bash
# A machine without fonts (a headless server, a GPU image without
# fonts-dejavu): run, grind and sweep collect still draw their pictures, in
# the font built into the program. The fonts are hidden in a private mount
# namespace (root's `unshare -m`, a tmpfs over /usr/share/fonts); where that
# is not allowed the test says so and is skipped (exit 77). Each picture is
# decoded (millcharge_png_ink) and its title's box must hold ink, the top
# rows above it none.
#   no_font.sh MILLCHARGE_BINARY SOURCE_DIR PNG_INK_BINARY
set -euo pipefail
mc=$1
src=$2
ink=$3
if ! unshare -m --propagation private true 2> /dev/null; then
  echo "no_font.sh: cannot make a private mount namespace here (unshare -m needs root): skipped"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$src"
export MC=$mc WORK=$work INK=$ink
unshare -m --propagation private bash -euo pipefail -c '
  mount -t tmpfs none /usr/share/fonts
  if ls /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf > /dev/null 2>&1; then
    echo "no_font.sh: the font is still visible"; exit 1
  fi
  fail() { echo "no_font.sh: $*"; exit 1; }
  png() { [ "$(head -c 8 "$1" | od -An -tx1 | tr -d " \n")" = 89504e470d0a1a0a ] || fail "$1 is not a PNG"; }
  # titled FILE centre|left: text drawn in the title'"'"'s box (200 x 22 px about
  # the centre, or 250 x 24 px from x = 50 for the liner'"'"'s left-set panel
  # title; 720 to 1235 pixels of ink measured with the fonts), at least 300
  # pixels; none in the top 8 rows above it.
  titled() {
    png "$1"
    local w h n
    read -r w h n < <("$INK" "$1" 0 0 1 1) || fail "$1: cannot be decoded"
    if [ "$2" = centre ]; then read -r w h n < <("$INK" "$1" $((w / 2 - 100)) 10 $((w / 2 + 100)) 32) || fail "$1: cannot be decoded"
    else read -r w h n < <("$INK" "$1" 50 4 300 28) || fail "$1: cannot be decoded"; fi
    [ "$n" -ge 300 ] || fail "$1: $n pixels of ink in the title'"'"'s box: no text drawn"
    read -r w h n < <("$INK" "$1" 0 0 "$w" 8) || fail "$1: cannot be decoded"
    [ "$n" -eq 0 ] || fail "$1: $n pixels of ink in the top 8 rows, where nothing is drawn"
  }
  # A short run of the lab mill: every picture drawn, no warning.
  "$MC" run --set mill.length=0.04 --set run.settle=0.1 --set run.warmup=0.05 --set run.duration=0.2 \
    --set run.snapshot_interval=0 --quiet --out "$WORK/run" > "$WORK/run.log" 2>&1 || { cat "$WORK/run.log"; fail "run failed"; }
  for f in power charge spectra; do titled "$WORK/run/$f.png" centre; done
  titled "$WORK/run/liner.png" left
  ! grep -q "warning" "$WORK/run.log" || { cat "$WORK/run.log"; fail "run warned"; }
  # A MILLCHARGE_FONT that names a missing file: a warning, still the pictures.
  MILLCHARGE_FONT=/usr/share/fonts/none.ttf "$MC" grind "$WORK/run" --ore assets/ores/example_spectrum.toml \
    --time 1 --out "$WORK/grind" > "$WORK/grind.log" 2>&1 || { cat "$WORK/grind.log"; fail "grind failed"; }
  titled "$WORK/grind/grind.png" centre
  grep -q "warning: cannot read the plot font /usr/share/fonts/none.ttf" "$WORK/grind.log" ||
    { cat "$WORK/grind.log"; fail "no warning for the missing MILLCHARGE_FONT"; }
  echo "no_font.sh: run and grind drew every picture with no font on the machine"
'
