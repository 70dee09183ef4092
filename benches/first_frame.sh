# Sourced by benches/gpu_startup.sh and benches/device_check.sh: the
# courtyard's first frame at 160x90 on the GPU backend, timed, with
# NVIDIA's driver cache kept in $work/driver-cache and lmanim's in
# $work/lmanim-cache-METHOD. Set $lmanim and $work first. Each run goes
# through first_frame_runner, where the sourcing script defines one
# (device_check.sh's bounds it by its deadline); else it runs as it is.

# NVIDIA's driver keeps its compiled code here; emptied before a cold row.
export __GL_SHADER_DISK_CACHE_PATH=$work/driver-cache

empty_driver_cache() {
    rm -rf "$__GL_SHADER_DISK_CACHE_PATH" "$HOME/.cache/nvidia"
    mkdir -p "$__GL_SHADER_DISK_CACHE_PATH"
}

declare -F first_frame_runner >/dev/null || first_frame_runner() { "$@"; }

# One run: its name, then the method. Prints the adapter and the wall
# seconds, and returns lmanim's status.
first_frame() {
    local began=$EPOCHREALTIME status
    first_frame_runner "$lmanim" animations/courtyard.gltf \
        --frames 0 --width 160 --height 90 --backend gpu --method "$2" \
        --cache "$work/lmanim-cache-$2" --out "$work/$1.####.exr" --stats "$work/$1.json" \
        2>&1 | grep -E 'adapter|rror'
    status=${PIPESTATUS[0]}
    echo "$1: exit $status, $(awk "BEGIN{print $EPOCHREALTIME - $began}") s"
    return "$status"
}
