"""`pip install .` as python/README.md ("Install with pip") says, into a fresh
virtual environment, from the CMake build tree ctest runs in
(HAMAL_CMAKE_BUILD_DIR: the module's targets are up to date, nothing is
compiled); then, from a directory outside the checkout, the installed
package: its version is CMakeLists.txt's and its metadata's, it loads its
own libhamal, solves a graph found through HAMAL_DATA_DIR, says what to set
without it, and carries py.typed, stubs mypy accepts and the examples.

Run by ctest as python_pip_install (tests/CMakeLists.txt), which gives
HAMAL_PYTHON (the interpreter the module is built for), HAMAL_SOURCE_DIR,
HAMAL_BINARY_DIR and HAMAL_VERSION (the project's VERSION)."""

import os
import shutil
import subprocess
import tempfile
import textwrap
import unittest

# Three poses, odometry and a loop closure that disagree by 0.3 m.
TINY_G2O = """\
VERTEX_SE2 0 0 0 0
VERTEX_SE2 1 1 0 0
VERTEX_SE2 2 2 0 0
EDGE_SE2 0 1 1 0 0 100 0 0 100 0 400
EDGE_SE2 1 2 1 0 0 100 0 0 100 0 400
EDGE_SE2 0 2 2.3 0 0 100 0 0 100 0 400
"""


class PipInstallTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.python = os.environ.get("HAMAL_PYTHON")
        cls.source = os.environ.get("HAMAL_SOURCE_DIR")
        cls.binary = os.environ.get("HAMAL_BINARY_DIR")
        cls.version = os.environ.get("HAMAL_VERSION")
        if not (cls.python and cls.source and cls.binary and cls.version):
            raise unittest.SkipTest("HAMAL_PYTHON, HAMAL_SOURCE_DIR, HAMAL_BINARY_DIR, HAMAL_VERSION "
                                    "not given (ctest sets them)")
        cls.tmp = tempfile.mkdtemp(prefix="hamal-pip-")
        cls.venv = os.path.join(cls.tmp, "venv")
        cls.outside = os.path.join(cls.tmp, "elsewhere")
        cls.data = os.path.join(cls.tmp, "data")
        os.makedirs(cls.outside)
        os.makedirs(cls.data)
        with open(os.path.join(cls.data, "tiny.g2o"), "w") as f:
            f.write(TINY_G2O)
        # Neither the caller's module path nor pip's configuration of this machine.
        cls.env = {k: v for k, v in os.environ.items()
                   if k not in ("PYTHONPATH", "HAMAL_DATA_DIR", "HAMAL_PLUGIN_PATH")
                   and not k.startswith("PIP_")}
        cls.env.update(PIP_CONFIG_FILE=os.devnull, PIP_NO_CACHE_DIR="1",
                       PIP_DISABLE_PIP_VERSION_CHECK="1", PYTHONDONTWRITEBYTECODE="1")
        subprocess.run([cls.python, "-m", "venv", "--system-site-packages", cls.venv],
                       env=cls.env, check=True)
        install = subprocess.run(
            [os.path.join(cls.venv, "bin", "pip"), "install", "-v", "--no-build-isolation",
             "--no-index", cls.source],
            env={**cls.env, "HAMAL_CMAKE_BUILD_DIR": cls.binary}, cwd=cls.outside,
            capture_output=True, text=True)
        cls.pip_output = install.stdout + install.stderr
        if install.returncode != 0:
            shutil.rmtree(cls.tmp, ignore_errors=True)
            raise AssertionError("pip install failed:\n" + cls.pip_output[-6000:])

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def run_python(self, code, **env):
        """Runs `code` in the venv's python from outside the checkout; its stdout."""
        result = subprocess.run([os.path.join(self.venv, "bin", "python"), "-c", textwrap.dedent(code)],
                                env={**self.env, **env}, cwd=self.outside, capture_output=True, text=True)
        self.assertEqual(result.returncode, 0, result.stderr)
        return result.stdout.strip()

    def package_dir(self):
        return self.run_python("import hamal, os; print(os.path.dirname(hamal.__file__))")

    def test_pip_compiled_nothing_in_the_up_to_date_tree(self):
        self.assertNotIn("Building CXX object", self.pip_output)
        self.assertIn("--component python_wheel", self.pip_output)

    def test_version_is_the_projects_and_the_metadatas(self):
        out = self.run_python("""
            import importlib.metadata, hamal
            print(hamal.__version__, importlib.metadata.version("hamal"))""").split()
        self.assertEqual(out, [self.version, self.version])

    def test_imports_from_the_venv_with_its_own_libhamal(self):
        package = self.package_dir()
        self.assertTrue(package.startswith(self.venv + os.sep), package)
        mapped = self.run_python("""
            import hamal
            print(sorted({l.split()[-1] for l in open("/proc/self/maps") if "libhamal" in l}))""")
        self.assertEqual(mapped, str([os.path.join(package, "libhamal.so.0")]))

    def test_solves_a_graph_found_through_HAMAL_DATA_DIR(self):
        out = self.run_python("""
            import hamal
            r = hamal.run(hamal.read_graph(hamal.dataset("tiny.g2o")), "cholesky")
            p = r.estimate.pose(hamal.x(2))
            print(r.not_ok, round(p.x, 3), round(p.y, 3))""", HAMAL_DATA_DIR=self.data)
        not_ok, x, y = out.split()
        self.assertEqual(not_ok, "0")
        self.assertAlmostEqual(float(x), 2.2, places=3)  # the loop's 0.3 m shared by three edges
        self.assertAlmostEqual(float(y), 0.0, places=3)

    def test_without_HAMAL_DATA_DIR_it_says_to_set_it(self):
        out = self.run_python("""
            import hamal
            try:
                hamal.dataset("tiny.g2o")
            except hamal.Error as e:
                print(e)""")
        self.assertIn("HAMAL_DATA_DIR is not set", out)
        self.assertIn("hamal is installed", out)
        missing = self.run_python("""
            import hamal
            try:
                hamal.dataset("M3500.toro")
            except hamal.Error as e:
                print(e)""", HAMAL_DATA_DIR=self.data)
        self.assertIn(f"not found in {self.data} (HAMAL_DATA_DIR)", missing)

    def test_typed_with_stubs_mypy_accepts(self):
        package = self.package_dir()
        self.assertTrue(os.path.isfile(os.path.join(package, "py.typed")))
        stub = os.path.join(package, "_hamal.pyi")
        with open(stub) as f:
            self.assertIn("class Backend:", f.read())
        out = self.run_python(f"""
            from mypy import api
            out, err, status = api.run(["--cache-dir", {os.path.join(self.tmp, "mypy")!r}, {stub!r}])
            print(status, out, err)""")
        self.assertTrue(out.startswith("0 Success"), out)

    def test_examples_are_installed_as_hamal_examples(self):
        out = self.run_python("""
            import hamal.examples.m3500_comparison as m, hamal.examples.range_only_factor as r
            print(m.DEFAULT_BACKENDS[0], callable(r.solve))""")
        self.assertEqual(out, "aprilsam True")


if __name__ == "__main__":
    unittest.main()
