"""Grids: mesh bakes from arrays and files against exact distances, numpy views, files, meshes back."""
import numpy as np
import pytest

import sdftrace
from conftest import box_distance, cube_mesh


def band_points(grid, n=20000, band_voxels=2.0, seed=7):
    """Random points in the grid's box within `band_voxels` of the cube's surface."""
    rng = np.random.default_rng(seed)
    lo, hi = (np.array(b) for b in grid.info["bounds"])
    p = rng.uniform(lo, hi, (n * 4, 3)).astype(np.float32)
    near = np.abs(box_distance(p)) < band_voxels * grid.info["voxel_size"]
    return p[near][:n]


@pytest.mark.parametrize("dense", [True, False])
def test_an_exact_bake_of_a_cube_reads_its_exact_distance(dense):
    v, f = cube_mesh()
    grid = sdftrace.bake(v, f, resolution=40, dense=dense)
    voxel = grid.info["voxel_size"]
    p = band_points(grid)
    err = np.abs(grid.sample(p) - box_distance(p))
    # Trilinear interpolation is exact on the faces' planes; near edges and corners it rounds
    # them off by a fraction of a voxel.
    assert np.mean(err) < 0.02 * voxel
    assert np.max(err) < 0.3 * voxel
    assert grid.info["kind"] == ("dense" if dense else "sparse")


def test_every_method_gets_the_sign_right_away_from_the_surface():
    v, f = cube_mesh()
    p = np.random.default_rng(8).uniform(-0.9, 0.9, (5000, 3)).astype(np.float32)
    exact = box_distance(p)
    far = np.abs(exact) > 0.1
    for method in ["exact", "jfa", "danielsson", "edt", "rtsdf"]:
        grid = sdftrace.bake(v, f, resolution=32, method=method, dense=True)
        d = grid.sample(p)
        assert np.mean(np.sign(d[far]) == np.sign(exact[far])) > 0.99, method
        assert np.mean(np.abs(d[far] - exact[far])) < 2 * grid.info["voxel_size"], method


def test_a_bake_from_a_file_equals_the_bake_from_its_arrays(tmp_path):
    v, f = cube_mesh()
    obj = tmp_path / "cube.obj"
    obj.write_text("".join("v %r %r %r\n" % tuple(map(float, p)) for p in v) +
                   "".join("f %d %d %d\n" % tuple(t + 1) for t in f))
    a = sdftrace.bake(v, f, resolution=24, dense=True).to_numpy()
    b = sdftrace.bake(obj, resolution=24, dense=True).to_numpy()
    np.testing.assert_array_equal(a, b)


def test_to_numpy_is_a_read_only_view_indexed_by_vertex():
    v, f = cube_mesh()
    grid = sdftrace.bake(v, f, resolution=20, dense=True)
    a = grid.to_numpy()
    info = grid.info
    assert a.shape == tuple(c + 1 for c in info["cells"])
    assert not a.flags.writeable and a.base is not None  # the grid's own samples
    ijk = np.array([[3, 5, 7], [10, 2, 19], [0, 0, 0]])
    pts = (np.array(info["origin"]) + ijk * info["voxel_size"]).astype(np.float32)
    np.testing.assert_allclose(grid.sample(pts), a[ijk[:, 0], ijk[:, 1], ijk[:, 2]], atol=1e-6)
    del grid  # the view keeps the samples alive
    assert np.isfinite(a).all()


def test_a_sparse_grid_keeps_the_band_in_less_memory():
    v, f = cube_mesh()
    dense = sdftrace.bake(v, f, resolution=64, dense=True)
    sparse = sdftrace.bake(v, f, resolution=64, band=3)
    assert sparse.info["memory_bytes"] < dense.info["memory_bytes"]
    assert sparse.info["blocks"]["surface"] > 0
    # cells whose corners are all within the 3-voxel band: points within 3 - sqrt(3) voxels
    voxel = sparse.info["voxel_size"]
    p = band_points(sparse, band_voxels=1.2)
    err = np.abs(sparse.sample(p) - box_distance(p))
    assert np.mean(err) < 0.02 * voxel and np.max(err) < 0.3 * voxel
    # every vertex in the band holds the exact distance; the others are clamped to the band
    # (3 voxels) or read +-background in the dropped blocks, with the right sign
    a = sparse.to_numpy()
    info = sparse.info
    ijk = np.indices(a.shape).reshape(3, -1).T
    exact = box_distance(np.array(info["origin"]) + ijk * voxel).reshape(a.shape)
    band = np.abs(exact) < 2.5 * voxel
    np.testing.assert_allclose(a[band], exact[band], atol=1e-3 * voxel)
    assert np.all(np.abs(a[~band]) <= 3 * voxel * (1 + 1e-5))
    assert np.all(np.sign(a[~band]) == np.sign(exact[~band]))


