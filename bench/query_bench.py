"""Mesh queries (sdftrace.MeshQuery, docs/guide/10-mesh-queries.md) against Open3D's
RaycastingScene from Debian (python3-open3d) and against the exact bake's cost per sample, in one
process, on meshes of several kinds: a small closed one, an open scan, a thin-walled CAD-like
part and a 1.1M-triangle scan (the Stanford bunny subdivided). Medians of REPS runs.

Per mesh, with 1M points uniform in the mesh's box (float32, all cores for both):
  - sdftrace distance (unsigned) and signed_distance (winding signs) against Open3D's
    compute_distance (unsigned; its signed variant is not compared: Debian's 0.16 gets signs
    wrong, see below);
  - sdftrace ray_cast against Open3D's cast_rays, 1M rays from points in the box in random
    directions; hit rates are printed, each checked against a brute-force sample;
  - distances against Open3D's (max difference) and a brute-force reference on a sample;
  - the exact bake's seconds per stored sample (sdftrace.bake, method exact, dense, 128 cells);
  - on the open scan, winding signs against the winding-number bake at 256 cells for points
    farther than one voxel;
  - a DeepSDF-style sampling run of 10M near-surface points: time and peak memory growth.

    PYTHONPATH=build/release/python python3 bench/query_bench.py [--quick] [--reps N]
    ... bench/query_bench.py --distances    # only the distance columns, against Open3D
    ... bench/query_bench.py --rays         # only the ray columns, against Open3D
"""
import argparse
import resource
import time

import numpy as np

import sdftrace
from python_evaluate_bench import median_seconds  # bench/, beside this script

try:
    import open3d as o3d
except ImportError:  # the comparison needs Debian's python3-open3d
    o3d = None


def obj_mesh(path):
    v, f = [], []
    for line in open(path):
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            v.append([float(x) for x in t[1:4]])
        elif t[0] == "f":
            idx = [int(c.split("/")[0]) - 1 for c in t[1:]]
            f += [(idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1)]
    v, f = np.array(v), np.array(f, np.int64)
    used = np.unique(f)
    remap = np.full(len(v), -1)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def subdivide(v, f, times):
    """Midpoint subdivision (4 triangles per triangle), `times` times."""
    for _ in range(times):
        edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(edges, axis=0, return_inverse=True)
        mid = len(v) + inv.reshape(3, -1).T  # ab, bc, ca
        v = np.vstack([v, 0.5 * (v[uniq[:, 0]] + v[uniq[:, 1]])])
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        ab, bc, ca = mid[:, 0], mid[:, 1], mid[:, 2]
        f = np.vstack([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1),
                       np.stack([ca, bc, c], 1), np.stack([ab, bc, ca], 1)])
    return v, f


