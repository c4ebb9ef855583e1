"""The package as a user meets it: its version, its build information, a docstring that explains
every parameter of every public function and method, type stubs that match the module, and
`pip install .` into a fresh virtual environment."""
import inspect
import os
import re
import shutil
import subprocess
import sys
import tempfile

import pytest

import sdftrace
from conftest import ROOT


def test_version_is_the_projects():
    cmake = (ROOT / "CMakeLists.txt").read_text()
    assert sdftrace.__version__ == re.search(r"project\(sdftrace VERSION ([0-9.]+)", cmake).group(1)
    info = sdftrace.build_info()
    assert info["version"] == sdftrace.__version__
    assert isinstance(info["cuda"], bool) and info["simd"] in ("avx2", "sse2")


def _parameters(func):
    """Parameter names from pybind11's signature line, or from Python's own signature."""
    doc = func.__doc__ or ""
    first = doc.splitlines()[0] if doc else ""
    m = re.match(r"\w+\((.*)\) ->", first)
    if m:
        names = re.findall(r"(?:^|,\s*)\*{0,2}(\w+)\s*:", m.group(1))
        return [n for n in names if n != "self"]
    try:
        return [p for p in inspect.signature(func).parameters if p != "self"]
    except (TypeError, ValueError):
        return []


def _public_callables():
    for name in sdftrace.__all__:
        obj = getattr(sdftrace, name)
        if inspect.isclass(obj):
            for mname, member in vars(obj).items():
                if mname.startswith("_"):
                    continue
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                if isinstance(member, property):
                    yield "%s.%s" % (name, mname), member.fget, False
                elif callable(member):
                    yield "%s.%s" % (name, mname), member, True
            yield name, obj, False
        elif callable(obj):
            yield name, obj, True


def test_every_public_function_documents_each_parameter():
    missing = []
    for name, func, has_params in _public_callables():
        doc = func.__doc__ or ""
        text = "\n".join(doc.splitlines()[1:]) if re.match(r"\w+\(.*\) ->", doc) else doc
        if len(text.strip()) < 20:
            missing.append("%s: no docstring" % name)
            continue
        if has_params:
            for p in _parameters(func):
                if not re.search(r"\b%s\b" % re.escape(p), text):
                    missing.append("%s: parameter '%s' not explained" % (name, p))
    assert not missing, "\n".join(missing)


def test_stubs_match_the_module():
    script = ROOT / "scripts" / "make-python-stubs.py"
    r = subprocess.run([sys.executable, str(script), "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (ROOT / "python" / "sdftrace" / "py.typed").exists()


@pytest.mark.skipif(not os.environ.get("SDFT_BUILD_DIR"), reason="run through ctest")
def test_pip_install_into_a_fresh_environment():
    """`pip install .` offline with Debian's pip and setuptools, into a virtual environment that
    sees the system's numpy; the module then imports from another directory. The build tree the
    tests use is reused (SDFT_CMAKE_BUILD_DIR), so nothing is compiled twice."""
    if not os.path.exists("/usr/bin/python3"):
        pytest.skip("Debian's python3 not found")
    with tempfile.TemporaryDirectory() as work:
        venv = os.path.join(work, "venv")
        subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", venv],
                       check=True)
        py = os.path.join(venv, "bin", "python")
        env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        env["SDFT_CMAKE_BUILD_DIR"] = os.environ["SDFT_BUILD_DIR"]
        env["PIP_NO_INDEX"] = "1"  # offline: nothing may be downloaded
        src = os.path.join(work, "src")
        # A copy of the checkout, as pip builds in the source tree.
        shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns("build", ".git", "fuzz"))
        r = subprocess.run([py, "-m", "pip", "install", "--no-build-isolation", "--no-deps",
                            src], env=env, capture_output=True, text=True, cwd=work)
        assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
        r = subprocess.run([py, "-c", "import sdftrace, numpy as np; "
                            "print(sdftrace.__version__, sdftrace.__file__); "
                            "s = sdftrace.Scene.from_dict({'objects': [{'type': 'sphere', 'radius': 1}]}); "
                            "print(float(s.field.evaluate(np.array([[0, 0, 3.0]]))[0]))"],
                           env=env, capture_output=True, text=True, cwd=work)
        assert r.returncode == 0, r.stderr
        version, path = r.stdout.split()[:2]
        assert version == sdftrace.__version__
        assert path.startswith(venv), path
        assert abs(float(r.stdout.split()[2]) - 2.0) < 1e-5