@pytest.mark.parametrize("ext", ["sdfg", "vdb"])
def test_grids_survive_their_files(tmp_path, ext):
    v, f = cube_mesh()
    grid = sdftrace.bake(v, f, resolution=24)
    path = tmp_path / ("cube." + ext)
    grid.save(path)
    back = sdftrace.Grid.load(path)
    p = band_points(grid, band_voxels=2.0)
    # .sdfg keeps the samples; .vdb keeps OpenVDB's voxels (the same floats) but sdftrace's
    # reader rebuilds the blocks' aprons from them, within float rounding
    tol = 1e-6 if ext == "sdfg" else 1e-3 * grid.info["voxel_size"]
    np.testing.assert_allclose(back.sample(p), grid.sample(p), atol=tol)
    assert back.info["cells"] == grid.info["cells"]


def test_from_numpy_round_trips_and_samples_trilinearly():
    x = np.linspace(-1, 1, 17)
    X, Y, Z = np.meshgrid(x, x, x, indexing="ij")
    values = (np.sqrt(X**2 + Y**2 + Z**2) - 0.6).astype(np.float32)
    grid = sdftrace.Grid.from_numpy(values, origin=(-1, -1, -1), voxel_size=0.125)
    np.testing.assert_array_equal(grid.to_numpy(), values)
    p = np.array([[0.0625, 0.0, 0.0]], np.float32)  # halfway between two vertices
    i = 8
    expected = 0.5 * (values[i, i, i] + values[i + 1, i, i])
    np.testing.assert_allclose(grid.sample(p), [expected], atol=1e-6)
    sparse = sdftrace.Grid.from_numpy(values, origin=(-1, -1, -1), voxel_size=0.125, sparse=True)
    assert sparse.info["kind"] == "sparse"


