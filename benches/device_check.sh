#!/usr/bin/env bash
# What a session lent a real GPU runs for issues 33 and 34, in one call
# (about 8 minutes on an H100), from target/device.tar.xz
# (benches/device_pack.sh): the GPU tests, which must give the CPU's bits
# there too; the city fly-through at 1280x720, LMM1 against Whitted, with
# `--stats` (waits, bytes, stages per frame; issue 33's steady frame under
# 30 ms); and the 64-lamp bench at 1080p on the GPU backend (cold and
# flythrough frames, Whitted against LMM1), twice: with the fill's shafts
# and without (whether a GPU is better off tracing every segment).
# Everything it prints and the stats files land in $OUT (the device
# tool's folder) or /tmp/device-check.
# WIDTH, HEIGHT, FRAMES and BENCH_HEIGHT (0 skips the bench) make it a
# smaller run, to try the script on lavapipe first.
#
# The images lent so far had the NVIDIA ICD but no Vulkan loader, and the
# ICD that names libGLX_nvidia refuses vkCreateInstance without a display
# (BENCHMARKS.md, "GPU start-up"): the packed loader and an ICD file naming
# libEGL_nvidia are used where that is so.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${OUT:-/tmp/device-check}
width=${WIDTH:-1280} height=${HEIGHT:-720} frames=${FRAMES:-0..12}
bench_height=${BENCH_HEIGHT:-1080}
mkdir -p "$out"
exec > >(tee "$out/device_check.log") 2>&1
tar -C target -xJf target/device.tar.xz
bin=$PWD/target/device
if ! ldconfig -p | grep -q 'libvulkan.so.1 '; then
  export LD_LIBRARY_PATH=$bin${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
fi
if grep -qs libGLX_nvidia /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json; then
  echo '{"file_format_version":"1.0.1","ICD":{"library_path":"libEGL_nvidia.so.0","api_version":"1.3"}}' \
    > "$out/nvidia_egl_icd.json"
  export VK_ICD_FILENAMES=$out/nvidia_egl_icd.json
fi
# The tests find the repository's files where they were built.
built=/work/main
if [ ! -e "$built/animations" ]; then
  mkdir -p "$(dirname "$built")" && ln -sfn "$PWD" "$built"
fi
if command -v nvidia-smi >/dev/null; then nvidia-smi --query-gpu=name,driver_version --format=csv,noheader; fi

echo "== GPU tests (the CPU's bits)"
for test in gpu_backend gpu_traffic reuse_property sequence_reuse; do
  timeout 300 "$bin/$test" --test-threads 4 2>&1 | grep -E '^test |test result' | grep -v ' ok$'
done

echo "== city fly-through, ${width}x$height, frames $frames"
for method in lmm1 whitted; do
  timeout 300 "$bin/lmanim" animations/city.gltf --backend gpu --method "$method" \
    --frames "$frames" --width "$width" --height "$height" --no-cache --quiet \
    --stats "$out/city-$method.json" --out "$out/city-$method.####.exr"
  python3 - "$out/city-$method.json" "$method" <<'PY'
import json, sys
for f in json.load(open(sys.argv[1]))["frames"]:
    g = f["gpu"]
    stages = " ".join(f"{k} {v * 1e3:.1f}" for k, v in sorted(f["stages"].items()))
    print(f'{sys.argv[2]} frame {f["frame"]}: {f["seconds"] * 1e3:.1f} ms ({stages} ms), '
          f'waits {g["waits"]}, up {g["bytes_up"] / 1e6:.1f} MB, down {g["bytes_down"] / 1e6:.1f} MB, '
          f'segments {g["segments_traced"]}')
PY
done
rm -f "$out"/city-*.exr

if [ "$bench_height" != 0 ]; then
  for shafts in test skip; do
    echo "== 64 lamps, ${bench_height}p, GPU backend, the fill's shafts: $shafts"
    LMANIM_BENCH_BACKEND=gpu LMANIM_BENCH_LAMPS=64 LMANIM_BENCH_HEIGHT=$bench_height \
      LMANIM_BENCH_SHAFTS=$shafts timeout 300 "$bin/bench_lmm" --bench
  done
fi
