# cmake --install puts the package where python/README.md says, and the
# installed module loads the installed libhamal (its run path), not the
# build tree's.
import os
import subprocess
import sys

import pytest


def test_installed_package_imports_from_its_prefix(tmp_path):
    cmake, binary = os.environ.get("HAMAL_CMAKE"), os.environ.get("HAMAL_BINARY_DIR")
    install_dir = os.environ.get("HAMAL_PYTHON_INSTALL_DIR")
    if not (cmake and binary and install_dir):
        pytest.skip("HAMAL_CMAKE, HAMAL_BINARY_DIR, HAMAL_PYTHON_INSTALL_DIR not given (ctest sets them)")
    prefix = tmp_path / "prefix"
    subprocess.run([cmake, "--install", binary, "--prefix", str(prefix)], check=True,
                   stdout=subprocess.DEVNULL)
    package = prefix / install_dir
    assert (package / "__init__.py").is_file()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "LD_LIBRARY_PATH")}
    env["PYTHONPATH"] = str(package.parent)
    out = subprocess.run(
        [sys.executable, "-c",
         "import hamal, hamal._hamal as m, os; print(hamal.__file__); "
         "print(open('/proc/self/maps').read().count(os.environ['PREFIX'] + '/lib/libhamal')); "
         "print(hamal.backend('aprilsam'))"],
        env={**env, "PREFIX": str(prefix)}, capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0].startswith(str(package))
    assert int(out[1]) > 0  # libhamal mapped from the prefix
    assert out[2] == "<hamal.Backend aprilsam>"
