"""Tests of apps/sweep/atomic_json.py, the one write-to-temporary-then-rename
of the Python tools: a write puts the whole value in place, and a value that
cannot be written leaves the old file as it was and no temporary behind.

Run by ctest (tests/CMakeLists.txt, sweep_tools)."""

import json
import os
import shutil
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "apps", "sweep"))
import atomic_json  # noqa: E402


class AtomicJsonTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="atomic_json_test_")
        self.path = os.path.join(self.dir, "record.json")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_writes_the_value_and_replaces_an_old_one(self):
        atomic_json.write_json(self.path, {"a": 1})
        atomic_json.write_json(self.path, {"b": [1, 2]})
        with open(self.path) as f:
            self.assertEqual(json.load(f), {"b": [1, 2]})
        self.assertEqual(os.listdir(self.dir), ["record.json"])

    def test_a_failed_write_keeps_the_old_file_and_no_temporary(self):
        atomic_json.write_json(self.path, {"a": 1})
        with self.assertRaises(TypeError):
            atomic_json.write_json(self.path, {"a": object()})
        with open(self.path) as f:
            self.assertEqual(json.load(f), {"a": 1})
        self.assertEqual(os.listdir(self.dir), ["record.json"])


if __name__ == "__main__":
    unittest.main()
