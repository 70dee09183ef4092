#!/usr/bin/env bash
# What a session lent a real GPU runs for issues 33 and 34, in one call,
# from target/device.tar.xz (benches/device_pack.sh). In the order of what
# matters most, each step only while time is left (DEADLINE seconds, 420
# by default, from the start):
#   1. the first frame on a fresh machine (the driver compiles every
#      pipeline), then with lmanim's pipeline cache alone, then with both
#      caches, and whether the three frames are the same bits;
#   2. the city fly-through at 1280x720, LMM1 against Whitted, with
#      `--stats` (waits, bytes, stages and each pass's GPU time per frame:
#      issue 33's steady frame), and LMM1 with the trees still;
#   3. the 64-lamp bench at 1080p on the GPU backend (cold and fly-through
#      frames, Whitted against LMM1's penumbrae);
#   4. the GPU tests, which must give the CPU's bits there too;
#   5. the bench again with every segment traced (no shafts).
# Everything it prints and the stats files land in $OUT (the device
# tool's folder) or /tmp/device-check.
# WIDTH, HEIGHT, FRAMES and BENCH_HEIGHT (0 skips the bench) make it a
# smaller run, to try the script on a software adapter first.
#
# Vulkan on the lent images: some had the NVIDIA ICD but no loader, or an
# ICD naming libGLX_nvidia without glvnd beside it, which refuses
# vkCreateInstance (BENCHMARKS.md, "GPU start-up"). Where the machine
# lacks either, the packed Debian packages of both are unpacked into /
# (the device runs as root; on 2026-11-30's H200 that made the ICD work),
# and the ICD files are tried in turn until one gives lmanim an adapter.
set -uo pipefail
cd "$(dirname "$0")/.."
started=$SECONDS
deadline=${DEADLINE:-420}
out=${OUT:-/tmp/device-check}
width=${WIDTH:-1280} height=${HEIGHT:-720} frames=${FRAMES:-0..9}
bench_height=${BENCH_HEIGHT:-1080}
mkdir -p "$out"
exec > >(tee "$out/device_check.log") 2>&1
# The log itself, for what a step's filter would drop.
exec 3>&1
tar -C target -xJf target/device.tar.xz
bin=$PWD/target/device
if ! ldconfig -p | grep -q 'libvulkan.so.1 ' || ! ldconfig -p | grep -q 'libGLdispatch.so.0 '; then
  for deb in "$bin"/debs/*.deb; do dpkg -x "$deb" /; done
  ldconfig
fi
# The tests find the repository's files, and the command-line tests
# lmanim, where they were built.
built=/work/main
if [ ! -e "$built/animations" ]; then
  mkdir -p "$(dirname "$built")" && ln -sfn "$PWD" "$built"
fi
if [ ! -e "$built/target/release/lmanim" ]; then
  mkdir -p "$built/target/release" && cp "$bin/lmanim" "$built/target/release/"
fi
if command -v nvidia-smi >/dev/null; then nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; fi

left() { echo $((deadline - (SECONDS - started))); }
# Runs the rest of its line under a timeout of at most $1 seconds and the
# time left; skips it (saying so) when under 20 s are left.
budget() {
  local most=$1 time_left
  shift
  time_left=$(left)
  if [ "$time_left" -lt 20 ]; then echo "skipped for time: $*" >&3; return 1; fi
  timeout $((most < time_left ? most : time_left)) "$@"
}

work=$(mktemp -d)
lmanim=$bin/lmanim
first_frame_runner() { budget 180 "$@"; }
source benches/first_frame.sh

echo "== 1. first frame (courtyard, LMM1, 160x90)"
egl_icd=$work/nvidia_egl_icd.json
echo '{"file_format_version":"1.0.1","ICD":{"library_path":"libEGL_nvidia.so.0","api_version":"1.3"}}' >"$egl_icd"
found=
for icd in "" /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json "$egl_icd"; do
  [ -n "$icd" ] && [ ! -e "$icd" ] && continue
  if [ -n "$icd" ]; then
    export VK_ICD_FILENAMES=$icd VK_DRIVER_FILES=$icd
    echo "ICD file: $icd"
  fi
  empty_driver_cache
  rm -rf "$work/lmanim-cache-lmm1"
  if first_frame no-cache lmm1 && grep -q '"adapter"' "$work/no-cache.json" 2>/dev/null \
    || [ -e "$work/no-cache.0000.exr" ]; then
    found=yes
    break
  fi
done
[ -n "$found" ] || { echo "no GPU adapter: stopping"; exit 1; }
empty_driver_cache
first_frame lmanim-cache lmm1
first_frame both-caches lmm1
for run in lmanim-cache both-caches; do
  cmp -s "$work/no-cache.0000.exr" "$work/$run.0000.exr" &&
    echo "$run: the same bits" || echo "$run: BITS DIFFER"
done

# One city run: its name, the scene, the method; per-frame figures from
# its `--stats`.
city() {
  budget 120 "$bin/lmanim" "$2" --backend gpu --method "$3" \
    --frames "$frames" --width "$width" --height "$height" --no-cache --quiet \
    --stats "$out/$1.json" --out "$work/$1.####.exr" || return
  python3 - "$out/$1.json" "$1" <<'PY'
import json, sys
for f in json.load(open(sys.argv[1]))["frames"]:
    g = f["gpu"]
    stages = " ".join(f"{k} {v * 1e3:.1f}" for k, v in sorted(f["stages"].items()))
    print(f'{sys.argv[2]} frame {f["frame"]}: {f["seconds"] * 1e3:.1f} ms ({stages} ms), '
          f'waits {g["waits"]} ({g["wait_seconds"] * 1e3:.1f} ms), up {g["bytes_up"] / 1e6:.1f} MB, down {g["bytes_down"] / 1e6:.1f} MB, '
          f'segments {g["segments_traced"]}')
    passes = sorted(g.get("pass_seconds", {}).items(), key=lambda kv: -kv[1])
    if passes:
        print("  on the GPU: " + ", ".join(f"{name} {seconds * 1e3:.2f}" for name, seconds in passes) + " ms")
PY
}

echo "== 2. city fly-through, ${width}x$height, frames $frames"
city city-lmm1 animations/city.gltf lmm1
city city-whitted animations/city.gltf whitted
# The city without its swaying trees: what the crowns' walks cost a
# steady frame (BENCHMARKS.md, "A steady city frame's fill is the wind's").
python3 - "$work/city-still-trees.gltf" <<'PY'
import json, sys
scene = json.load(open("animations/city.gltf"))
scene["animations"] = [a for a in scene["animations"] if a.get("name") != "Wind"]
json.dump(scene, open(sys.argv[1], "w"))
PY
city city-still-trees-lmm1 "$work/city-still-trees.gltf" lmm1

bench() {
  echo "== $1. 64 lamps, ${bench_height}p, GPU backend, the fill's shafts: $2"
  LMANIM_BENCH_BACKEND=gpu LMANIM_BENCH_LAMPS=64 LMANIM_BENCH_HEIGHT=$bench_height \
    LMANIM_BENCH_SHAFTS=$2 budget 200 "$bin/bench_lmm" --bench
}
[ "$bench_height" != 0 ] && bench 3 test

echo "== 4. GPU tests (the CPU's bits; failures and totals; each whole log in $out)"
for test in gpu_backend sequence_reuse reuse_property gpu_traffic; do
  budget 150 "$bin/$test" --test-threads 8 >"$out/test-$test.log" 2>&1
  grep -E '^test |test result|panicked|left:|right:' "$out/test-$test.log" | grep -v ' ok$'
done

[ "$bench_height" != 0 ] && bench 5 skip
echo "== done in $((SECONDS - started)) s"
