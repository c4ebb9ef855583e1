#!/usr/bin/env python3
"""Writes data/meshes/animated/bending_tube.gltf: a closed, capped tube 2 units tall skinned to two
joints (issue 16's skinned-mesh tests and examples). The root joint slides 1 unit along +x over
2 s; the upper joint, at y = 1, bends the upper half 90 degrees about +z (towards -x) over the
same 2 s. Vertex weights blend the joints over y in [0.75, 1.25] (smoothstep). One glTF 2.0 file,
its buffer embedded as base64. Written by sdftrace's authors; same terms as the project."""
import base64, json, math, struct, sys

RINGS, SEGMENTS, RADIUS, HEIGHT = 17, 16, 0.25, 2.0

positions, joints, weights, indices = [], [], [], []

def weight_upper(y):
    t = min(max((y - 0.75) / 0.5, 0.0), 1.0)
    return t * t * (3 - 2 * t)

def add_vertex(x, y, z):
    positions.append((x, y, z))
    w = weight_upper(y)
    joints.append((0, 1, 0, 0))
    weights.append((1 - w, w, 0.0, 0.0))
    return len(positions) - 1

rings = []
for r in range(RINGS):
    y = HEIGHT * r / (RINGS - 1)
    rings.append([add_vertex(RADIUS * math.cos(2 * math.pi * s / SEGMENTS), y,
                             RADIUS * math.sin(2 * math.pi * s / SEGMENTS)) for s in range(SEGMENTS)])
bottom, top = add_vertex(0, 0, 0), add_vertex(0, HEIGHT, 0)
for r in range(RINGS - 1):  # outward-facing (counter-clockwise seen from outside)
    for s in range(SEGMENTS):
        a, b = rings[r][s], rings[r][(s + 1) % SEGMENTS]
        c, d = rings[r + 1][s], rings[r + 1][(s + 1) % SEGMENTS]
        indices += [a, c, b, b, c, d]
for s in range(SEGMENTS):
    indices += [bottom, rings[0][s], rings[0][(s + 1) % SEGMENTS]]
    indices += [top, rings[-1][(s + 1) % SEGMENTS], rings[-1][s]]

times = [0.0, 1.0, 2.0]
slide = [(0.0, 0.0, 0.0), (0.5, 0.0, 0.0), (1.0, 0.0, 0.0)]
def zrot(deg):
    h = math.radians(deg) / 2
    return (0.0, 0.0, math.sin(h), math.cos(h))
bend = [zrot(0), zrot(45), zrot(90)]
inverse_bind = [
    (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1),   # root at the origin (column-major)
    (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1),  # upper joint at y = 1
]

blob, views, accessors = b"", [], []
def add(data, fmt, count, comp, kind, target=None, minmax=None):
    global blob
    while len(blob) % 4:
        blob += b"\0"
    raw = b"".join(struct.pack("<" + fmt, *(v if isinstance(v, tuple) else (v,))) for v in data)
    view = {"buffer": 0, "byteOffset": len(blob), "byteLength": len(raw)}
    if target:
        view["target"] = target
    views.append(view)
    blob += raw
    acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": kind}
    if minmax:
        acc["min"], acc["max"] = minmax
    accessors.append(acc)
    return len(accessors) - 1

lo = [min(p[i] for p in positions) for i in range(3)]
hi = [max(p[i] for p in positions) for i in range(3)]
POS = add(positions, "3f", len(positions), 5126, "VEC3", 34962, (lo, hi))
JNT = add(joints, "4H", len(joints), 5123, "VEC4", 34962)
WGT = add(weights, "4f", len(weights), 5126, "VEC4", 34962)
IDX = add(indices, "I", len(indices), 5125, "SCALAR", 34963)
IBM = add(inverse_bind, "16f", 2, 5126, "MAT4")
TIM = add(times, "f", 3, 5126, "SCALAR", None, ([0.0], [2.0]))
SLD = add(slide, "3f", 3, 5126, "VEC3")
BND = add(bend, "4f", 3, 5126, "VEC4")

gltf = {
    "asset": {"version": "2.0", "generator": "sdftrace scripts/make-bending-tube.py"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1]}],
    "nodes": [
        {"name": "tube", "mesh": 0, "skin": 0},
        {"name": "root", "children": [2]},
        {"name": "upper", "translation": [0, 1, 0]},
    ],
    "meshes": [{"name": "tube", "primitives": [{"attributes": {"POSITION": POS, "JOINTS_0": JNT,
                                                              "WEIGHTS_0": WGT},
                                                "indices": IDX}]}],
    "skins": [{"joints": [1, 2], "inverseBindMatrices": IBM, "skeleton": 1}],
    "animations": [{"name": "bend", "channels": [
        {"sampler": 0, "target": {"node": 1, "path": "translation"}},
        {"sampler": 1, "target": {"node": 2, "path": "rotation"}}],
        "samplers": [{"input": TIM, "output": SLD, "interpolation": "LINEAR"},
                     {"input": TIM, "output": BND, "interpolation": "LINEAR"}]}],
    "buffers": [{"byteLength": len(blob),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    "bufferViews": views,
    "accessors": accessors,
}
out = sys.argv[1] if len(sys.argv) > 1 else "data/meshes/animated/bending_tube.gltf"
with open(out, "w") as f:
    json.dump(gltf, f, indent=1)
print(f"{out}: {len(positions)} vertices, {len(indices) // 3} triangles")
