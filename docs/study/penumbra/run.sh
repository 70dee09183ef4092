#!/usr/bin/env bash
# The penumbra study (STUDY.md, "Penumbra width from the blocker"): the box
# at three lamp radii and the other three study scenes, each with kernel
# box/smooth and penumbra fixed/blocker/wide, Whitted and the LMM1 sweep, all
# variants of a scene against one area reference. Run from the repository
# root after `cargo build --release`; writes under ./study-penumbra.
set -euo pipefail
lmanim=$(realpath target/release/lmanim)
animations=$(realpath animations)
mkdir -p study-penumbra && cd study-penumbra
variants="box:fixed smooth:fixed box:blocker smooth:blocker box:wide smooth:wide"
study() { # name, scene, the settings' lamps line (or nothing)
  local name=$1 scene=$2 lamps=$3 reference=""
  for variant in $variants; do
    local kernel=${variant%%:*} penumbra=${variant##*:}
    local dir=$PWD/$name-$kernel-$penumbra
    mkdir -p "$dir"
    cp "$animations/$scene.gltf" "$dir/"
    printf '(\n%s    lightmesh: (kernel: %s, penumbra: %s),\n)\n' "$lamps" "$kernel" "$penumbra" >"$dir/$scene.ron"
    local against=()
    [ -n "$reference" ] && against=(--reference "$reference")
    "$lmanim" study "$dir/$scene.gltf" --width 320 --height 180 --methods whitted,lmm1 \
        "${against[@]}" --out "$dir/out" --quiet
    reference=${reference:-$dir/out/reference.exr}
    cp "$dir/out/study.csv" "$PWD/$name-$kernel-$penumbra.csv"
  done
}
for radius in 0.05 0.2 0.5; do
  study "box-$radius" study-box "    lamps: (radius: {\"Lamp\": $radius}),
"
done
for scene in leaves street wall; do study "$scene" "study-$scene" ""; done
