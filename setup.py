"""The build of `pip install .` (pyproject.toml; python/README.md, "Install
with pip"): setuptools packs python/hamal, python/examples (as
hamal.examples) and what CMake builds and installs as the component
python_wheel (python/CMakeLists.txt): the extension _hamal, its stubs, the
generated _version.py and libhamal beside them.

Which CMake build tree:
- HAMAL_CMAKE_BUILD_DIR=<dir>, an existing configured tree (CI's, or a
  developer's `build`): only the module's targets are brought up to date,
  nothing else is rebuilt;
- else a Release tree of its own, <setuptools build dir>/cmake, configured
  for the Python running pip and building the module's targets only (the
  first install compiles the library: minutes).

setuptools' own build directory is `build-pip` in the checkout, or `pip/`
inside HAMAL_CMAKE_BUILD_DIR, never CMake's `build/` itself.
"""

import os
import re
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))
CMAKE_BUILD_DIR = os.environ.get("HAMAL_CMAKE_BUILD_DIR")


def cmake_project_version():
    """project(hamal VERSION x.y.z) of CMakeLists.txt: the one place the version is written."""
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        match = re.search(r"^project\(hamal\s+VERSION\s+([0-9][0-9.]*)", f.read(), flags=re.M)
    if not match:
        sys.exit("setup.py: no project(hamal VERSION ...) in CMakeLists.txt")
    return match.group(1)


def cmake(*args):
    print("setup.py: cmake " + " ".join(args), flush=True)
    subprocess.run(["cmake", *args], check=True)


class CMakeBuild(build_ext):
    """Builds the extension with CMake and copies the component python_wheel
    into the package."""

    def run(self):
        if self.inplace:
            sys.exit("setup.py: editable installs are not supported; use PYTHONPATH=build/python "
                     "(python/README.md)")
        if shutil.which("cmake") is None:
            sys.exit("setup.py: cmake not found (scripts/setup.sh installs the Debian packages)")
        if CMAKE_BUILD_DIR:
            tree = os.path.abspath(CMAKE_BUILD_DIR)
        else:
            tree = os.path.abspath(os.path.join(self.build_temp, "cmake"))
            configure = ["-S", ROOT, "-B", tree, "-DCMAKE_BUILD_TYPE=Release",
                         "-DHAMAL_BUILD_TESTS=OFF", "-DHAMAL_BUILD_PYTHON=ON",
                         f"-DPython3_EXECUTABLE={sys.executable}"]
            if shutil.which("ccache"):
                configure.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
            cmake(*configure)
        build = ["--build", tree, "--target", "hamal_python", "hamal_python_stubs"]
        if "CMAKE_BUILD_PARALLEL_LEVEL" not in os.environ:
            build += ["--parallel", str(os.cpu_count() or 1)]
        cmake(*build)
        stage = os.path.abspath(os.path.join(self.build_temp, "stage"))
        shutil.rmtree(stage, ignore_errors=True)
        cmake("--install", tree, "--component", "python_wheel", "--prefix", stage)

        staged = os.path.join(stage, "hamal")
        module = "_hamal" + sysconfig.get_config_var("EXT_SUFFIX")
        if not os.path.isfile(os.path.join(staged, module)):
            found = [f for f in os.listdir(staged) if f.startswith("_hamal.") and f != "_hamal.pyi"]
            sys.exit(f"setup.py: the CMake tree {tree} built {found or 'no module'}, not {module} for "
                     f"{sys.executable}; configure it with -DPython3_EXECUTABLE={sys.executable}")
        if not os.path.isfile(os.path.join(staged, "_hamal.pyi")):
            sys.exit(f"setup.py: the CMake tree {tree} made no stubs (_hamal.pyi): install python3-mypy "
                     "and configure it again")
        package = os.path.join(self.build_lib, "hamal")
        os.makedirs(package, exist_ok=True)
        for name in os.listdir(staged):
            shutil.copy2(os.path.join(staged, name), os.path.join(package, name))


if CMAKE_BUILD_DIR and not os.path.isfile(os.path.join(CMAKE_BUILD_DIR, "CMakeCache.txt")):
    sys.exit(f"setup.py: HAMAL_CMAKE_BUILD_DIR={CMAKE_BUILD_DIR} is not a configured CMake build tree")
# setuptools' build and egg-info directories, away from CMake's build/.
BUILD_BASE = (os.path.join(os.path.abspath(CMAKE_BUILD_DIR), "pip") if CMAKE_BUILD_DIR
              else os.path.join(ROOT, "build-pip"))
os.makedirs(BUILD_BASE, exist_ok=True)

setup(
    version=cmake_project_version(),
    packages=["hamal", "hamal.examples"],
    package_dir={"hamal": "python/hamal", "hamal.examples": "python/examples"},
    # The extension's sources and flags are CMake's; this entry makes the
    # wheel a platform wheel and runs CMakeBuild.
    ext_modules=[Extension("hamal._hamal", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": BUILD_BASE}, "egg_info": {"egg_base": BUILD_BASE}},
    zip_safe=False,
)
