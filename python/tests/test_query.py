"""MeshQuery: exact distances, signs, closest points, winding numbers, ray casts and sampling of a
mesh at numpy points, against closed-form answers (a cube) and a brute-force reference (a scan)."""
import subprocess
import threading

import numpy as np
import pytest

import sdftrace
from conftest import box_distance, cube_mesh


def obj_mesh(path):
    """Vertices and triangles of a plain OBJ (v lines, f lines; polygons fanned)."""
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
    return np.array(v), np.array(f)


def brute_distance(v, f, p):
    """Unsigned distance of each point to the triangles, by projecting onto every triangle's
    plane, edges and corners (float64 numpy, O(points x triangles))."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    best = np.full(len(p), np.inf)
    for i, x in enumerate(p):
        n = np.cross(b - a, c - a)
        nn = np.einsum("ij,ij->i", n, n)
        d = np.einsum("ij,ij->i", x - a, n) / nn
        q = x - d[:, None] * n
        # Inside test of the projection by edge signs.
        s1 = np.einsum("ij,ij->i", np.cross(b - a, q - a), n)
        s2 = np.einsum("ij,ij->i", np.cross(c - b, q - b), n)
        s3 = np.einsum("ij,ij->i", np.cross(a - c, q - c), n)
        inside = (s1 >= 0) & (s2 >= 0) & (s3 >= 0)
        dist = np.where(inside, np.abs(d) * np.sqrt(nn), np.inf)
        for e0, e1 in ((a, b), (b, c), (c, a)):
            e = e1 - e0
            t = np.clip(np.einsum("ij,ij->i", x - e0, e) / np.einsum("ij,ij->i", e, e), 0, 1)
            dist = np.minimum(dist, np.linalg.norm(x - (e0 + t[:, None] * e), axis=1))
        best[i] = dist.min()
    return best


@pytest.fixture
def cube():
    v, f = cube_mesh()
    return sdftrace.MeshQuery(v, f)


def test_signed_distances_of_a_cube_are_exact_under_every_sign_rule(cube):
    rng = np.random.default_rng(1)
    p = rng.uniform(-1.5, 1.5, (20000, 3))
    truth = box_distance(p)
    for sign in ("winding", "parity", "pseudonormal"):
        d = cube.signed_distance(p, sign=sign)
        assert d.dtype == np.float64 and d.shape == (20000,)
        np.testing.assert_allclose(d, truth, atol=1e-12)
    np.testing.assert_allclose(cube.distance(p), np.abs(truth), atol=1e-12)
    assert cube.watertight
    assert (cube.contains(p) == (truth < 0)).all()
    np.testing.assert_allclose(cube.winding_number(p), (truth < 0).astype(float), atol=1e-9)


def test_float32_in_float32_out(cube):
    p = np.random.default_rng(2).uniform(-1, 1, (1000, 3)).astype(np.float32)
    d = cube.signed_distance(p)
    assert d.dtype == np.float32
    np.testing.assert_allclose(d, box_distance(p.astype(np.float64)), atol=1e-6)
    pts, faces, bary = cube.closest_points(p)
    assert pts.dtype == np.float32 and faces.dtype == np.int64 and bary.dtype == np.float32


def test_closest_points_and_barycentrics_of_a_scan_match_brute_force(root):
    v, f = obj_mesh(root / "data/meshes/suzanne.obj")
    q = sdftrace.MeshQuery(v, f)
    rng = np.random.default_rng(3)
    lo, hi = v.min(0), v.max(0)
    p = rng.uniform(lo - 0.3, hi + 0.3, (300, 3))
    d = q.distance(p)
    np.testing.assert_allclose(d, brute_distance(v, f, p), atol=1e-6 * np.linalg.norm(hi - lo))
    pts, faces, bary = q.closest_points(p)
    corners = v[f[faces]]  # N x 3 corners x 3
    np.testing.assert_allclose(np.einsum("ij,ijk->ik", bary, corners), pts, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(p - pts, axis=1), d, atol=1e-12)
    assert not q.watertight


def test_ray_casts_hit_the_cube_where_the_slab_test_says(cube):
    rng = np.random.default_rng(4)
    o = rng.uniform(-3, 3, (5000, 3))
    d = rng.normal(size=(5000, 3))
    t, face, bary, normal = cube.ray_cast(o, d)
    # Slab test against [-0.5, 0.5]^3 (t in units of the direction's length).
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (-0.5 - o) / d
        t1 = (0.5 - o) / d
    tnear = np.max(np.minimum(t0, t1), axis=1)
    tfar = np.min(np.maximum(t0, t1), axis=1)
    hit = (tfar >= np.maximum(tnear, 0))
    entry = np.where(tnear > 0, tnear, tfar)
    assert (np.isfinite(t) == hit).all()
    np.testing.assert_allclose(t[hit], entry[hit], rtol=1e-6, atol=1e-9)
    assert (face[~hit] == -1).all() and (face[hit] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(normal[hit], axis=1), 1, atol=1e-12)
    t2, *_ = cube.ray_cast(o, d, t_max=1.0)
    assert (np.isfinite(t2) == (hit & (entry <= 1.0))).all()


def test_sampling_is_reproducible_and_signed(cube):
    p, n, faces = cube.sample_surface(5000, seed=5)
    assert p.shape == (5000, 3) and p.dtype == np.float32
    np.testing.assert_allclose(np.abs(box_distance(p.astype(np.float64))), 0, atol=1e-6)
    p2, *_ = cube.sample_surface(5000, seed=5)
    assert (p == p2).all()
    pts, sdf = cube.sample_near_surface(20000, sigmas=[0.05, 0.005], seed=6, dtype=np.float64)
    assert pts.dtype == np.float64
    np.testing.assert_allclose(sdf, box_distance(pts), atol=1e-12)
    assert 0.3 < np.mean(sdf < 0) < 0.7
    pts, sdf = cube.sample_volume(20000, bounds=((-1, -1, -1), (1, 1, 1)), seed=7)
    assert pts.min() >= -1 and pts.max() <= 1
    np.testing.assert_allclose(sdf, box_distance(pts.astype(np.float64)), atol=1e-6)
    assert abs(np.mean(sdf < 0) - 1 / 8) < 0.02  # the cube fills an eighth of the box


def test_calls_from_several_threads_agree(cube):
    p = np.random.default_rng(8).uniform(-1, 1, (50000, 3))
    want = cube.signed_distance(p)
    got = [None] * 4

    def work(i):
        got[i] = cube.signed_distance(p)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for g in got:
        assert (g == want).all()


@pytest.mark.parametrize("call, message", [
    (lambda q: q.distance(np.zeros((4, 2))), "distance: points: expected an N x 3 array"),
    (lambda q: q.distance([[0, 0, np.nan]]), "distance: points: row 0 is not finite"),
    (lambda q: q.signed_distance(np.zeros((1, 3)), sign="ray"), "sign = 'ray'"),
    (lambda q: q.ray_cast(np.zeros((2, 3)), np.ones((3, 3))), "ray_cast: directions: 3 rows"),
    (lambda q: q.ray_cast(np.zeros((2, 3)), np.ones((2, 3)), t_max=-1), "t_max"),
    (lambda q: q.sample_near_surface(10, sigmas=[-1.0]), "sigmas"),
    (lambda q: q.sample_volume(10, bounds=((1, 1, 1), (0, 0, 0))), "bounds"),
    (lambda q: q.sample_surface(10, dtype=np.int32), "dtype"),
    (lambda q: q.distance("points"), "distance: points"),
])
def test_bad_input_raises_value_error_naming_the_argument(cube, call, message):
    with pytest.raises(ValueError, match=message):
        call(cube)


def test_bad_meshes_raise_value_error():
    v, f = cube_mesh()
    with pytest.raises(ValueError, match="face 0 names vertex 8"):
        sdftrace.MeshQuery(v, np.array([[0, 1, 8]]))
    with pytest.raises(ValueError, match="no face"):
        sdftrace.MeshQuery(v, np.zeros((0, 3), np.int32))
    bad = v.copy()
    bad[2, 1] = np.inf
    with pytest.raises(ValueError, match="vertex 2"):
        sdftrace.MeshQuery(bad, f)
    with pytest.raises(ValueError, match="faces"):
        sdftrace.MeshQuery(v, f.astype(np.float32))


def test_the_cli_writes_what_the_module_computes(cli, tmp_path, root):
    mesh = root / "data/meshes/suzanne.obj"
    v, f = obj_mesh(mesh)
    q = sdftrace.MeshQuery(v, f)
    p = np.random.default_rng(9).uniform(-1.5, 1.5, (2000, 3))
    np.save(tmp_path / "p.npy", p)
    subprocess.run([cli, "query", str(mesh), str(tmp_path / "p.npy"), "-o",
                    str(tmp_path / "r.npz"), "--closest", "-q"], check=True)
    r = np.load(tmp_path / "r.npz")
    assert set(r.files) == {"sdf", "closest", "face", "barycentric"}
    # The CLI's mesh is read in float32 (the loaders' precision): within float rounding.
    np.testing.assert_allclose(r["sdf"], q.signed_distance(p), atol=1e-6)
    np.savetxt(tmp_path / "p.csv", p[:10], delimiter=",", header="x,y,z", comments="")
    subprocess.run([cli, "query", str(mesh), str(tmp_path / "p.csv"), "-o",
                    str(tmp_path / "r.csv"), "--sign", "none", "-q"], check=True)
    back = np.loadtxt(tmp_path / "r.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(back, q.distance(p[:10]), atol=1e-6)
