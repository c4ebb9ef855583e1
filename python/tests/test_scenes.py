"""Scenes from files and dicts: the file format's schema and its one-line errors as ValueError."""
import numpy as np
import pytest

import sdftrace


def test_a_dict_scene_is_the_file_scene(root, tmp_path):
    import json
    desc = json.loads((root / "examples" / "csg.json").read_text())
    a = sdftrace.render(sdftrace.Scene.from_dict(desc), 48, 32)["color"]
    b = sdftrace.render(sdftrace.Scene.load(root / "examples" / "csg.json"), 48, 32)["color"]
    np.testing.assert_array_equal(a, b)


def test_scene_errors_name_the_json_path():
    with pytest.raises(ValueError, match=r"<dict>: /objects/0/radius: .*"):
        sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": -1}]})
    with pytest.raises(ValueError, match=r"<dict>: /objects/0/type"):
        sdftrace.Scene.from_dict({"objects": [{"type": "spheer"}]})
    with pytest.raises(ValueError, match="Scene.from_dict: expected a dict"):
        sdftrace.Scene.from_dict([1, 2])
    with pytest.raises(ValueError, match="not JSON data"):
        sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": float("nan")}]})


def test_missing_and_broken_files_are_named(tmp_path):
    with pytest.raises(ValueError, match="nowhere.json"):
        sdftrace.Scene.load(tmp_path / "nowhere.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"objects": [')
    with pytest.raises(ValueError, match="bad.json"):
        sdftrace.Scene.load(bad)


def test_relative_assets_start_from_base_dir(root):
    desc = {"objects": [{"mesh": "data/meshes/bunny_npm.obj", "resolution": 32}]}
    scene = sdftrace.Scene.from_dict(desc, base_dir=root)
    bounds = scene.field.bounds
    assert bounds is not None
    with pytest.raises(ValueError, match="bunny_npm.obj"):
        sdftrace.Scene.from_dict(desc, base_dir=root / "nowhere")


def test_a_mesh_file_loads_as_a_framed_scene(root):
    scene = sdftrace.Scene.load(root / "data" / "meshes" / "bunny_npm.obj")
    img = sdftrace.render(scene, 40, 30, aovs=["depth"])["depth"]
    assert 0.05 < np.isfinite(img).mean() < 0.95


def test_slices_colour_the_field():
    field = sdftrace.Scene.from_dict({"objects": [{"type": "sphere", "radius": 1.0}]}).field
    d = sdftrace.slice_field(field, axis="z", resolution=64)
    assert d.shape == (64, 64)
    centre, corner = d[32, 32], d[0, 0]
    assert centre < 0 < corner
    rgb = sdftrace.colorize_distance(d)
    assert rgb.shape == (64, 64, 3) and rgb.dtype == np.uint8
    assert rgb[32, 32, 2] > rgb[32, 32, 0] and rgb[0, 0, 0] > rgb[0, 0, 2]  # blue in, orange out
    with pytest.raises(ValueError, match="axis"):
        sdftrace.slice_points(((0, 0, 0), (1, 1, 1)), axis="w")
