"""Builds sdftrace's Python module with CMake for `pip install .` (pyproject.toml).

The extension `sdftrace._sdftrace` and the plugins it loads (OpenVDB's tools for .vdb output and
meshing, the GPU renderer's kernels where CUDA is built) are built by the project's CMake (Debian's packages, nothing downloaded) and copied into the
package. Environment:
  SDFT_CMAKE_BUILD_DIR  an already configured build tree to build the module in (no configure
                        step; the tests use their own), default build/pip in the checkout
  SDFT_CMAKE_ARGS       extra arguments for the configure step, e.g. "-DSDFT_CUDA=OFF"
  SDFT_JOBS             parallel compile jobs (default: the CPU count)
"""
import glob
import os
import re
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


def project_version():
    text = open(os.path.join(HERE, "CMakeLists.txt"), encoding="utf-8").read()
    return re.search(r"project\(sdftrace VERSION ([0-9.]+)", text).group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.environ.get("SDFT_CMAKE_BUILD_DIR")
        jobs = os.environ.get("SDFT_JOBS", str(os.cpu_count() or 2))
        if not build:
            build = os.path.join(HERE, "build", "pip")
            args = ["cmake", "-S", HERE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                    "-DSDFT_BUILD_TESTS=OFF", "-DSDFT_BUILD_BENCH=OFF", "-DSDFT_PYTHON=ON",
                    "-DPython3_EXECUTABLE=" + sys.executable]
            args += shlex.split(os.environ.get("SDFT_CMAKE_ARGS", ""))
            subprocess.check_call(args)
        # The module's target depends on the plugins it loads (OpenVDB's tools, the GPU kernels).
        subprocess.check_call(["cmake", "--build", build, "-j", jobs, "--target", "sdftrace_python"])
        built = glob.glob(os.path.join(build, "python", "sdftrace", "_sdftrace*.so"))
        if not built:
            raise RuntimeError("sdftrace: the CMake build made no Python module in " + build)
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(built[0], target)
        for plugin in glob.glob(os.path.join(build, "apps", "sdftrace", "libsdftrace_*.so")):
            shutil.copyfile(plugin, os.path.join(os.path.dirname(target), os.path.basename(plugin)))


setup(version=project_version(),
      ext_modules=[Extension("sdftrace._sdftrace", sources=[])],
      cmdclass={"build_ext": CMakeBuild})
