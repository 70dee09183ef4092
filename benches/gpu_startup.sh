#!/usr/bin/env bash
# Issue 35's start-up figures: how long the courtyard's first LMM1 frame
# (160x90, --backend gpu) takes with the driver's and lmanim's pipeline
# caches empty, with lmanim's alone, and with both; and whether the three
# frames are the same bits. BENCHMARKS.md, "GPU start-up", records them.
#
#   benches/gpu_startup.sh [LMANIM]     (default: target/release/lmanim)
#
# On lavapipe set MESA_SHADER_CACHE_DISABLE=true for the "driver cache
# empty" rows. On a headless NVIDIA machine whose nvidia_icd.json names
# libGLX_nvidia (which refuses vkCreateInstance without a display), point
# the loader at the EGL library instead:
#   echo '{"file_format_version":"1.0.1","ICD":{"library_path":"libEGL_nvidia.so.0","api_version":"1.4.312"}}' > /tmp/nvidia_egl_icd.json
#   export VK_ICD_FILENAMES=/tmp/nvidia_egl_icd.json
set -uo pipefail
cd "$(dirname "$0")/.."
lmanim=${1:-target/release/lmanim}
work=$(mktemp -d)
source benches/first_frame.sh

for method in lmm1 whitted; do
    empty_driver_cache
    first_frame "$method-no-cache" "$method"
    empty_driver_cache
    first_frame "$method-lmanim-cache" "$method"
    first_frame "$method-both-caches" "$method"
    for run in lmanim-cache both-caches; do
        cmp -s "$work/$method-no-cache.0000.exr" "$work/$method-$run.0000.exr" \
            && echo "$method-$run: the same bits" || echo "$method-$run: BITS DIFFER"
    done
done
echo "stats (gpu.pipelines per run) in $work"
