"""Builds penumbra's extension `penumbra._penumbra` with the project's CMake build (pyproject.toml)."""
import os
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    """Configures the CMake project for this interpreter and builds only the extension target. With
    PENUMBRA_CMAKE_BUILD_DIR set, the extension target of that already configured build is used instead."""

    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        jobs = str(os.cpu_count() or 2)
        if os.environ.get("PENUMBRA_CMAKE_BUILD_DIR"):
            build = Path(os.environ["PENUMBRA_CMAKE_BUILD_DIR"]).resolve()
        else:
            build = Path(self.build_temp).resolve() / "cmake"
            build.mkdir(parents=True, exist_ok=True)
            subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                            "-DPython_EXECUTABLE=" + sys.executable, "-DPENUMBRA_BUILD_TESTS=OFF",
                            "-DPENUMBRA_BUILD_BENCH=OFF", "-DPENUMBRA_BUILD_APP=OFF"], check=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "penumbra_python", "-j", jobs], check=True)
        built = next((build / "python" / "penumbra").glob("_penumbra*.so"))
        target.parent.mkdir(parents=True, exist_ok=True)
        self.copy_file(str(built), str(target))


setup(ext_modules=[Extension("penumbra._penumbra", sources=[])], cmdclass={"build_ext": CMakeBuild})
