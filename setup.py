"""`pip install .`: the compiled core `budjam._budjam` comes from the project's own CMake build
(only the libraries and the module: no tests, no benchmarks, no executable; a unity build, which
halves the compile time); the package's Python files come from python/budjam. The interpreter that
runs pip is the one CMake builds for.

Environment: CMAKE_BUILD_PARALLEL_LEVEL (build jobs, default: all cores), BUDJAM_CMAKE_ARGS (extra
configure options, e.g. "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"). The CMake build directory is
build-pip/ beside this file, so that a second install rebuilds only what changed."""
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


def project_version():
    """The version of project(budjam VERSION ...) in CMakeLists.txt, which the module reports too."""
    match = re.search(r"project\(budjam VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    if not match:
        sys.exit("setup.py: no 'project(budjam VERSION x.y.z' in CMakeLists.txt")
    return match.group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = ROOT / "build-pip"
        configure = ["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                     f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF", "-DBUDJAM_BENCHMARKS=OFF",
                     "-DBUDJAM_UNITY_BUILD=ON",
                     *shlex.split(os.environ.get("BUDJAM_CMAKE_ARGS", ""))]
        subprocess.run(configure, check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build), "--target", "budjam_python", "-j", jobs], check=True)
        built = list((build / "python" / "budjam").glob("_budjam*.so"))
        if len(built) != 1:
            sys.exit(f"setup.py: expected one compiled module in {build}/python/budjam, found {built}")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


setup(version=project_version(), packages=["budjam"], package_dir={"budjam": "python/budjam"},
      ext_modules=[Extension("budjam._budjam", sources=[])], cmdclass={"build_ext": CMakeBuild})
