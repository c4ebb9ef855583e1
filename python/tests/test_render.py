"""Renders from Python: the CLI's images, AOVs, the tracer switches as keywords, their errors."""
import subprocess

import numpy as np
import pytest

import sdftrace


def read_pfm(path):
    """A PFM as sdftrace writes it (rows bottom to top) as top-to-bottom H x W x C."""
    data = open(path, "rb").read()
    header = data.split(b"\n", 3)
    kind, (w, h), scale = header[0], map(int, header[1].split()), float(header[2])
    c = 3 if kind == b"PF" else 1
    img = np.frombuffer(header[3], "<f4" if scale < 0 else ">f4", w * h * c).reshape(h, w, c)
    return img[::-1]


@pytest.mark.parametrize("scene", ["csg.json", "shadows.json", "textures.json"])
def test_a_render_equals_the_cli_render(root, cli, tmp_path, scene):
    path = root / "examples" / scene
    out = tmp_path / "cli.pfm"
    subprocess.run([cli, "render", str(path), "--width", "96", "--height", "64", "-q", "-o",
                    str(out), "--aov", "depth=%s" % (tmp_path / "depth.pfm")], check=True)
    img = sdftrace.render(sdftrace.Scene.load(path), 96, 64, aovs=["color", "depth"])
    np.testing.assert_allclose(img["color"], read_pfm(out), atol=1e-6)
    cli_depth = read_pfm(tmp_path / "depth.pfm")
    assert np.array_equal(np.isfinite(img["depth"]), np.isfinite(cli_depth))
    hit = np.isfinite(cli_depth)
    np.testing.assert_allclose(img["depth"][hit], cli_depth[hit], rtol=1e-6)


def test_aovs_have_their_shapes_and_values():
    names = ["color", "depth", "normal", "steps", "shadow", "ao"]
    img = sdftrace.render(sdftrace.Scene.demo(), 80, 45, aovs=names, ao=True)
    assert sorted(img) == sorted(names)
    assert img["color"].shape == (45, 80, 3) and img["normal"].shape == (45, 80, 3)
    assert img["depth"].shape == (45, 80, 1)
    assert np.isfinite(img["color"]).all()
    hit = np.isfinite(img["depth"][..., 0])
    assert 0.3 < hit.mean() < 1.0
    np.testing.assert_allclose(np.linalg.norm(img["normal"][hit], axis=1), 1.0, atol=1e-3)
    assert (img["steps"][hit] >= 1).all()
    assert ((img["shadow"] >= 0) & (img["shadow"] <= 1)).all()


def test_the_camera_keywords_move_the_view():
    scene = sdftrace.Scene.demo()
    cam = scene.camera
    a = sdftrace.render(scene, 64, 36, aovs=["depth"])["depth"]
    b = sdftrace.render(scene, 64, 36, eye=cam["eye"], target=cam["target"], up=cam["up"],
                        fov=cam["fov"], aovs=["depth"])["depth"]
    np.testing.assert_array_equal(a, b)
    far = np.array(cam["eye"]) * 2 - np.array(cam["target"])
    c = sdftrace.render(scene, 64, 36, eye=far, aovs=["depth"])["depth"]
    hit = np.isfinite(a) & np.isfinite(c)
    assert np.median(c[hit]) > np.median(a[hit])


def test_enhanced_tracing_hits_where_classic_tracing_hits_in_fewer_steps():
    scene = sdftrace.Scene.demo()
    classic, cs = sdftrace.render(scene, 96, 54, aovs=["depth"], classic=True, return_stats=True)
    enhanced, es = sdftrace.render(scene, 96, 54, aovs=["depth"], omega=1.6, return_stats=True)
    same = np.isfinite(classic["depth"]) == np.isfinite(enhanced["depth"])
    assert same.mean() > 0.97  # silhouettes may differ by the half-pixel exit
    assert es["evaluations_per_ray"] < cs["evaluations_per_ray"]
    assert cs["primary_rays"] == 96 * 54 and cs["rays_per_second"] > 0


def test_frames_accumulate_jittered_frames():
    scene = sdftrace.Scene.demo()
    one = sdftrace.render(scene, 64, 36)["color"]
    four = sdftrace.render(scene, 64, 36, frames=4)["color"]
    assert np.isfinite(four).all() and not np.array_equal(one, four)
    assert np.abs(one - four).mean() < 0.05  # the same picture, anti-aliased


