#!/usr/bin/env bash
# The faint lamps' study (STUDY.md, "Faint lamps"): the street, the one
# study scene with more than one lamp, by LMM1 with `penumbra: wide` at
# lightmesh.faint_lamps 0 (every lamp's penumbra sized), 1/32, 1/16 (the
# default) and 1/8, each against one area reference. The single-lamp
# scenes never have a faint lamp (tests/frame_hashes.rs holds their
# bits). Run from the repository root after `cargo build --release`;
# writes under ./study-faint.
set -euo pipefail
lmanim=$(realpath target/release/lmanim)
animations=$(realpath animations)
mkdir -p study-faint && cd study-faint
reference=""
for share in 0 0.03125 0.0625 0.125; do
  dir=$PWD/street-$share
  mkdir -p "$dir"
  cp "$animations/study-street.gltf" "$dir/"
  printf '(\n    lightmesh: (penumbra: wide, faint_lamps: %s),\n)\n' "$share" >"$dir/study-street.ron"
  against=()
  [ -n "$reference" ] && against=(--reference "$reference")
  "$lmanim" study "$dir/study-street.gltf" --width 320 --height 180 --methods whitted,lmm1 \
      "${against[@]}" --out "$dir/out" --quiet
  reference=${reference:-$dir/out/reference.exr}
  cp "$dir/out/study.csv" "$PWD/street-$share.csv"
done