def test_to_mesh_gives_back_the_cube():
    v, f = cube_mesh()
    grid = sdftrace.bake(v, f, resolution=32)
    verts, faces = grid.to_mesh()
    assert verts.dtype == np.float32 and faces.dtype == np.int32
    assert len(faces) > 100 and faces.max() < len(verts)
    voxel = grid.info["voxel_size"]
    # on the faces the vertices lie on the surface; trilinear interpolation rounds the cube's
    # edges and corners off by under a voxel
    err = np.abs(box_distance(verts))
    assert np.median(err) < 0.02 * voxel and np.max(err) < voxel
    # outward winding: the mesh's signed volume is the cube's
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    volume = np.sum(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6
    assert abs(volume - 1.0) < 0.05
    fewer = grid.to_mesh(adaptivity=0.8)[1]
    assert len(fewer) < len(faces)


def test_a_baked_grid_is_a_field_and_renders():
    v, f = cube_mesh()
    grid = sdftrace.bake(v, f, resolution=32)
    # in the band the field reads the samples divided by the reconstruction's Lipschitz bound
    # (a 1-Lipschitz field for the tracer), or the gap lattice's bound of the distance where that
    # is larger (a few points by the cube's corners, where L is largest); elsewhere both are
    # bounds (the field's: at least the distance to the grid's box outside it)
    p = band_points(grid, 2000, band_voxels=1.0)
    L = grid.info["lipschitz"]
    assert L >= 1.0
    field, sample = grid.field.evaluate(p), grid.sample(p)
    assert (np.sign(field) == np.sign(sample)).all()
    assert (np.abs(field) * L >= np.abs(sample) - 1e-5).all()
    assert np.isclose(field * L, sample, atol=1e-5).mean() > 0.99
    img = sdftrace.render(grid, 48, 32, aovs=["color", "depth"])
    assert img["color"].shape == (32, 48, 3) and np.isfinite(img["color"]).all()
    assert np.isfinite(img["depth"]).mean() > 0.05


def test_bad_meshes_and_options_are_value_errors():
    v, f = cube_mesh()
    with pytest.raises(ValueError, match=r"bake: faces: face 0 names vertex 99; expected indices in \[0, 8\)"):
        sdftrace.bake(v, np.array([[0, 1, 99]]))
    with pytest.raises(ValueError, match="bake: method = 'magic': unknown value 'magic'; accepted: exact, jfa"):
        sdftrace.bake(v, f, method="magic")
    with pytest.raises(ValueError, match="bake: sign"):
        sdftrace.bake(v, f, sign="guess")
    with pytest.raises(ValueError, match="bake: resolution"):
        sdftrace.bake(v, f, resolution=1)
    with pytest.raises(ValueError, match="bake: vertices: expected an N x 3"):
        sdftrace.bake(v[:, :2], f)
    with pytest.raises(ValueError, match="bake: faces"):
        sdftrace.bake(v)
    with pytest.raises(ValueError, match="no triangle with area"):
        sdftrace.bake(v, np.array([[0, 0, 1]]))
    with pytest.raises(ValueError, match="missing.obj"):
        sdftrace.bake("missing.obj")


def write_cube_obj(path):
    v, f = cube_mesh()
    path.write_text("".join("v %r %r %r\n" % tuple(map(float, p)) for p in v) +
                    "".join("f %d %d %d\n" % tuple(t + 1) for t in f))
    return path


@pytest.mark.parametrize("options", [
    {},  # every default
    {"resolution": 24, "method": "jfa", "jfa_variant": "1+jfa", "block": 8, "band": 4,
     "padding": 1},
    {"resolution": 20, "method": "rtsdf", "rays": 8, "mask": 2, "dense": True},
])
def test_the_cli_a_scene_file_and_python_bake_alike_from_one_option_table(cli, tmp_path, options):
    """One table of bake options: the same keys give the same grid through sdftrace.bake, a scene
    file's mesh object and `sdftrace bake`'s flags, and the defaults agree."""
    import json
    import subprocess
    obj = write_cube_obj(tmp_path / "cube.obj")
    ours = sdftrace.bake(obj, **options)
    flags = []
    for key, value in options.items():
        if value is True:
            flags.append("--" + key)
        else:
            flags += ["--" + key.replace("_", "-"), str(value)]
    subprocess.run([cli, "bake", str(obj), "-o", str(tmp_path / "cli.sdfg"), "-q"] + flags,
                   check=True, capture_output=True)
    theirs = sdftrace.Grid.load(tmp_path / "cli.sdfg")
    scene = sdftrace.Scene.from_dict({"objects": [dict({"mesh": str(obj)}, **options)]})
    at = np.random.default_rng(3).uniform(-0.7, 0.7, (4000, 3)).astype(np.float32)
    assert ours.info["cells"] == theirs.info["cells"]
    assert ours.info["kind"] == theirs.info["kind"]
    np.testing.assert_array_equal(ours.sample(at), theirs.sample(at))
    # The scene's field is the grid's samples over its Lipschitz bound, as Grid.field reads them.
    np.testing.assert_allclose(scene.field.evaluate(at), ours.field.evaluate(at), atol=1e-6)


def test_bad_bake_options_name_the_keyword_and_what_is_accepted():
    v, f = cube_mesh()
    with pytest.raises(ValueError, match=r"bake: block = 6: unknown value '6'; accepted: 4, 8"):
        sdftrace.bake(v, f, block=6)
    with pytest.raises(ValueError, match=r"bake: band = 1: expected a half-width in voxels in \[2, 64\]"):
        sdftrace.bake(v, f, band=1)
    with pytest.raises(ValueError, match=r"bake: rays = 0: expected an integer in \[1, 4096\]"):
        sdftrace.bake(v, f, method="rtsdf", rays=0)
    with pytest.raises(ValueError, match=r"to_grid: padding = -1"):
        sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": 1}]}).field.to_grid(padding=-1)


def test_bad_grid_files_are_value_errors(tmp_path):
    junk = tmp_path / "junk.sdfg"
    junk.write_bytes(b"not a grid at all")
    with pytest.raises(ValueError, match="junk.sdfg"):
        sdftrace.Grid.load(junk)
    v, f = cube_mesh()
    with pytest.raises(ValueError, match="unknown grid file extension"):
        sdftrace.bake(v, f, resolution=8).save(tmp_path / "cube.txt")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["junk.sdfg"]  # nothing half-written


def test_damaged_mesh_files_are_value_errors_naming_the_file(tmp_path):
    """The CLI's readers: a PLY cut short, a binary STL whose count does not fit, an OFF index
    past its vertices, an OBJ index before its first vertex: one ValueError each, naming the file
    and what is wrong."""
    import struct
    ply = tmp_path / "cut.ply"
    ply.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\n"
                    b"property float x\nproperty float y\nproperty float z\nelement face 2000\n"
                    b"property list uchar int vertex_indices\nend_header\n" + struct.pack("<9f", *range(9)))
    with pytest.raises(ValueError, match=r"cut.ply: PLY: the header declares 1000 vertex and 2000 face"):
        sdftrace.bake(ply, resolution=8)
    stl = tmp_path / "short.stl"
    stl.write_bytes(b"\0" * 80 + struct.pack("<I", 12) + b"\0" * 100)
    with pytest.raises(ValueError, match=r"short.stl: STL: binary STL declares 12 triangles"):
        sdftrace.bake(stl, resolution=8)
    off = tmp_path / "index.off"
    off.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
    with pytest.raises(ValueError, match=r"index.off:6: OFF: face 0 uses vertex 7, but there are 3"):
        sdftrace.bake(off, resolution=8)
    obj = tmp_path / "index.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n")
    with pytest.raises(ValueError, match=r"index.obj:4: OBJ: a face uses vertex -4 with 3 vertices read"):
        sdftrace.bake(obj, resolution=8)
