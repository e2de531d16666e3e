"""The build step of `pip install .`: configure and build the pybind11 module with CMake.

pyproject.toml holds the metadata; this file only adds the native extension, built by the
project's own CMake (the target `actionshift_python`, libraries only: no tests, benchmarks or CLI)
for the interpreter that runs pip. Environment:

  CMAKE_ARGS                   extra configure arguments, e.g. "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
  CMAKE_BUILD_PARALLEL_LEVEL   compile jobs (default 2)
  ACTIONSHIFT_CMAKE_BUILD_DIR  take the module from this existing, already built CMake tree instead
                               of building one (its module must be built for this interpreter's ABI;
                               nothing is compiled, so the tree is never reconfigured)
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
(ROOT / "build" / "pip").mkdir(parents=True, exist_ok=True)  # setuptools writes its build and egg-info there


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    m = re.search(r"project\(\s*ActionShift\s+VERSION\s+([0-9][0-9.]*)", text)
    if not m:
        sys.exit("setup.py: CMakeLists.txt: no `project(ActionShift VERSION x.y.z)` line")
    return m.group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        reuse = os.environ.get("ACTIONSHIFT_CMAKE_BUILD_DIR")
        if reuse:
            module_dir = Path(reuse).resolve() / "python" / "actionshift"
        else:
            build_dir = Path(self.build_temp).resolve() / "cmake"
            build_dir.mkdir(parents=True, exist_ok=True)
            configure = ["cmake", "-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
                         f"-DPython3_EXECUTABLE={sys.executable}", "-DACTIONSHIFT_PYTHON=ON",
                         "-DACTIONSHIFT_BUILD_TESTS=OFF", "-DACTIONSHIFT_BUILD_BENCHMARKS=OFF",
                         "-DACTIONSHIFT_BUILD_APPS=OFF"] + shlex.split(os.environ.get("CMAKE_ARGS", ""))
            jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
            try:
                subprocess.run(configure, check=True)
                subprocess.run(["cmake", "--build", str(build_dir), "--target", "actionshift_python", "-j", jobs],
                               check=True)
            except FileNotFoundError:
                sys.exit("setup.py: cmake not found (Debian: bash scripts/setup installs it and the libraries)")
            except subprocess.CalledProcessError as e:
                sys.exit(f"setup.py: the CMake build failed ({' '.join(e.cmd[:3])} ... exit {e.returncode}); "
                         "the packages it needs are installed by bash scripts/setup")
            module_dir = build_dir / "python" / "actionshift"
        built = module_dir / f"_native{suffix}"
        if not built.is_file():
            found = sorted(p.name for p in module_dir.glob("_native*")) if module_dir.is_dir() else []
            sys.exit(f"setup.py: {built}: not found (this interpreter needs the suffix {suffix}; "
                     f"found: {', '.join(found) or 'nothing'}){' in ACTIONSHIFT_CMAKE_BUILD_DIR' if reuse else ''}")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)
        os.chmod(target, 0o755)


setup(
    version=project_version(),
    ext_modules=[Extension("actionshift._native", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": "build/pip"}, "egg_info": {"egg_base": "build/pip"}},
    zip_safe=False,
)
