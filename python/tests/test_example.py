"""The notebook-style example runs and writes its pictures."""
import os
import subprocess
import sys


def test_the_example_bakes_slices_renders_and_meshes(root, tmp_path):
    script = root / "examples" / "python" / "bake_slice_render.py"
    run = subprocess.run([sys.executable, str(script), str(root / "data" / "meshes" / "bunny_npm.obj"),
                          str(tmp_path)], capture_output=True, text=True, env=os.environ)
    assert run.returncode == 0, run.stderr
    for name in ["slice.png", "render.png", "steps.png"]:
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG", name
    assert "mesh back:" in run.stdout
