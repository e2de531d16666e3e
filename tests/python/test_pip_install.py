"""`pip install` of the package into a fresh virtual environment, offline.

What this checks: pyproject.toml and setup.py (the build backend pip runs, with --no-build-isolation
and --no-index, so nothing can be downloaded) install the package into a new
`python3 -m venv --system-site-packages` environment, both as `pip install .` and `pip install -e .`;
the installed package (not the build tree's copy: PYTHONPATH is cleared) imports, its
`__version__` equals `importlib.metadata.version("actionshift")` and the CMake project's version,
and an environment steps. What it does not: compile the module from scratch. A fresh `pip install .`
runs CMake on the whole library (a quarter of an hour or more on two cores); here setup.py takes the module
this ctest build tree already compiled (ACTIONSHIFT_CMAKE_BUILD_DIR), which is the same target,
built by the same CMake code for the same interpreter. The source is copied first, so the checkout
is not written to.
"""
import os
import re
import shutil
import subprocess
import sys
import venv

import pytest

BUILD_DIR = os.environ.get("ACTIONSHIFT_BUILD_DIR")


def _run(cmd, env, cwd=None):
    p = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, f"{' '.join(map(str, cmd))}: exit {p.returncode}\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    return p.stdout


def _copy_source(src, dst):
    keep = ("CMakeLists.txt", "pyproject.toml", "setup.py", "README.md", "LICENSE", "python")
    os.makedirs(dst)
    for name in keep:
        s = os.path.join(src, name)
        (shutil.copytree if os.path.isdir(s) else shutil.copy2)(
            s, os.path.join(dst, name), **({"ignore": shutil.ignore_patterns("*.so", "__pycache__")} if os.path.isdir(s) else {}))


@pytest.mark.parametrize("editable", [False, True], ids=["install", "editable"])
def test_pip_install_into_a_fresh_venv_offline(tmp_path, source_dir, editable):
    if not BUILD_DIR:
        pytest.fail("ACTIONSHIFT_BUILD_DIR is not set (run this test through ctest)")
    src = tmp_path / "src"
    _copy_source(source_dir, src)
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(system_site_packages=True, with_pip=True).create(env_dir)
    py = str(env_dir / "bin" / "python")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PIP_INDEX_URL", "PIP_EXTRA_INDEX_URL")}
    env.update(ACTIONSHIFT_CMAKE_BUILD_DIR=BUILD_DIR, PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1",
               PYTHONDONTWRITEBYTECODE="1")
    args = [py, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-deps"]
    _run(args + (["-e", str(src)] if editable else [str(src)]), env, cwd=tmp_path)
    cmake_version = re.search(r"project\(ActionShift VERSION ([0-9.]+)", open(src / "CMakeLists.txt").read()).group(1)
    out = _run([py, "-c", """
import importlib.metadata, os, sys
import numpy as np
import actionshift
print(actionshift.__version__, importlib.metadata.version("actionshift"), os.path.realpath(actionshift.__file__))
env = actionshift.make("pick_cube")
env.reset(seed=1)
print(env.step(np.zeros(7))[4]["elapsed_steps"])
"""], env, cwd=tmp_path)
    version, dist_version, where, steps = out.split()
    assert version == dist_version == cmake_version
    assert steps == "1"
    if editable:  # the package is the copied source tree itself
        assert where == os.path.realpath(src / "python" / "actionshift" / "__init__.py")
    else:
        assert where.startswith(os.path.realpath(env_dir)) and "site-packages" in where
    # the metadata pip records: name, version, the numpy requirement
    meta = _run([py, "-c", "import importlib.metadata as m; d = m.metadata('actionshift'); "
                           "print(d['Name'], d['Version'], m.requires('actionshift'))"], env, cwd=tmp_path)
    assert meta.split()[:2] == ["actionshift", cmake_version] and "numpy" in meta
