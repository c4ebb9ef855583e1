"""Bake a mesh to a signed distance field, look at a slice of it, render it, and mesh it back.

    PYTHONPATH=build/release/python python3 examples/python/bake_slice_render.py [mesh] [outdir]
"""
import pathlib
import sys
import time

import numpy as np

import sdftrace

root = pathlib.Path(__file__).resolve().parents[2]
mesh = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else root / "data" / "meshes" / "bunny_npm.obj"
out = pathlib.Path(sys.argv[2]) if len(sys.argv) > 2 else pathlib.Path(".")
out.mkdir(parents=True, exist_ok=True)

# 1. Bake: the exact narrow-band SDF, 96 cells along the longest side.
t = time.perf_counter()
grid = sdftrace.bake(mesh, resolution=96, method="exact", band=3)
info = grid.info
print("baked %s in %.2f s: %s, %d x %d x %d cells, voxel %.4g, %.1f KiB" % (
    mesh.name, time.perf_counter() - t, info["kind"], *info["cells"], info["voxel_size"],
    info["memory_bytes"] / 1024))

# 2. A slice through the middle of the field, coloured by distance (inside blue, outside orange).
# The narrow band holds distances within 3 voxels; a dense bake has them everywhere.
dense = sdftrace.bake(mesh, resolution=96, dense=True)
d = sdftrace.slice_field(dense, axis="z", resolution=384)
sdftrace.write_image(out / "slice.png", sdftrace.colorize_distance(d))
print("slice: distances from %.3f to %.3f -> %s" % (d.min(), d.max(), out / "slice.png"))

# 3. Distances and normals at points, through the batched tape.
pts = np.random.default_rng(0).uniform(*info["bounds"], (100000, 3)).astype(np.float32)
dist, grad = grid.field.evaluate(pts, gradients=True)
print("evaluated %d points: %.1f%% inside" % (len(pts), 100 * np.mean(dist < 0)))

# 4. Render: colour, depth and the steps heat map, enhanced sphere tracing with soft shadows.
img, stats = sdftrace.render(grid, 480, 360, aovs=["color", "depth", "steps"],
                             shadow_method="soft", return_stats=True)
sdftrace.write_image(out / "render.png", img["color"])
sdftrace.write_image(out / "steps.png", img["steps"][..., 0], label="steps")
print("rendered 480x360 in %.3f s, %.2f evaluations per ray -> %s" % (
    stats["seconds"], stats["evaluations_per_ray"], out / "render.png"))

# 5. Back to triangles (OpenVDB's volumeToMesh).
verts, faces = grid.to_mesh(adaptivity=0.1)
print("mesh back: %d vertices, %d triangles" % (len(verts), len(faces)))
