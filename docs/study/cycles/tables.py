"""Prints the Cycles study's tables (STUDY.md, "Beside Blender Cycles") as
Markdown from run.sh's outputs: study-cycles/<scene>/study/study.json and
study-cycles/<scene>/cycles/cycles.json.

    python3 tables.py study-cycles box leaves street wall
"""

import json
import os
import sys

# What the glTF importer's light conversion predicts for the fitted scale:
# it writes a point light of I candela as I·4π/683 W, and Cycles' point
# light of P W has the intensity P/(4π) W/sr.
PREDICTED_SCALE = 683.0


def load(root, scene):
    with open(os.path.join(root, scene, "study", "study.json"), encoding="utf-8") as file:
        study = json.load(file)
    with open(os.path.join(root, scene, "cycles", "cycles.json"), encoding="utf-8") as file:
        cycles = json.load(file)
    return study, cycles


def name(run):
    if "candidate" in run:
        return run["candidate"]
    if run["method"] == "area":
        return f"area {run['spp']} spp"
    if run["method"] in ("lmm", "lmm1"):
        if run["default_lattice"]:
            return f"{run['method']}, default"
        return f"{run['method']}, h = {run['h']:.3f}, kI {run['ki']:g}"
    return run["method"]


def cell(value, digits=4):
    return "" if value is None else f"{value:.{digits}f}"


def rows(study):
    """The table's runs: every run but the swept lattices, of which the
    most accurate in the penumbra stands for them."""
    runs = study["runs"]
    swept = [r for r in runs if r.get("method") in ("lmm", "lmm1") and not r["default_lattice"]]
    best = {}
    for run in swept:
        kept = best.get(run["method"])
        if kept is None or run["penumbra_rmse"] < kept["penumbra_rmse"]:
            best[run["method"]] = run
    chosen = []
    for run in runs:
        if run in swept and best.get(run["method"]) is not run:
            continue
        chosen.append(run)
    return chosen


def scene_table(scene, study, cycles):
    reference = study["reference"]
    whitted = next(r for r in study["runs"] if r.get("method") == "whitted")
    lines = [
        f"#### {scene}",
        "",
        f"Reference: {reference_label(reference)}; {reference['lit_pixels']} lit pixels, "
        f"{reference['penumbra_pixels']} in penumbra. Cycles' light scale "
        f"{cycles['fit']['scale']:.1f}.",
        "",
        "| run | frames | seconds | RMSE lit | RMSE penumbra | penumbra / Whitted's | Pareto |",
        "|---|---|---|---|---|---|---|",
    ]
    for run in rows(study):
        ratio = run["penumbra_rmse"] / whitted["penumbra_rmse"]
        best = "" if run.get("candidate") or run.get("default_lattice") or run.get("method") != "lmm1" else " (best of sweep)"
        lines.append(
            f"| {name(run)}{best} | {run['frames']} | {run['seconds']:.3f} | {cell(run['rmse'])} | "
            f"{cell(run['penumbra_rmse'])} | {ratio:.2f} | {'yes' if run['pareto'] else ''} |"
        )
    return lines


def reference_label(reference):
    if reference.get("spp"):
        return f"area {reference['spp']} spp ({reference['seconds']:.1f} s)"
    return reference["source"]


def fit_table(scenes, loaded):
    lines = [
        "| scene | light scale (over the predicted 683) | median relative difference | pixels within 2% | "
        "import s | first render s |",
        "|---|---|---|---|---|---|",
    ]
    for scene in scenes:
        cycles = loaded[scene][1]
        fit = cycles["fit"]
        lines.append(
            f"| {scene} | {fit['scale']:.1f} ({fit['scale'] / PREDICTED_SCALE:.3f}) | "
            f"{fit['residual_median_abs']:.4f} | {100 * fit['within_2pct']:.1f}% | "
            f"{cycles['import_seconds']:.2f} | {cycles['first_render_seconds']:.2f} |"
        )
    return lines


def flicker_table(scenes, loaded):
    lines = [
        "| scene | run | frames | seconds per frame | RMSE penumbra (pooled) | flicker lit | flicker penumbra | flicker / error, penumbra |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for scene in scenes:
        for run in loaded[scene][0]["runs"]:
            if run["frames"] < 2:
                continue
            flicker = run["flicker"]
            share = flicker["penumbra"] / run["penumbra_rmse"] if run["penumbra_rmse"] else 0.0
            lines.append(
                f"| {scene} | {name(run)} | {run['frames']} | {run['seconds']:.3f} | "
                f"{cell(run['penumbra_rmse'])} | {cell(flicker['lit'])} | "
                f"{cell(flicker['penumbra'])} | {share:.2f} |"
            )
    return lines


def equal_time_table(scenes, loaded):
    """LMM1's default against the denoised Cycles runs: the cheapest
    (1 spp, fast denoiser), the most accurate within 1.5× LMM1's time
    (timings on a shared machine move by that much), and the cheapest at
    least as accurate."""
    lines = [
        "| scene | LMM1 default: s, penumbra | cheapest denoised Cycles | most accurate denoised Cycles within 1.5× LMM1's time | cheapest denoised Cycles as accurate as LMM1 |",
        "|---|---|---|---|---|",
    ]
    for scene in scenes:
        runs = loaded[scene][0]["runs"]
        lmm1 = next(r for r in runs if r.get("method") == "lmm1" and r["default_lattice"])
        denoised = [r for r in runs if r.get("candidate", "").startswith("cycles+oidn")]
        cheapest = min(denoised, key=lambda r: r["seconds"], default=None)
        within = [r for r in denoised if r["seconds"] <= 1.5 * lmm1["seconds"]]
        best = min(within, key=lambda r: r["penumbra_rmse"], default=None)
        accurate = [r for r in denoised if r["penumbra_rmse"] <= lmm1["penumbra_rmse"]]
        as_accurate = min(accurate, key=lambda r: r["seconds"], default=None)
        describe = lambda r: "none" if r is None else (
            f"{name(r)}: {r['seconds']:.3f} s ({r['seconds'] / lmm1['seconds']:.1f}×), "
            f"{r['penumbra_rmse']:.4f}")
        lines.append(
            f"| {scene} | {lmm1['seconds']:.3f} s, {lmm1['penumbra_rmse']:.4f} | "
            f"{describe(cheapest)} | {describe(best)} | {describe(as_accurate)} |"
        )
    return lines


def main():
    root, scenes = sys.argv[1], sys.argv[2:]
    loaded = {scene: load(root, scene) for scene in scenes}
    blender = {loaded[s][1]["blender"] for s in scenes}
    out = [f"Blender {', '.join(sorted(blender))} (bpy), Cycles on the CPU, "
           f"{loaded[scenes[0]][1]['threads']} threads, "
           f"{loaded[scenes[0]][1]['width']}×{loaded[scenes[0]][1]['height']}.", "",
           "### Light units: Cycles' hard-shadowed frame against lmanim's Whitted frame", ""]
    out += fit_table(scenes, loaded)
    out += ["", "### Time and error per scene", ""]
    for scene in scenes:
        out += scene_table(scene, *loaded[scene]) + [""]
    out += ["### LMM1's default at Cycles+OIDN's time", ""]
    out += equal_time_table(scenes, loaded)
    out += ["", "### Flicker: still view, frames that differ only by seed or by the flight between them", ""]
    out += flicker_table(scenes, loaded)
    print("\n".join(out))


if __name__ == "__main__":
    main()
