"""Writes the flicker study's fly-through for one study scene: a camera path
(`lmanim --camera-path`) that starts at the scene's own camera, flies away
from it and back every PERIOD seconds, so that the frames at multiples of
PERIOD see exactly the study's view while the masks in between are made
for other views and reused. Prints the frames to render and the frames
that see the study's view.

    python3 flight.py SCENE.gltf OUT.ron [VISITS]
"""

import json
import math
import sys

FPS = 24
# Seconds between returns to the study's view: 6 frames at 24 fps.
PERIOD = 0.25
# The excursions, in units of the camera's distance from the origin: right,
# up (the look-at point stays put, so the camera swings round the view).
EXCURSIONS = ((0.1, 0.0), (-0.1, 0.05), (0.0, 0.1), (0.1, -0.03))


def rotate(q, v):
    """v rotated by the unit quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    u = (x, y, z)
    cross = lambda a, b: (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                          a[0] * b[1] - a[1] * b[0])
    t = tuple(2 * c for c in cross(u, v))
    s = cross(u, t)
    return tuple(v[i] + w * t[i] + s[i] for i in range(3))


def main():
    scene, out = sys.argv[1], sys.argv[2]
    visits = int(sys.argv[3]) if len(sys.argv) > 3 else 16
    with open(scene, encoding="utf-8") as file:
        document = json.load(file)
    node = next(n for n in document["nodes"] if "camera" in n)
    camera = document["cameras"][node["camera"]]
    position = node.get("translation", [0.0, 0.0, 0.0])
    rotation = node.get("rotation", [0.0, 0.0, 0.0, 1.0])
    forward = rotate(rotation, (0.0, 0.0, -1.0))
    right = rotate(rotation, (1.0, 0.0, 0.0))
    scale = math.sqrt(sum(c * c for c in position))
    look_at = [p + 3.0 * f for p, f in zip(position, forward)]
    fov = math.degrees(camera["perspective"]["yfov"])

    def waypoint(at, time):
        coords = ", ".join(f"{c:.9g}" for c in at)
        target = ", ".join(f"{c:.9g}" for c in look_at)
        return f"        (position: ({coords}), look_at: ({target}), time: {time:.9g}),"

    lines = []
    for visit in range(visits):
        lines.append(waypoint(position, visit * PERIOD))
        if visit + 1 < visits:
            side, up = EXCURSIONS[visit % len(EXCURSIONS)]
            away = [p + scale * (side * r + up * (1.0 if i == 1 else 0.0))
                    for i, (p, r) in enumerate(zip(position, right))]
            lines.append(waypoint(away, (visit + 0.5) * PERIOD))
    with open(out, "w", encoding="utf-8") as file:
        file.write(f"// The flicker study's fly-through of {scene} (docs/study/cycles/flight.py)\n")
        file.write(f"(\n    fov: {fov:.9g},\n    waypoints: [\n")
        file.write("\n".join(lines) + "\n    ],\n)\n")
    step = round(PERIOD * FPS)
    print(f"0..{(visits - 1) * step + 1}")
    print(",".join(str(visit * step) for visit in range(visits)))


if __name__ == "__main__":
    main()
