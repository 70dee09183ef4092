#!/usr/bin/env python3
"""Where a GPU run's frames spent their time on the GPU: a Markdown table
of each frame's wall time and its passes' GPU seconds (`gpu.pass_seconds`
in `--stats`, written where the adapter has timestamp queries), heaviest
pass first, from one or several stats files.

    lmanim animations/city.gltf --backend gpu --method lmm1 --frames 0..3 \\
        --width 640 --height 360 --no-cache --stats lmm1.json
    python3 benches/pass_times.py lmm1.json whitted.json
"""
import json
import sys


def rows(path):
    run = json.load(open(path))
    for frame in run["frames"]:
        gpu = frame.get("gpu") or {}
        passes = gpu.get("pass_seconds", {})
        yield run["method"], frame, gpu, passes


def main(paths):
    if not paths:
        sys.exit(__doc__)
    print("| method | frame | wall (ms) | GPU passes (ms) | waits | segments traced | heaviest passes (ms) |")
    print("|---|---|---|---|---|---|---|")
    for path in paths:
        for method, frame, gpu, passes in rows(path):
            heaviest = sorted(passes.items(), key=lambda kv: -kv[1])[:4]
            print(
                f"| {method} | {frame['frame']} | {frame['seconds'] * 1e3:.0f} "
                f"| {sum(passes.values()) * 1e3:.0f} | {gpu.get('waits', '—')} "
                f"| {gpu.get('segments_traced', '—')} | "
                + ", ".join(f"{name} {seconds * 1e3:.0f}" for name, seconds in heaviest)
                + (f" ({gpu['passes_untimed']} passes untimed)" if gpu.get("passes_untimed") else "")
                + " |"
            )


if __name__ == "__main__":
    main(sys.argv[1:])