def test_bad_keywords_are_value_errors_that_say_what_is_accepted():
    scene = sdftrace.Scene.demo()
    with pytest.raises(ValueError, match="render: shadow_method = 'fuzzy': .*hard, soft"):
        sdftrace.render(scene, 8, 8, shadow_method="fuzzy")
    with pytest.raises(ValueError, match=r"render: omega = 5: .*\[1, 2\)"):
        sdftrace.render(scene, 8, 8, omega=5)
    with pytest.raises(ValueError, match="render: ao = 1: expected True or False"):
        sdftrace.render(scene, 8, 8, ao=1)
    with pytest.raises(ValueError, match="render: omgea: unknown keyword; accepted: .*omega"):
        sdftrace.render(scene, 8, 8, omgea=1.5)
    with pytest.raises(ValueError, match="render: aovs: 'colour'"):
        sdftrace.render(scene, 8, 8, aovs=["colour"])
    with pytest.raises(ValueError, match="render: eye: expected three"):
        sdftrace.render(scene, 8, 8, eye=(1, 2))
    with pytest.raises(ValueError, match="render: width/height"):
        sdftrace.render(scene, 0, 8)
    with pytest.raises(ValueError, match="render: scene: expected"):
        sdftrace.render(42, 8, 8)
    keys = [o["key"] for o in sdftrace.render_options()]
    assert "omega" in keys and "shadow_method" in keys


def test_images_are_written_atomically_in_the_asked_format(tmp_path):
    img = sdftrace.render(sdftrace.Scene.demo(), 40, 30, aovs=["color", "depth"])
    sdftrace.write_image(tmp_path / "c.png", img["color"])
    sdftrace.write_image(tmp_path / "c.exr", img["color"])
    sdftrace.write_image(tmp_path / "d.png", img["depth"][..., 0], label="depth")
    sdftrace.write_image(tmp_path / "s.png", sdftrace.srgb(img["color"]))
    assert (tmp_path / "c.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "c.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"
    with pytest.raises(ValueError, match="write_image: path"):
        sdftrace.write_image(tmp_path / "c.bmp", img["color"])
    with pytest.raises(ValueError, match="4 channels"):
        sdftrace.write_image(tmp_path / "x.png", np.zeros((4, 4, 4), np.float32))
    with pytest.raises(ValueError):
        sdftrace.write_image(tmp_path / "no-such-dir" / "x.png", img["color"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.exr", "c.png", "d.png", "s.png"]


def test_the_device_is_a_keyword_of_render_and_bake():
    """device='cpu' | 'cuda' | 'auto', resolved by the library as the CLI's --device: cuda insists
    (a ValueError saying why not), auto falls back to the CPU with a warning saying why."""
    info = sdftrace.gpu_info()
    assert set(info) >= {"present", "name", "why", "memory_bytes", "compute_capability"}
    scene = sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": 1}]})
    cpu = sdftrace.render(scene, 24, 16, device="cpu")["color"]
    with pytest.raises(ValueError, match=r"render: device = 'tpu': expected one of cpu, cuda, auto"):
        sdftrace.render(scene, 24, 16, device="tpu")
    from conftest import cube_mesh
    v, f = cube_mesh()
    # What the GPU does not bake is refused wherever this runs.
    with pytest.raises(ValueError, match=r"bake: device = 'cuda': .*exact"):
        sdftrace.bake(v, f, resolution=16, method="exact", device="cuda")
    if info["present"]:
        gpu = sdftrace.render(scene, 24, 16, device="cuda")["color"]
        assert np.mean(np.abs(gpu - cpu)) < 2e-3
        return
    assert info["why"]
    with pytest.raises(ValueError, match=r"render: device = 'cuda': "):
        sdftrace.render(scene, 24, 16, device="cuda")
    with pytest.warns(RuntimeWarning, match=r"render: device = 'auto': running on the CPU \("):
        auto = sdftrace.render(scene, 24, 16, device="auto")["color"]
    np.testing.assert_array_equal(auto, cpu)
    with pytest.warns(RuntimeWarning, match=r"bake: device = 'auto': running on the CPU"):
        grid = sdftrace.bake(v, f, resolution=16, method="jfa", device="auto")
    np.testing.assert_array_equal(
        grid.to_numpy(), sdftrace.bake(v, f, resolution=16, method="jfa").to_numpy())
