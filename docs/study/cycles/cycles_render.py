"""Renders one study scene with Blender Cycles for `lmanim study --candidate`.

Run with the `bpy` package's Python (see run.sh beside this file):

    python cycles_render.py SCENE.gltf WHITTED.exr OUT_DIR

It imports the scene with Blender's glTF importer, matches what lmanim
computes (direct light only, no world light, a box filter one pixel wide,
the lamps as spheres of the glTF file's `extras.radius`, glTF's range
window), fits ONE scale on the lights' power so that a hard-shadowed Cycles
frame matches lmanim's Whitted frame (WHITTED.exr) over lit pixels, then
renders each (samples, denoiser) configuration: 1 spp as a still
sequence with a new seed per frame (its errors pooled over the frames,
and its flicker measured), more samples as one frame. It writes
the frames as EXR into OUT_DIR, `cycles.json` (the fit and every
render's seconds) and `candidates.txt`, one `--candidate` argument per
line for `lmanim study`.

Seconds are the wall time of `bpy.ops.render.render` after a warm-up
render, with persistent data kept (the scene's BVH is built once, as
lmanim's study builds its world outside the timed render); the importer's
and the first render's time are reported apart in `cycles.json`.
"""

import argparse
import json
import math
import os
import sys
import time

import bpy
import numpy as np

# Samples per pixel of the table's rows, as lmanim's `area` sweep.
SPP = (1, 4, 16, 64)
# The denoisers tried, by the rows' family name: none; OpenImageDenoise
# at Blender's defaults (quality high, albedo and normal prefiltered); and
# at its fastest (quality fast, prefilter fast), what a preview would use.
DENOISERS = {
    "cycles": None,
    "cycles+oidn": ("HIGH", "ACCURATE"),
    "cycles+oidn-fast": ("FAST", "FAST"),
}
# Samples per pixel of the hard-shadowed frame the light units are fitted on:
# enough that, with 16 lamps and one sampled per sample, the residuals say
# more about the shading than about the noise.
FIT_SPP = 64
# A render shorter than this is repeated and its fastest time kept, as
# `lmanim study` does with its own runs.
REPEAT_BELOW_SECONDS = 1.0
MAX_REPEATS = 3


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", help="the study scene, .gltf")
    parser.add_argument("whitted", help="lmanim's Whitted frame of it, EXR")
    parser.add_argument("out", help="directory for the frames and tables")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--frames", type=int, default=16,
                        help="frames (seeds) of each 1-spp sequence")
    parser.add_argument("--spp", type=lambda s: [int(v) for v in s.split(",")],
                        default=list(SPP))
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    return parser.parse_args(argv)


def luminance(rgba):
    return 0.2126 * rgba[..., 0] + 0.7152 * rgba[..., 1] + 0.0722 * rgba[..., 2]


def read_exr(path):
    """An EXR's RGBA as a (height, width, 4) array, top row first."""
    image = bpy.data.images.load(os.path.abspath(path), check_existing=False)
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return np.flipud(pixels.reshape(height, width, 4))


def lamps_of(scene_path):
    """Per glTF light name: (lamp radius in metres, range or None)."""
    with open(scene_path, encoding="utf-8") as file:
        document = json.load(file)
    lights = document.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    return {
        light.get("name"): ((light.get("extras") or {}).get("radius", 0.0), light.get("range"))
        for light in lights
    }


def range_window(light, reach):
    """glTF's recommended range window, clamp(1 − (d/range)⁴, 0, 1)², on the
    light's emission (lmanim's falloff; Blender's importer drops `range`).
    d is Cycles' ray length to the light's sample."""
    light.use_nodes = True
    nodes, links = light.node_tree.nodes, light.node_tree.links
    emission = next(node for node in nodes if node.type == "EMISSION")
    path = nodes.new("ShaderNodeLightPath")

    def math_node(operation, a, b):
        node = nodes.new("ShaderNodeMath")
        node.operation = operation
        for socket, value in zip(node.inputs, (a, b)):
            if isinstance(value, (int, float)):
                socket.default_value = value
            else:
                links.new(value, socket)
        return node.outputs[0]

    ratio = math_node("DIVIDE", path.outputs["Ray Length"], reach)
    fourth = math_node("POWER", ratio, 4.0)
    window = math_node("SUBTRACT", 1.0, fourth)
    window = math_node("MAXIMUM", window, 0.0)
    window = math_node("POWER", window, 2.0)
    links.new(window, emission.inputs["Strength"])