def thin_part():
    """A CAD-like part: a box 1 x 0.6 x 0.4 with walls 1 % of its size thick (outer and inner
    shells, the inner one reversed), a thin fin on top, each face split into a 24 x 24 grid."""
    def box(lo, hi, n, flip):
        verts, faces = [], []
        for axis in range(3):
            for side in (0, 1):
                u, w = [a for a in range(3) if a != axis]
                base = len(verts)
                for i in range(n + 1):
                    for j in range(n + 1):
                        p = [0.0, 0.0, 0.0]
                        p[axis] = hi[axis] if side else lo[axis]
                        # The last row exactly at hi: shared edges weld (a closed part).
                        p[u] = hi[u] if i == n else lo[u] + (hi[u] - lo[u]) * i / n
                        p[w] = hi[w] if j == n else lo[w] + (hi[w] - lo[w]) * j / n
                        verts.append(p)
                for i in range(n):
                    for j in range(n):
                        q = [base + i * (n + 1) + j, base + (i + 1) * (n + 1) + j,
                             base + (i + 1) * (n + 1) + j + 1, base + i * (n + 1) + j + 1]
                        tri = [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
                        faces += tri
        v, f = np.array(verts), np.array(faces)
        # Orient every triangle outward from the box's centre (then flip the inner shell).
        c = 0.5 * (np.array(lo) + np.array(hi))
        n_ = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        out = np.einsum("ij,ij->i", n_, v[f].mean(1) - c) > 0
        f[~out] = f[~out][:, ::-1]
        if flip:
            f = f[:, ::-1]
        return v, f
    parts = [box((0, 0, 0), (1, 0.6, 0.4), 24, False),
             box((0.01, 0.01, 0.01), (0.99, 0.59, 0.39), 24, True),
             box((0.3, 0.295, 0.4), (0.7, 0.305, 0.6), 24, False)]
    v, f, off = [], [], 0
    for pv, pf in parts:
        v.append(pv)
        f.append(pf + off)
        off += len(pv)
    return np.vstack(v), np.vstack(f)


def brute_distance(v, f, p):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    n = np.cross(b - a, c - a)
    nn = np.einsum("ij,ij->i", n, n)
    out = np.empty(len(p))
    for i, x in enumerate(p):
        d = np.einsum("ij,ij->i", x - a, n) / nn
        q = x - d[:, None] * n
        inside = ((np.einsum("ij,ij->i", np.cross(b - a, q - a), n) >= 0) &
                  (np.einsum("ij,ij->i", np.cross(c - b, q - b), n) >= 0) &
                  (np.einsum("ij,ij->i", np.cross(a - c, q - c), n) >= 0))
        dist = np.where(inside, np.abs(d) * np.sqrt(nn), np.inf)
        for e0, e1 in ((a, b), (b, c), (c, a)):
            e = e1 - e0
            t = np.clip(np.einsum("ij,ij->i", x - e0, e) / np.einsum("ij,ij->i", e, e), 0, 1)
            dist = np.minimum(dist, np.linalg.norm(x - (e0 + t[:, None] * e), axis=1))
        out[i] = dist.min()
    return out


def open3d_scene(v, f):
    """Open3D's RaycastingScene of the mesh (float32 vertices, uint32 faces, as it takes them)."""
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
    return scene


def bench_mesh(name, v, f, n, reps, rng):
    q = sdftrace.MeshQuery(v, f)
    lo, hi = v.min(0), v.max(0)
    diag = float(np.linalg.norm(hi - lo))
    pts = rng.uniform(lo, hi, (n, 3)).astype(np.float32)
    dirs = rng.normal(size=(n, 3)).astype(np.float32)
    row = {"mesh": name, "triangles": len(f), "closed": q.watertight}
    row["ours_unsigned"] = median_seconds(lambda: q.distance(pts), reps)
    row["ours_signed"] = median_seconds(lambda: q.signed_distance(pts), reps)
    row["ours_rays"] = median_seconds(lambda: q.ray_cast(pts, dirs), reps)
    d = q.distance(pts)
    t, *_ = q.ray_cast(pts, dirs)
    row["ours_hits"] = float(np.isfinite(t).mean())
    k = 200 if len(f) < 200000 else 20
    ref = brute_distance(v, f, pts[:k].astype(np.float64))
    row["brute_err"] = float(np.max(np.abs(q.distance(pts[:k].astype(np.float64)) - ref)) / diag)
    if o3d is not None:
        scene = open3d_scene(v, f)
        tp = o3d.core.Tensor(pts)
        rays = o3d.core.Tensor(np.hstack([pts, dirs]))
        row["o3d_unsigned"] = median_seconds(lambda: scene.compute_distance(tp), reps)
        row["o3d_rays"] = median_seconds(lambda: scene.cast_rays(rays), reps)
        od = scene.compute_distance(tp).numpy()
        row["o3d_diff"] = float(np.max(np.abs(od - d)) / diag)
        row["o3d_hits"] = float(np.isfinite(scene.cast_rays(rays)["t_hit"].numpy()).mean())
    res = 128
    t0 = time.perf_counter()
    g = sdftrace.bake(v, f, resolution=res, method="exact", dense=True)
    samples = np.prod([c + 1 for c in g.info["cells"]])
    row["bake_per_sample_us"] = (time.perf_counter() - t0) / samples * 1e6
    row["ours_signed_per_point_us"] = row["ours_signed"] / n * 1e6
    return row, q


def sign_agreement(v, f, q, rng, n=1_000_000):
    """Winding signs against the winding-number bake at 256 cells, points farther than a voxel."""
    g = sdftrace.bake(v, f, resolution=256, sign="winding")
    voxel = g.info["voxel_size"]
    lo, hi = (np.array(b) for b in g.info["bounds"])
    p = rng.uniform(lo, hi, (n, 3))
    d = q.signed_distance(p)
    far = np.abs(d) > voxel
    agree = (d[far] < 0) == (g.sample(p[far].astype(np.float32)) < 0)
    return float(agree.mean()), int(far.sum())


def deepsdf_run(q, n):
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.perf_counter()
    pts, sdf = q.sample_near_surface(n, seed=1)
    seconds = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return seconds, (after - before) / 1024.0, (pts.nbytes + sdf.nbytes) / 2**20


def each_mesh(meshes, n, rng):
    """Per mesh: its name, faces, our MeshQuery, Open3D's scene and n float32 points in its box."""
    for name, v, f in meshes:
        pts = rng.uniform(v.min(0), v.max(0), (n, 3)).astype(np.float32)
        yield name, f, sdftrace.MeshQuery(v, f), open3d_scene(v, f), pts


def distances_only(meshes, n, reps, rng):
    """Unsigned and signed distances against Open3D's unsigned compute_distance, nothing else."""
    print("| mesh | triangles | Open3D compute_distance | ours unsigned | ours signed (winding) |")
    print("| --- | --- | --- | --- | --- |")
    for name, f, q, scene, pts in each_mesh(meshes, n, rng):
        tp = o3d.core.Tensor(pts)
        o = median_seconds(lambda: scene.compute_distance(tp), reps)
        u = median_seconds(lambda: q.distance(pts), reps)
        s = median_seconds(lambda: q.signed_distance(pts), reps)
        print("| %s | %d | %.3f s | %.3f s (%.2fx) | %.3f s (%.2fx) |" % (
            name, len(f), o, u, o / u, s, o / s), flush=True)


def rays_only(meshes, n, reps, rng):
    """Ray casts against Open3D's cast_rays (float32 rays, as both take them), nothing else."""
    print("| mesh | triangles | Open3D cast_rays | ours | hits ours / Open3D |")
    print("| --- | --- | --- | --- | --- |")
    for name, f, q, scene, pts in each_mesh(meshes, n, rng):
        dirs = rng.normal(size=(n, 3)).astype(np.float32)
        rays = o3d.core.Tensor(np.hstack([pts, dirs]))
        o = median_seconds(lambda: scene.cast_rays(rays), reps)
        r = median_seconds(lambda: q.ray_cast(pts, dirs), reps)
        hits = np.isfinite(q.ray_cast(pts, dirs)[0]).mean()
        o3d_hits = np.isfinite(scene.cast_rays(rays)["t_hit"].numpy()).mean()
        print("| %s | %d | %.3f s | %.3f s (%.2fx) | %.1f %% / %.1f %% |" % (
            name, len(f), o, r, o / r, 100 * hits, 100 * o3d_hits), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="100k points, no 1.1M mesh")
    ap.add_argument("--distances", action="store_true",
                    help="only distances against Open3D's compute_distance")
    ap.add_argument("--rays", action="store_true", help="only rays against Open3D's cast_rays")
    ap.add_argument("--reps", type=int, default=3)
    args = ap.parse_args()
    n = 100_000 if args.quick else 1_000_000
    rng = np.random.default_rng(0)
    meshes = [("bunny_npm (closed, 3.7k)", *obj_mesh("data/meshes/bunny_npm.obj")),
              ("stanford-bunny (open scan, 69k)", *obj_mesh("data/meshes/stanford-bunny.obj")),
              ("elephant-with-holes (open, 4.5k)", *obj_mesh("data/meshes/elephant-with-holes.obj")),
              ("thin-walled part (CAD-like, 21k)", *thin_part())]
    if not args.quick:
        meshes.append(("bunny subdivided (scan, 1.1M)",
                       *subdivide(*obj_mesh("data/meshes/stanford-bunny.obj"), 2)))
    if args.distances:
        return distances_only(meshes, n, args.reps, rng)
    if args.rays:
        return rays_only(meshes, n, args.reps, rng)
    print("| mesh | triangles | closed | unsigned: ours / Open3D | signed (winding): ours | "
          "vs Open3D unsigned | rays: ours / Open3D | hits ours / Open3D | max error vs brute "
          "force / vs Open3D (of diagonal) | signed per point / exact bake per sample |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    scan = None
    for name, v, f in meshes:
        r, q = bench_mesh(name, v, f, n, args.reps, rng)
        if "open scan" in name:
            scan = (v, f, q)
        o3u, o3r = r.get("o3d_unsigned", float("nan")), r.get("o3d_rays", float("nan"))
        print("| %s | %d | %s | %.3f / %.3f s (%.2fx) | %.3f s | %.2fx | %.3f / %.3f s (%.2fx) | "
              "%.1f %% / %.1f %% | %.1e / %.1e | %.2f / %.2f us |" % (
                  name, r["triangles"], "yes" if r["closed"] else "no", r["ours_unsigned"], o3u,
                  o3u / r["ours_unsigned"], r["ours_signed"], o3u / r["ours_signed"],
                  r["ours_rays"], o3r, o3r / r["ours_rays"], 100 * r["ours_hits"],
                  100 * r.get("o3d_hits", float("nan")), r["brute_err"],
                  r.get("o3d_diff", float("nan")), r["ours_signed_per_point_us"],
                  r["bake_per_sample_us"]))
    if scan is not None:
        agree, count = sign_agreement(*scan, rng, n)
        print("\nopen scan: winding signs agree with the 256-cell winding-number bake on "
              "%.4f %% of %d points farther than one voxel" % (100 * agree, count))
        seconds, grown, outputs = deepsdf_run(scan[2], 1_000_000 if args.quick else 10_000_000)
        print("DeepSDF sampling, %s points: %.2f s, peak memory grew %.0f MiB for %.0f MiB of "
              "answers" % ("1M" if args.quick else "10M", seconds, grown, outputs))


if __name__ == "__main__":
    main()
