#!/usr/bin/env bash
# Packs what a session lent a GPU machine runs (benches/device_check.sh):
# the release lmanim, the GPU test binaries and the light-mesh bench,
# stripped, with Debian's packages of the Vulkan loader and glvnd (the
# lent images have had neither), into target/device.tar.xz: about 16 MB,
# where the device tool carries at most 64 MiB. Run from the repository root on the build
# machine, then carry target/device.tar.xz and run
# `bash benches/device_check.sh` on the device.
set -euo pipefail
out=target/device
rm -rf "$out" && mkdir -p "$out"
cargo build --release --quiet
cp target/release/lmanim "$out/"

# The executable cargo built for target $2 of kind $1 (test, bench),
# from its JSON messages: not the last one named, which is lmanim itself
# when the build had to relink it for the tests.
executable() {
  local kind=$1 name=$2 profile=()
  # Benches build with the bench profile (release) already.
  [ "$kind" = test ] && profile=(--release)
  cargo "$kind" "${profile[@]}" --"$kind" "$name" --no-run --quiet --message-format=json |
    python3 -c 'import json, sys
kind, name = sys.argv[1:]
print(*[m["executable"] for m in map(json.loads, sys.stdin)
        if m.get("executable") and m["target"]["name"] == name and kind in m["target"]["kind"]])' \
      "$kind" "$name"
}
for test in gpu_backend gpu_traffic reuse_property sequence_reuse; do
  cp "$(executable test "$test")" "$out/$test"
done
cp "$(executable bench lmm)" "$out/bench_lmm"
strip "$out"/*
# The Vulkan loader and glvnd, which NVIDIA's ICD needs (its
# libGLX_nvidia refuses vkCreateInstance without libGLdispatch): the lent
# images have had neither (BENCHMARKS.md, "GPU start-up").
mkdir -p "$out/debs"
(cd "$out/debs" && apt-get download -q libvulkan1 libglvnd0 libegl1 libgl1 libglx0 libgles2 libopengl0 2>/dev/null)
tar -C target -cJf target/device.tar.xz device
ls -l target/device.tar.xz
