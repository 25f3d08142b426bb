# A full M3500 run through Python ends where the C++ run ends: the same
# chi2 as hamal_solve's incremental aprilsam run, to every digit it prints.
import os
import re
import subprocess

import pytest

import hamal
from conftest import dataset_or_skip


def test_m3500_through_python_ends_at_the_cpp_runs_chi2():
    path = dataset_or_skip("M3500.toro")
    solve = os.environ.get("HAMAL_SOLVE")
    if not solve or not os.path.isfile(solve):
        pytest.skip("HAMAL_SOLVE (build/apps/hamal_solve) not given")
    out = subprocess.run([solve, path, "--backend", "aprilsam", "--incremental"],
                         capture_output=True, text=True, check=True).stdout
    cpp = re.search(r"^chi2 after:\s+(\S+)$", out, re.M).group(1)

    run = hamal.run(hamal.read_graph(path), "aprilsam")
    assert len(run.results) == 3500 and run.not_ok == 0
    assert f"{run.chi2:.10g}" == cpp