def load(args):
    """The scene imported and set up as lmanim renders it; the lamps."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(args.scene))
    scene = bpy.context.scene
    scene.camera = next(o for o in scene.objects if o.type == "CAMERA")
    scene.world = None  # lmanim's study scenes have no ambient or background light
    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x, render.resolution_y = args.width, args.height
    render.resolution_percentage = 100
    render.threads_mode = "FIXED"
    render.threads = args.threads
    render.use_persistent_data = True
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_mode = "RGBA"
    render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_adaptive_sampling = False  # exactly `samples` per pixel
    cycles.pixel_filter_type = "BOX"  # lmanim's reference: uniform over the pixel
    cycles.filter_width = 1.0
    # Direct light only: lmanim's Whitted recursion follows mirrors and
    # glass, and the study scenes have neither (rough dielectrics only).
    for bounces in ("max_bounces", "diffuse_bounces", "glossy_bounces",
                    "transmission_bounces", "volume_bounces", "transparent_max_bounces"):
        setattr(cycles, bounces, 0)
    cycles.caustics_reflective = cycles.caustics_refractive = False
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.light_sampling_threshold = 0.0  # no light is cut off as too faint
    cycles.denoiser = "OPENIMAGEDENOISE"
    cycles.denoising_input_passes = "RGB_ALBEDO_NORMAL"
    cycles.denoising_prefilter = "ACCURATE"
    scene.view_layers[0].cycles.use_denoising = True
    gltf_lamps = lamps_of(args.scene)
    lamps = []
    for obj in scene.objects:
        if obj.type != "LIGHT":
            continue
        radius, reach = gltf_lamps.get(obj.data.name, (0.0, None))
        light = obj.data
        light.use_soft_falloff = False  # a sphere of uniform radiance, as lmanim's `area`
        obj.visible_camera = False  # lmanim never draws the lamp itself
        if reach:
            range_window(light, reach)
        lamps.append((light, radius, light.energy))
    return scene, lamps


def set_lamps(lamps, scale, soft):
    for light, radius, energy in lamps:
        light.energy = energy * scale
        light.shadow_soft_size = radius if soft else 0.0


def render(scene, path, spp, denoise, seed):
    """Renders to `path` (EXR) with `denoise` (None or a DENOISERS value);
    returns the fastest render's seconds."""
    cycles = scene.cycles
    cycles.samples = spp
    cycles.use_denoising = denoise is not None
    if denoise:
        cycles.denoising_quality, cycles.denoising_prefilter = denoise
    cycles.seed = seed
    fastest, spent = math.inf, 0.0
    for _ in range(MAX_REPEATS):
        started = time.perf_counter()
        bpy.ops.render.render()
        seconds = time.perf_counter() - started
        fastest, spent = min(fastest, seconds), spent + seconds
        if spent >= REPEAT_BELOW_SECONDS:
            break
    bpy.data.images["Render Result"].save_render(os.path.abspath(path), scene=scene)
    return fastest


def fit_scale(scene, lamps, whitted_path, out):
    """One scale on every light's power: the median, over the pixels both
    light, of lmanim's Whitted luminance over Cycles' hard-shadowed one.
    A median, not least squares: the few pixels where the two shading
    models part (grazing light, edges a pixel's area and its centre see
    differently) are the brightest and would pull a least-squares scale
    off most of the frame (by 1.5-2.7% on three scenes; on the box, the
    one scene without them, the two agree to 0.15%). The relative
    residuals say how well the shading models agree, noise included."""
    set_lamps(lamps, 1.0, soft=False)
    path = os.path.join(out, "cycles-hard-fit.exr")
    render(scene, path, FIT_SPP, None, 0)
    cycles = luminance(read_exr(path))
    whitted = luminance(read_exr(whitted_path))
    if cycles.shape != whitted.shape:
        sys.exit(f"{whitted_path} is {whitted.shape[::-1]}, Cycles rendered {cycles.shape[::-1]}")
    lit = (whitted > 1e-3 * whitted.max()) & (cycles > 1e-3 * cycles.max())
    w, c = whitted[lit].astype(np.float64), cycles[lit].astype(np.float64)
    scale = float(np.median(w / c))
    relative = (scale * c - w) / w
    return {
        "scale": scale,
        "spp": FIT_SPP,
        "pixels": int(lit.sum()),
        "residual_rms": float(np.sqrt(np.mean(relative ** 2))),
        "residual_median_abs": float(np.median(np.abs(relative))),
        "within_2pct": float(np.mean(np.abs(relative) <= 0.02)),
    }


def main():
    args = arguments()
    os.makedirs(args.out, exist_ok=True)
    started = time.perf_counter()
    scene, lamps = load(args)
    imported = time.perf_counter() - started
    started = time.perf_counter()
    set_lamps(lamps, 1.0, soft=True)
    render(scene, os.path.join(args.out, "cycles-warm-up.exr"), 1, None, 0)
    warm_up = time.perf_counter() - started
    fit = fit_scale(scene, lamps, args.whitted, args.out)
    print(f"cycles: light scale {fit['scale']:.4g} (residual RMS {fit['residual_rms']:.4f} "
          f"over {fit['pixels']} pixels)", file=sys.stderr)
    set_lamps(lamps, fit["scale"], soft=True)
    runs, candidates = [], []
    for family, denoise in DENOISERS.items():
        for spp in args.spp:
            frames = args.frames if spp == 1 else 1
            name = f"{family} {spp} spp"
            stem = f"{family}-{spp}spp"
            paths, times = [], []
            for seed in range(frames):
                path = os.path.join(args.out, f"{stem}.{seed:04}.exr")
                times.append(render(scene, path, spp, denoise, seed))
                paths.append(os.path.abspath(path))
            seconds = float(np.mean(times))
            print(f"cycles: {name}: {seconds:.3f} s", file=sys.stderr)
            runs.append({"name": name, "spp": spp, "denoiser": denoise, "frames": frames,
                         "seconds": seconds, "seconds_each": times})
            candidates.append(f"{name}={seconds:.6f}:{','.join(paths)}")
    report = {
        "blender": bpy.app.version_string,
        "scene": args.scene,
        "width": args.width,
        "height": args.height,
        "threads": args.threads,
        "import_seconds": imported,
        "first_render_seconds": warm_up,
        "fit": fit,
        "runs": runs,
    }
    with open(os.path.join(args.out, "cycles.json"), "w", encoding="utf-8") as file:
        json.dump(report, file, indent=2)
    with open(os.path.join(args.out, "candidates.txt"), "w", encoding="utf-8") as file:
        file.write("\n".join(candidates) + "\n")


if __name__ == "__main__":
    main()
