#!/usr/bin/env python3
"""The bad-input contract checked across every tool, as a benchmark (not CI).

Runs a few hundred hostile but fair inputs through hamal_solve, hamal_bench,
hamal_generate, hamal_flag, hamal_moss, hamal_robust and hamal_spoil: damaged
graph, floor-plan and world files, absurd numbers, bad option values, and
outputs that are device nodes (twins of /dev/null and /dev/full, made with
mknod: run as root) or FIFOs. Each case is counted in one of:

  abort       exit status >= 128 (a signal) or a sanitizer report
  false ok    exit 0 on bad input (or a device or FIFO output refused)
  clobbered   a device or FIFO output replaced by a regular file
  unclear     an error that does not name the file (with its line, when the
              fault is on one) or the option at fault (its flag, or the
              quantity's name in a library's check: "sigma_xy", "range sigma")
  hang        no answer within --timeout seconds

The tools' contract (CONTRIBUTING.md, docs/ARCHITECTURE.md "Errors") wants
all five at 0. The bad-input table test (tests/apps/bad_input_test.cc) holds
the cases that once failed here.

  scripts/bad_input_campaign.py [--build build] [--timeout 60] [--verbose]
                                [--part all|tools|python]

--part python runs only the Python module's scenarios (threads, re-entrant
callbacks, refused values; see python_cases), which need no root; --part
runners the runners' (kill -9 and resume, two sweeps on one folder, a
read-only and a full file system; see runner_cases).

With --build build-asan (scripts/test.sh makes it) the same cases run under
AddressSanitizer and UBSan. Exit status 1 when any count is not 0.
"""

import argparse
import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))

CHAIN = ("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
         "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n")

# Bad graph files: name, content, what the message must name after the path
# (":LINE:" for a fault on a line, ":" for the file as a whole).
BAD_GRAPHS = [
    ("nan.g2o", CHAIN + "EDGE_SE2 0 2 nan 0 0 1 0 0 1 0 1\n", ":6:"),
    ("inf.g2o", CHAIN + "EDGE_SE2 0 2 inf 0 0 1 0 0 1 0 1\n", ":6:"),
    ("huge.g2o", CHAIN + "EDGE_SE2 0 2 1e300 0 0 1 0 0 1 0 1\n", ":6:"),
    ("dth.g2o", CHAIN + "EDGE_SE2 0 2 2 0 1e150 1 0 0 1 0 1\n", ":6:"),
    ("nul.g2o", CHAIN + "EDGE_SE2 0 2 1\x0099 0 0 1 0 0 1 0 1\n", ":6:"),
    ("short.g2o", CHAIN + "EDGE_SE2 0 2 2 0 0 1 0 0\n", ":6:"),
    ("long.g2o", CHAIN + "EDGE_SE2 0 2 2 0 0 1 0 0 1 0 1 7\n", ":6:"),
    ("word.g2o", CHAIN + "EDGE_SE2 0 2 two 0 0 1 0 0 1 0 1\n", ":6:"),
    ("notpd.g2o", CHAIN + "EDGE_SE2 0 2 2 0 0 -1 0 0 1 0 1\n", ":6:"),
    ("zeroinfo.g2o", CHAIN + "EDGE_SE2 0 2 2 0 0 0 0 0 0 0 0\n", ":6:"),
    ("self.g2o", CHAIN + "EDGE_SE2 1 1 0 0 0 1 0 0 1 0 1\n", ":6:"),
    ("unknownid.g2o", CHAIN + "EDGE_SE2 0 9 2 0 0 1 0 0 1 0 1\n", ":6:"),
    ("negid.g2o", CHAIN + "EDGE_SE2 0 -2 2 0 0 1 0 0 1 0 1\n", ":6:"),
    ("bigid.g2o", CHAIN + "EDGE_SE2 0 99999999999999999999 2 0 0 1 0 0 1 0 1\n", ":6:"),
    ("dupvertex.g2o", CHAIN + "VERTEX_SE2 1 5 5 0\n", ":6:"),
    ("badtag.g2o", CHAIN + "EDGE_FOO 0 1 2\n", ":6:"),
    ("vertexnan.g2o", "VERTEX_SE2 0 0 nan 0\n" + CHAIN[19:], ":1:"),
    ("ambiguous.txt", "EDGE2 0 1 1 0 0 1 0 1 1 0 0\n", ":1:"),
    ("binary.g2o", "\x7fELF\x02\x01\x01\x00\x00\x00\x00" * 8 + "\n", ":1:"),
    ("empty.g2o", "", ":"),
    ("comment.g2o", "# nothing\n", ":"),
    ("maxmix_scale.g2o", CHAIN + "EDGE_MAXMIX 0.1 5 EDGE_SE2 0 2 2 0 0 1 0 0 1 0 1\n", ":6:"),
    ("maxmix_weight.g2o", CHAIN + "EDGE_MAXMIX 1 1e-6 EDGE_SE2 0 2 2 0 0 1 0 0 1 0 1\n", ":6:"),
    ("maxmix_nested.g2o",
     CHAIN + "EDGE_MAXMIX 0.1 1e-6 EDGE_MAXMIX 0.1 1e-6 EDGE_SE2 0 2 2 0 0 1 0 0 1 0 1\n", ":6:"),
    ("missing.g2o", None, ":"),
]

# Graphs a reader accepts that no back-end can solve to a meaningful answer:
# each back-end must say so (exit 2), never "ok".
ABSURD_GRAPHS = [
    ("far.g2o", CHAIN + "EDGE_SE2 0 2 1e150 0 0 1e150 0 0 1e150 0 1e150\n"),
    ("far151.g2o", CHAIN + "EDGE_SE2 0 2 1e151 0 0 1 0 0 1 0 1\n"),
    ("info150.g2o", CHAIN + "EDGE_SE2 0 2 0 0 3 1e150 0 0 1e150 0 1e150\n"),
]

MOSS_BOX = "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
BAD_WORLDS = [  # hamal_moss world files
    ("w_tag.txt", "WORLD T\nSTART 1 1 0\nROUTE 3 1\n" + MOSS_BOX + "DOOR 1 2 3 4\n", ":8:"),
    ("w_nan.txt", "WORLD T\nSTART 1 nan 0\nROUTE 3 1\n" + MOSS_BOX, ":2:"),
    ("w_zero.txt", "WORLD T\nSTART 1 1 0\nROUTE 3 1\n" + MOSS_BOX + "WALL 2 2 2 2\n", ":8:"),
    ("w_inwall.txt", "WORLD T\nSTART 1 1 0\nROUTE 3 0.1\n" + MOSS_BOX, ":3:"),
    ("w_outside.txt", "WORLD T\nSTART -5 -5 0\nROUTE -5 5\n" + MOSS_BOX, ":2:"),
    ("w_through.txt", "WORLD T\nSTART 1 1 0\nROUTE 20 1\n" + MOSS_BOX, ":3:"),
    ("w_gap.txt", "WORLD T\nSTART 1 5 0\nROUTE 9 5\n" + MOSS_BOX +
     "WALL 5 0 5 4.85\nWALL 5 5.15 5 10\n", ":3:"),
    ("w_noroute.txt", "WORLD T\nSTART 1 1 0\n" + MOSS_BOX, ":"),
    ("w_nostart.txt", "WORLD T\nROUTE 3 1\n" + MOSS_BOX, ":"),
    ("w_twostart.txt", "WORLD T\nSTART 1 1 0\nSTART 2 2 0\nROUTE 3 1\n" + MOSS_BOX, ":3:"),
    ("w_angle.txt", "WORLD T\nSTART 1 1 1e300\nROUTE 3 1\n" + MOSS_BOX, ":2:"),
    ("w_empty.txt", "", ":"),
]

PLAN_BOX = "WALL 0 0 10 0\nWALL 10 0 10 10\nWALL 10 10 0 10\nWALL 0 10 0 0\n"
BAD_PLANS = [  # hamal_flag floor plans
    ("p_tag.plan", PLAN_BOX + "DOOR 1 2\n", ":5:"),
    ("p_nan.plan", PLAN_BOX + "WALL 0 0 nan 1\n", ":5:"),
    ("p_short.plan", PLAN_BOX + "WALL 0 0 1\n", ":5:"),
    ("p_dupcorner.plan", PLAN_BOX + "CORNER 0 0 0 0 0\nCORNER 0 10 0 10 0\n", ":6:"),
    ("p_bigid.plan", PLAN_BOX + "CORNER 72057594037927936 0 0 0 0\n", ":5:"),
    ("p_empty.plan", "", ":"),
]


class Campaign:
    def __init__(self, build, timeout, verbose):
        self.apps = os.path.join(build, "apps")
        self.timeout = timeout
        self.verbose = verbose
        self.dir = tempfile.mkdtemp(prefix="hamal_campaign_")
        self.counts = {k: 0 for k in ("cases", "abort", "false ok", "clobbered", "unclear", "hang")}
        self.faults = []

    def path(self, name):
        return os.path.join(self.dir, name)

    def write(self, name, content):
        with open(self.path(name), "wb") as f:
            f.write(content.encode("latin-1"))
        return self.path(name)

    def run(self, tool, args):
        command = [os.path.join(self.apps, tool)] + args
        try:
            r = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               timeout=self.timeout, cwd=self.dir)
            return r.returncode, r.stdout.decode("utf-8", "replace")
        except subprocess.TimeoutExpired:
            return None, ""

    def fault(self, kind, tool, args, output):
        self.counts[kind] += 1
        self.faults.append((kind, tool + " " + " ".join(args), output.strip()[-400:]))

    def common(self, tool, args, rc, out):
        """Counts a hang or an abort; True when neither happened."""
        self.counts["cases"] += 1
        if rc is None:
            self.fault("hang", tool, args, out)
            return False
        if rc < 0 or rc >= 128 or re.search(r"Sanitizer|runtime error:|terminate called", out):
            self.fault("abort", tool, args, out)
            return False
        return True

    def bad(self, tool, args, must_name=None):
        """Bad input: an error naming `must_name`; with None, input no back-end
        solves meaningfully, for which a numerical-failure status (exit 2)
        is the answer. Exit 0 is a false ok either way."""
        rc, out = self.run(tool, args)
        if self.verbose:
            print(f"[{rc}] {tool} {' '.join(args)}\n    {out.strip()[-300:]}")
        if not self.common(tool, args, rc, out):
            return
        if rc == 0:
            self.fault("false ok", tool, args, out)
        elif must_name is not None and must_name not in out:
            self.fault("unclear", tool, args, out)

    def output(self, tool, args, kind):
        """`args` writes to "@": a /dev/null twin or a FIFO is written in place
        (exit 0), a /dev/full twin is an error naming it; none is replaced."""
        node = self.path(f"node{self.counts['cases']}")
        if os.path.lexists(node):
            os.unlink(node)
        if kind == "fifo":
            os.mkfifo(node)
            drain = threading.Thread(target=lambda: open(node, "rb").read(), daemon=True)
            drain.start()
        else:
            os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 3 if kind == "null" else 7))
        argv = [a.replace("@", node) for a in args]
        rc, out = self.run(tool, argv)
        if kind == "fifo":
            # Unblock a drain whose writer never opened the FIFO.
            try:
                fd = os.open(node, os.O_WRONLY | os.O_NONBLOCK)
                os.close(fd)
            except OSError:
                pass
        if self.verbose:
            print(f"[{rc}] {kind} {tool} {' '.join(argv)}\n    {out.strip()[-300:]}")
        if not self.common(tool, argv, rc, out):
            return
        mode = os.lstat(node).st_mode
        if not (stat.S_ISFIFO(mode) if kind == "fifo" else stat.S_ISCHR(mode)):
            self.fault("clobbered", tool, argv, out)
        if kind == "full":
            if rc == 0:
                self.fault("false ok", tool, argv, out)
            elif node not in out:
                self.fault("unclear", tool, argv, out)
        elif rc != 0:
            self.fault("false ok", tool, argv, "refused a writable node: " + out)

    def go(self):
        p = self.path
        chain = self.write("chain.g2o", CHAIN)
        rc, out = self.run("hamal_generate", ["--poses", "100", "--output", p("world.g2o")])
        assert rc == 0, out
        rc, out = self.run("hamal_spoil", ["--data", p("world.g2o"), "--outliers", "3",
                                           "--output", p("spoiled.g2o")])
        assert rc == 0, out

        # Damaged graph files through every reader of a graph.
        for name, content, where in BAD_GRAPHS:
            f = p(name) if content is None else self.write(name, content)
            must = f + where
            for backend in ("cholesky", "ceres", "aprilsam"):
                self.bad("hamal_solve", [f, "--backend", backend], must)
                self.bad("hamal_solve", [f, "--backend", backend, "--incremental"], must)
            self.bad("hamal_bench", ["--data", f, "--backend", "aprilsam"], must)
            self.bad("hamal_robust", ["--data", f, "--backend", "cholesky:robust=maxmix"], must)
            self.bad("hamal_spoil", ["--data", f, "--outliers", "2", "--output", p("s.g2o")], must)
        # A directory, a device that never ends, an unreadable file.
        for f, must in ((self.dir, self.dir + ": is a directory"),
                        ("/dev/zero", "/dev/zero:1:"),
                        ("/proc/self/mem", "/proc/self/mem")):
            self.bad("hamal_solve", [f, "--backend", "cholesky"], must)
            self.bad("hamal_bench", ["--data", f, "--backend", "cholesky"], must)
            self.bad("hamal_robust", ["--data", chain, "--false_edges", f,
                                      "--backend", "cholesky"], must)
            self.bad("hamal_moss", ["world", f], must)
            self.bad("hamal_flag", ["run", "--world", f], must)

        # Accepted by the readers, beyond what doubles resolve.
        for name, content in ABSURD_GRAPHS:
            f = self.write(name, content)
            for backend in ("cholesky", "ceres", "aprilsam", "aprilsam-top"):
                self.bad("hamal_solve", [f, "--backend", backend])
            self.bad("hamal_bench", ["--data", f, "--backend", "cholesky;ceres",
                                           "--reference", "none"])

        # World files and floor plans.
        for name, content, where in BAD_WORLDS:
            f = self.write(name, content)
            self.bad("hamal_moss", ["world", f], f + where)
        gap = self.write("w_gap06.txt", "WORLD T\nSTART 1 5 0\nROUTE 9 5\n" + MOSS_BOX +
                         "WALL 5 0 5 4.7\nWALL 5 5.3 5 10\n")
        self.bad("hamal_moss", ["experiment", "--world", gap, "--sizes", "2", "--train", "1",
                                "--test", "1", "--output", p("m_gap")], "--world " + gap)
        for name, content, where in BAD_PLANS:
            f = self.write(name, content)
            self.bad("hamal_flag", ["run", "--world", f], f + where)

        # Option values, each named by the message.
        spoiled = p("spoiled.g2o")
        opts = [
            ("hamal_solve", [chain, "--backend", "nosuch"], "nosuch"),
            ("hamal_solve", [chain, "--backend", "cholesky:max_iterations=-1"], "max_iterations"),
            ("hamal_solve", [chain, "--backend", "aprilsam:delta_t=abc"], "delta_t"),
            ("hamal_solve", [chain, "--backend", "ceres:threads=0"], "threads"),
            ("hamal_solve", [chain, "--backend", "ceres:every=0"], "every"),
            ("hamal_solve", [chain, "--backend", "cholesky:nope=1"], "nope"),
            ("hamal_solve", [chain, "--format", "xml"], "xml"),
            ("hamal_solve", [chain, "--init", "magic"], "magic"),
            ("hamal_solve", [chain, p("other.g2o")], "more than one input"),
            ("hamal_solve", [], "input"),
            ("hamal_solve", [chain, "--plugin", p("nosuch.so")], "nosuch.so"),
            ("hamal_solve", [chain, "--output", self.dir], "--output"),
            ("hamal_solve", [chain, "--output", p("no/dir/x.g2o")], "--output"),
            ("hamal_bench", ["--generate", "50", "--backends", "ceres:max_iterations=5;;every=2"],
             "every=2"),
            ("hamal_bench", ["--generate", "50", "--backend", "cholesky", "--max_steps", "-1"],
             "--max_steps"),
            ("hamal_bench", ["--generate", "-5", "--backend", "cholesky"], "--generate"),
            ("hamal_bench", ["--generate", "50", "--backend", "cholesky", "--rows", p("x"),
                             "--summary", p("x")], p("x")),
            ("hamal_bench", ["--generate", "50", "--backend", "cholesky", "--chi2_every", "-1"],
             "--chi2_every"),
            ("hamal_bench", ["--generate", "50", "--backend", "cholesky",
                             "--reference", "ceres:threads=0"], "threads"),
            ("hamal_bench", ["--data", chain, "--generate", "50", "--backend", "cholesky"],
             "--generate"),
            ("hamal_generate", ["--poses", "-5", "--output", p("g.g2o")], "--poses"),
            ("hamal_generate", ["--poses", "20", "--seed=-1", "--output", p("g.g2o")], "--seed"),
            ("hamal_generate", ["--poses", "20", "--output", p("g.g2o"), "--truth", p("g.g2o")],
             p("g.g2o")),
            ("hamal_generate", ["--poses", "20", "--sigma_xy", "-1", "--output", p("g.g2o")],
             "sigma_xy"),
            ("hamal_generate", ["--poses", "20", "--sigma_xy", "nan", "--output", p("g.g2o")],
             "sigma_xy"),
            ("hamal_generate", ["--poses", "20", "--turn_probability", "2",
                                "--output", p("g.g2o")], "turn_probability"),
            ("hamal_generate", ["--poses", "20", "--loop_closure_rate", "-0.5",
                                "--output", p("g.g2o")], "loop_closure_rate"),
            ("hamal_generate", ["--poses", "20", "--world_size", "1", "--output", p("g.g2o")],
             "world_size"),
            ("hamal_generate", ["--poses", "20", "--output", self.dir], "--output"),
            ("hamal_spoil", ["--data", chain, "--outliers", "-3", "--output", p("s.g2o")],
             "--outliers"),
            ("hamal_spoil", ["--data", chain, "--outliers", "3", "--policy", "nosuch",
                             "--output", p("s.g2o")], "nosuch"),
            ("hamal_spoil", ["--data", chain, "--outliers", "3", "--group_size", "0",
                             "--policy", "random-group", "--output", p("s.g2o")], "group_size"),
            ("hamal_spoil", ["--data", chain, "--outliers", "3"], "--out"),
            ("hamal_spoil", ["--data", chain, "--outliers", "3", "--output", chain], chain),
            ("hamal_robust", ["--data", spoiled, "--backend",
                              "cholesky:robust=maxmix,null_scale=5"], "null_scale"),
            ("hamal_robust", ["--data", spoiled, "--backend",
                              "cholesky:robust=maxmix,null_weight=1"], "null_weight"),
            ("hamal_robust", ["--data", spoiled, "--backend", "cholesky:robust=nosuch"], "nosuch"),
            ("hamal_robust", ["--data", spoiled, "--backend", "cholesky:robust=dcs,dcs_phi=0"],
             "dcs_phi"),
            ("hamal_robust", ["--data", spoiled, "--backend",
                              "cholesky:robust=huber,loss_scale=-1"], "loss_scale"),
            ("hamal_robust", ["-chi2_every=-1", "--data", chain, "--backend", "cholesky"],
             "--chi2_every"),
            ("hamal_robust", ["--data", spoiled, "--backend", "cholesky", "--rows", p("y"),
                              "--summary", p("y")], p("y")),
            ("hamal_robust", ["--data", spoiled, "--backend", "cholesky",
                              "--false_edges", p("nosuch.false")], "nosuch.false"),
            ("hamal_flag", ["trials", "dynamic", "--trials=-1"], "--trials"),
            ("hamal_flag", ["trials", "dynamic", "--trials", "0"], "--trials"),
            ("hamal_flag", ["trials", "dynamic", "--trials", "18446744073709551615",
                            "--seed", "2"], "--trials"),
            ("hamal_flag", ["trials", "static", "--seed", "18446744073709551615",
                            "--trials", "2"], "seed"),
            ("hamal_flag", ["trials", "nosuch"], "nosuch"),
            ("hamal_flag", ["nosuch"], "nosuch"),
            ("hamal_flag", ["trials", "static", "--trials", "1", "--max_mixture",
                            "--null_scale", "5"], "--null_scale"),
            ("hamal_flag", ["trials", "static", "--trials", "1", "--max_mixture",
                            "--null_weight", "0"], "--null_weight"),
            ("hamal_flag", ["run", "--world", "nosuch_world"], "nosuch_world"),
            ("hamal_flag", ["run", "--range_sigma", "0"], "range sigma"),
            ("hamal_flag", ["run", "--bearing_sigma_deg", "inf"], "bearing sigma"),
            ("hamal_flag", ["run", "--backend", "nosuch"], "nosuch"),
            ("hamal_flag", ["run", "--trajectory", p("t"), "--landmarks_out", p("t")], p("t")),
            ("hamal_flag", ["world", "office", "--output", self.dir], "--output"),
            ("hamal_moss", ["experiment", "--poses", "-1", "--output", p("m")], "--poses"),
            ("hamal_moss", ["experiment", "--map_poses", "-4", "--output", p("m")], "--map_poses"),
            ("hamal_moss", ["experiment", "--threads", "-2", "--output", p("m")], "--threads"),
            ("hamal_moss", ["experiment", "--seed", "-2", "--output", p("m")], "--seed"),
            ("hamal_moss", ["experiment", "--world", "CORRIDOR", "--poses", "1", "--sizes", "1",
                            "--output", p("m1")], "2 poses"),
            ("hamal_moss", ["experiment", "--sizes", "x4", "--output", p("m2")], "--sizes"),
            ("hamal_moss", ["experiment", "--sizes", "0", "--output", p("m3")], "--sizes"),
            ("hamal_moss", ["experiment", "--methods", "nosuch", "--output", p("m4")], "nosuch"),
            ("hamal_moss", ["experiment", "--information", "nosuch", "--output", p("m5")],
             "--information"),
            ("hamal_moss", ["experiment", "--world", "CORRIDOR"], "--out"),
            ("hamal_moss", ["world", "nosuch_world"], "nosuch_world"),
            ("hamal_moss", ["nosuch"], "nosuch"),
        ]
        for tool, args, must in opts:
            self.bad(tool, args, must)

        # Outputs that are not regular files.
        world = p("world.g2o")
        robust = ["--data", spoiled, "--backend", "cholesky"]
        outputs = [
            ("hamal_solve", [chain, "--backend", "cholesky", "--output", "@"]),
            ("hamal_generate", ["--poses", "20", "--output", "@"]),
            ("hamal_generate", ["--poses", "20", "--output", p("w2.g2o"), "--truth", "@"]),
            ("hamal_bench", ["--generate", "50", "--backend", "cholesky", "--rows", "@"]),
            ("hamal_bench", ["--generate", "50", "--backend", "cholesky", "--summary", "@"]),
            ("hamal_flag", ["world", "office", "--output", "@"]),
            ("hamal_robust", robust + ["--rows", "@"]),
            ("hamal_robust", robust + ["--summary", "@"]),
            ("hamal_robust", robust + ["--weights", "@"]),
            ("hamal_spoil", ["--data", world, "--outliers", "3", "--output", "@"]),
        ]
        for kind in ("null", "full", "fifo"):
            for tool, args in outputs:
                self.output(tool, args, kind)
        carmen_log_cases(self)  # the CARMEN block below


# ---------------------------------------------------------------------------
# Python module scenarios (python/THREADS.md): small
# scripts run by the python3 the module is built for, each ending with one
# verdict line: "OK" (right behaviour), "REFUSED: <message>" (the expected
# exception, naming the reason), "UNCLEAR: ..." (another exception, or one
# not naming the reason) or "FALSE OK: ..." (bad input accepted, or a wrong
# result). A signal is an abort, no answer a hang.

PYTHON_PRELUDE = r"""
import math, sys, threading
import numpy as np
import hamal
from hamal import x
INFO = np.diag([100.0, 100.0, 400.0])
def expect(call, kind, *words):
    try:
        call()
    except kind as e:
        missing = [w for w in words if w not in str(e)]
        print(("UNCLEAR: " if missing else "REFUSED: ") + str(e))
    except Exception as e:
        print(f"UNCLEAR: {type(e).__name__}: {e}")
    else:
        print("FALSE OK: accepted")
def pose_step(i, key, factor):
    v = hamal.Values()
    v.insert(key, hamal.Pose2(i + 0.1, 0, 0.01))
    return hamal.Step(i, v, [factor])
"""

PY_TWO_WRITERS = r"""
b = hamal.backend(sys.argv[1])
done, errors, N = {0: 0, 1000: 0}, [], 150
def writer(base):
    try:
        for i in range(N):
            f = (hamal.prior(x(base), hamal.Pose2(0, 0, 0), INFO) if i == 0 else
                 hamal.between(x(base + i - 1), x(base + i), hamal.Pose2(1, 0, 0), INFO))
            r = b.update(pose_step(i, x(base + i), f))
            if not r.status.ok:
                errors.append(str(r.status))
            done[base] = i + 1
    except Exception as e:
        errors.append(repr(e))
def reader():
    while any(t.is_alive() for t in writers):
        seen = dict(done)
        if len(b) < sum(seen.values()):
            errors.append("len behind the updates returned")
        for base, k in seen.items():
            if k and not math.isfinite(b.pose(x(base + k - 1)).x):
                errors.append("pose not finite")
writers = [threading.Thread(target=writer, args=(base,)) for base in done]
threads = writers + [threading.Thread(target=reader)]
for t in threads:
    t.start()
for t in threads:
    t.join()
ok = (not errors and len(b) == 2 * N and  # aprilsam's thresholds leave millimetres
      all(abs(b.pose(x(base + N - 1)).x - (N - 1)) < 0.05 for base in done))
print("OK" if ok else f"FALSE OK: {errors[:3]}, {len(b)} variables")
"""

PY_REENTRANT_UPDATE = r"""
b = hamal.backend(sys.argv[1])
inner = []
def residual(params):
    if not inner:
        inner.append(None)
        expect(lambda: b.update(pose_step(1, x(9), hamal.prior(x(9), hamal.Pose2(), INFO))),
               RuntimeError, "inside")
    return params[0] - np.array([1.0, 2.0, 0.3]), [np.eye(3)]
r = b.update(pose_step(0, x(0), hamal.PythonFactor([x(0)], 3, residual)))
if not r.status.ok or len(b) != 1:
    print(f"FALSE OK: outer update {r.status}, {len(b)} variables")
"""

PY_REENTRANT_PREDICT = r"""
b = hamal.backend("cholesky")
g = hamal.Graph()
g.add(hamal.PythonFactor([x(0), x(1)], 3, lambda p: (p[1] - p[0], [-np.eye(3), np.eye(3)]),
                         predict=lambda unknown, known: b.update(hamal.Step(0))))
steps = hamal.ThesisProtocol(g).steps(b)
b.update(next(steps))
expect(lambda: next(steps), RuntimeError, "inside")
"""

PY_KEPT_KNOWN = r"""
kept = []
def predict(unknown, known):
    p = known.pose(x(unknown.index - 1))
    kept.append((unknown.index - 1, known, p))
    return hamal.Pose2(p.x + 1, p.y, p.theta)
g = hamal.Graph()
for i in range(1, 200):
    g.add(hamal.PythonFactor([x(i - 1), x(i)], 3,
                             lambda p: (p[1] - p[0] - np.array([1.0, 0, 0]), [-np.eye(3), np.eye(3)]),
                             predict=predict))
run = hamal.run(g, "cholesky")
bad = [k for k, known, p in kept if known.pose(x(k)) != p]
print("OK" if len(kept) == 199 and not bad and run.not_ok == 0 else f"FALSE OK: {bad[:3]}")
"""

PYTHON_CASES = [  # name, script, arguments
    *[(f"two threads update one {s}", PY_TWO_WRITERS, [s]) for s in ("cholesky", "aprilsam", "ceres")],
    *[(f"re-entrant update in {s}", PY_REENTRANT_UPDATE, [s])
      for s in ("cholesky", "aprilsam", "ceres", "ceres:threads=2")],
    ("re-entrant update in predict", PY_REENTRANT_PREDICT, []),
    ("predict keeps known_values", PY_KEPT_KNOWN, []),
    ("x(2**56)", 'expect(lambda: hamal.x(2**56), hamal.Error, "too large")', []),
    ("l(2**56)", 'expect(lambda: hamal.l(2**56), hamal.Error, "too large")', []),
    ("insert_poses 2**53 + 1",
     "v = hamal.Values()\nv.insert_poses([2**53 + 1], np.zeros((1, 3)))\n"
     "print('OK' if [int(i) for i in v.pose_ids()] == [2**53 + 1] else f'FALSE OK: {v.pose_ids()}')",
     []),
    ("insert_poses float id 2**53 + 2",
     'expect(lambda: hamal.Values().insert_poses([2.0**53 + 2], np.zeros((1, 3))), hamal.Error, "ids")',
     []),
    ("Pose2.__setstate__ nan",
     'expect(lambda: hamal.Pose2.__new__(hamal.Pose2).__setstate__((math.nan, 0.0, 0.0)), '
     'hamal.Error, "not finite")', []),
    ("Key.__setstate__ 2**56",
     'expect(lambda: hamal.Key.__new__(hamal.Key).__setstate__(("x", 2**56)), hamal.Error, '
     '"too large")', []),
    ("ATE on disjoint Values",
     'a = hamal.Values.from_numpy(np.zeros((3, 3)))\n'
     'b = hamal.Values.from_numpy(np.zeros((3, 3)), pose_ids=[7, 8, 9])\n'
     'expect(lambda: hamal.absolute_trajectory_error(a, b), hamal.Error, "no pose in common")', []),
    ("ATE on empty Values",
     'expect(lambda: hamal.absolute_trajectory_error(hamal.Values(), hamal.Values()), hamal.Error, '
     '"no pose in common")', []),
    ("set_loss on a factor in a back-end",
     'b = hamal.backend("ceres")\nf = hamal.prior(x(0), hamal.Pose2(), INFO)\n'
     'b.update(pose_step(0, x(0), f))\n'
     'expect(lambda: f.set_loss("huber", 1.0), hamal.Error, "set_loss")', []),
]


def python_cases(c, python):
    """Runs PYTHON_CASES with `python` against the module in <build>/python,
    counted in the campaign `c`'s kinds."""
    module = os.path.join(os.path.dirname(c.apps), "python")
    env = dict(os.environ, PYTHONPATH=module)
    for name, script, args in PYTHON_CASES:
        try:
            r = subprocess.run([python, "-c", PYTHON_PRELUDE + script, *args],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               timeout=c.timeout, cwd=c.dir, env=env)
            rc, out = r.returncode, r.stdout.decode("utf-8", "replace")
        except subprocess.TimeoutExpired:
            rc, out = None, ""
        if c.verbose:
            print(f"[{rc}] python3: {name}\n    {out.strip()[-300:]}")
        if not c.common("python3", [name], rc, out):
            continue
        verdict = out.strip().splitlines()[-1] if out.strip() else ""
        if verdict.startswith("FALSE OK"):
            c.fault("false ok", "python3", [name], out)
        elif rc != 0 or not (verdict == "OK" or verdict.startswith("REFUSED: ")):
            c.fault("unclear", "python3", [name], out)
# ---------------------------------------------------------------------------


# --- CARMEN logs (apps/carmen/carmen_log.h) through every tool that reads one --------
# hamal_log, hamal_flag carmen and hamal_moss experiment --data take the
# reader's flags (apps/carmen/carmen_log_flags.h). Run this part alone with
#   scripts/bad_input_campaign.py --part carmen   (no root needed)

def carmen_flaser(ranges, pose, t):
    return (f"FLASER {len(ranges)} {' '.join(ranges)} {pose} {pose} {t} host {t}\n")


def carmen_corridor(scans):
    """A corridor: three beams hit, seven see nothing (51.00-51.16 m)."""
    lines = []
    for i in range(scans):
        r = ["1.5", "2", "2.5"] + [f"{51 + 0.01 * ((i * 7 + j * 3) % 17):.2f}" for j in range(3, 10)]
        lines.append(carmen_flaser(r, f"{0.5 * i:.2f} 0 0", f"{i}.{i % 10}"))
    return "".join(lines)


CARMEN_HEAD = carmen_corridor(3)
# name, content, what the message must name after the path, extra flags
BAD_CARMEN_LOGS = [
    ("c_range.log", CARMEN_HEAD + carmen_flaser(["1", "1e308", "2"], "2 0 0", "9"), ":4:", []),
    ("c_pose.log", CARMEN_HEAD + carmen_flaser(["1", "2", "3"], "1e300 0 0", "9"), ":4:", []),
    ("c_odom.log", CARMEN_HEAD + "ODOM 0 1e300 0 0 0 0 9 host 9\n", ":4:", []),
    ("c_offset.log", "PARAM robot_frontlaser_offset 1e308 0 host 0\n" + CARMEN_HEAD, ":1:", []),
    ("c_junk.log", "PARAM robot_frontlaser_offset 0.1junk 0 host 0\n" + CARMEN_HEAD, ":1:", []),
    ("c_maxjunk.log", "PARAM robot_front_laser_max 80.9x 0 host 0\n" + CARMEN_HEAD, ":1:", []),
    ("c_maxzero.log", "PARAM robot_front_laser_max 0 0 host 0\n" + CARMEN_HEAD, ":1:", []),
    ("c_rl_far.log", "ROBOTLASER1 0 -1.5 3 1.5 10 0.01 0 3 1 10 2 0 1e5 6 0 5 6 0 0 0 0 0 0 "
     "1.3 h 1.3\n", ":1:", []),
    ("c_rl_max.log", "ROBOTLASER1 0 -1.5 3 1.5 2e3 0.01 0 3 1 10 2 0 7 6 0 5 6 0 0 0 0 0 0 "
     "1.3 h 1.3\n", ":1:", []),
    # 0.8 s back: within the default tolerance, beyond the one given.
    ("c_back.log", CARMEN_HEAD + carmen_flaser(["1", "2", "3"], "2 0 0", "1.4"), ":4:",
     ["--max_time_reversal", "0.5"]),
    ("c_back2.log", CARMEN_HEAD + carmen_flaser(["1", "2", "3"], "2 0 0", "0.1"), ":4:", []),
]


def carmen_readers(c, f):
    """The command line of each tool that reads the log `f`."""
    return [("hamal_log", ["--data", f]),
            ("hamal_flag", ["carmen", "--data", f]),
            ("hamal_moss", ["experiment", "--data", f, "--sizes", "1",
                            "--output", c.path("m_carmen")])]


def carmen_log_cases(c):
    import gzip
    import random
    import zlib
    for name, content, where, flags in BAD_CARMEN_LOGS:
        f = c.write(name, content)
        for tool, args in carmen_readers(c, f):
            c.bad(tool, args + flags, f + where)
    # The reader's options, each named by the message.
    ok = c.write("c_ok.log", carmen_corridor(10))
    for flag, value in (("--no_return_range", "-1"), ("--no_return_range", "nan"),
                        ("--max_time_reversal", "-1"), ("--max_time_reversal", "inf")):
        for tool, args in carmen_readers(c, ok):
            c.bad(tool, args + [flag + "=" + value], flag)
    # A gzip log cut short: at random bytes, and where what inflates so far
    # ends with a whole line (it would read as a shorter log).
    whole = gzip.compress(carmen_corridor(400).encode(), mtime=0)
    boundary = []
    for n in range(20, len(whole) - 1):
        text = zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(whole[:n])
        if text.endswith(b"\n"):
            boundary.append(n)
    rng = random.Random(1)
    cuts = sorted(set(rng.sample(range(1, len(whole)), 10) + rng.sample(boundary, 10)))
    for n in cuts:
        f = c.path(f"c_cut{n}.log.gz")
        with open(f, "wb") as out:
            out.write(whole[:n])
        for tool, args in carmen_readers(c, f):
            c.bad(tool, args, f)
    return len(boundary), len(cuts)


def carmen_only(build, timeout=60, verbose=False):
    c = Campaign(os.path.abspath(build), timeout, verbose)
    boundary, cuts = carmen_log_cases(c)
    for kind, command, output in c.faults:
        print(f"{kind}: {command}\n    {output}")
    print(f"carmen logs ({cuts} gzip cuts, of {boundary} at a line boundary): " +
          ", ".join(f"{k} {v}" for k, v in c.counts.items()))
    shutil.rmtree(c.dir, ignore_errors=True)
    return 1 if c.faults else 0
# --- end of CARMEN logs --------------------------------------------------------------


# ---------------------------------------------------------------------------
# Outputs that are inputs, runs that fail half-way, false-edge lists that
# disagree with their header, absurd trial counts (the tools' outputs: every
# output is refused when it is one of the run's inputs, by inode, and a run's
# outputs are put in place together or not at all). Counted as above, and:
#   clobbered   also an input, or an output of a failed run, replaced
#   refused     a valid input refused
# Run alone with --part outputs.

def tool_outputs(c):
    c.counts.setdefault("refused", 0)
    p = c.path
    chain = c.write("to_chain.g2o", CHAIN)
    rc, out = c.run("hamal_generate", ["--poses", "100", "--output", p("to_world.g2o")])
    assert rc == 0, out
    world = p("to_world.g2o")
    rc, out = c.run("hamal_spoil", ["--data", world, "--outliers", "3",
                                    "--output", p("to_spoiled.g2o")])
    assert rc == 0, out
    spoiled, listed = p("to_spoiled.g2o"), p("to_spoiled.g2o.false")
    plan = c.write("to_box.plan", PLAN_BOX + "START 1 1 0\nROUTE 9 1\n")
    log = c.write("to_l_points.csv", "ODOM 0 0 0 0 0 0 1 h 1\n")
    for link, target in (("to_link.g2o", chain), ("to_link.false", listed)):
        if not os.path.lexists(p(link)):
            os.symlink(target, p(link))
    inputs = [chain, world, spoiled, listed, plan, log]

    def untouched(tool, args, before, out):
        for f, content in before.items():
            with open(f, "rb") as h:
                if h.read() != content:
                    c.fault("clobbered", tool, args, f"{f} replaced: " + out)

    def snapshot(files):
        before = {}
        for f in files:
            with open(f, "rb") as h:
                before[f] = h.read()
        return before

    robust = ["--data", spoiled, "--backend", "cholesky"]
    same = [  # (tool, args, the output named in the message)
        ("hamal_solve", [chain, "--backend", "cholesky", "--output", chain], chain),
        ("hamal_solve", [chain, "--output", p("to_link.g2o")], p("to_link.g2o")),
        ("hamal_solve", ["--data", chain, "--output", p("to_link.g2o")], p("to_link.g2o")),
        ("hamal_spoil", ["--data", world, "--outliers", "3", "--output", world], world),
        ("hamal_spoil", ["--data", chain, "--outliers", "0", "--output", p("to_link.g2o")],
         p("to_link.g2o")),
        ("hamal_robust", robust + ["--output", spoiled], spoiled),
        ("hamal_robust", robust + ["--weights", listed], listed),
        ("hamal_robust", robust + ["--rows", p("to_link.false")], p("to_link.false")),
        ("hamal_robust", robust + ["--summary", spoiled], spoiled),
        ("hamal_robust", robust + ["--rows", world, "--false_edges", world], world),
        ("hamal_bench", ["--data", world, "--backend", "cholesky", "--rows", world], world),
        ("hamal_bench", ["--data", world, "--backend", "cholesky", "--summary", world], world),
        ("hamal_flag", ["run", "--world", plan, "--trajectory", plan], plan),
        ("hamal_flag", ["run", "--world", plan, "--landmarks_out", plan], plan),
        ("hamal_log", ["--data", log, "--output", p("to_l")], log),
    ]
    for tool, args, output in same:
        before = snapshot(inputs)
        rc, out = c.run(tool, args)
        c.bad_checked(tool, args, rc, out, output + " is the input")
        untouched(tool, args, before, out)

    # One output fails after another was written: neither is put in place.
    node = p("to_full")
    if os.path.lexists(node):
        os.unlink(node)
    os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 7))
    kept = c.write("to_kept.g2o", "old\n")
    c.write("to_k_points.csv", "old\n")
    if not os.path.lexists(p("to_k_trajectory.csv")):
        os.symlink(node, p("to_k_trajectory.csv"))
    robot = c.write("to_robot.log", "ODOM 0 0 0 0 0 0 1 h 1\nODOM 1 0 0 0 0 0 2 h 2\n"
                    "FLASER 3 1 1 1 0 0 0 0 0 0 3 h 3\n")
    half = [
        ("hamal_generate", ["--poses", "20", "--output", kept, "--truth", node], [kept], node),
        ("hamal_log", ["--data", robot, "--output", p("to_k")], [p("to_k_points.csv")],
         p("to_k_trajectory.csv")),
        ("hamal_spoil", ["--data", world, "--outliers", "3", "--output", node], [], node),
    ]
    for tool, args, olds, must in half:
        before = snapshot(olds)
        rc, out = c.run(tool, args)
        c.bad_checked(tool, args, rc, out, must)
        untouched(tool, args, before, out)
        if os.path.lexists(node + ".false"):
            c.fault("clobbered", tool, args, node + ".false made beside a failed graph")
            os.unlink(node + ".false")

    # False-edge lists that disagree with their header.
    with open(listed) as f:
        lines = f.read().splitlines(keepends=True)
    cut = c.write("to_cut.false", "".join(lines[:-1]))
    bare = c.write("to_bare.false", "".join(lines[:3]))
    other = c.write("to_other.false", "".join(lines).replace("graph_factors=", "graph_factors=1"))
    for f, must in ((cut, cut + ":2:"), (bare, bare + ":2:"), (other, other)):
        for backend in ("cholesky", "cholesky:robust=gnc-tls"):
            rc, out = c.run("hamal_robust", robust[:2] + ["--backend", backend,
                                                          "--false_edges", f])
            c.bad_checked("hamal_robust", robust[:2] + ["--false_edges", f], rc, out, must)

    # An absurd trial count, whatever the seed; a valid seed accepted.
    for seed in ([], ["--seed", "2"]):
        args = ["trials", "dynamic", "--trials", "18446744073709551615"] + seed
        rc, out = c.run("hamal_flag", args)
        c.bad_checked("hamal_flag", args, rc, out, "--trials")
    for args in (["trials", "dynamic", "--trials", "1", "--seed", "2"],
                 ["trials", "static", "--trials", "1", "--seed", "18446744073709551614"]):
        rc, out = c.run("hamal_flag", args)
        if c.common("hamal_flag", args, rc, out) and rc != 0:
            c.fault("refused", "hamal_flag", args, out)


def _bad_checked(self, tool, args, rc, out, must_name):
    """Campaign.bad on a run already made."""
    if self.verbose:
        print(f"[{rc}] {tool} {' '.join(args)}\n    {out.strip()[-300:]}")
    if not self.common(tool, args, rc, out):
        return
    if rc == 0:
        self.fault("false ok", tool, args, out)
    elif must_name not in out:
        self.fault("unclear", tool, args, out)


Campaign.bad_checked = _bad_checked
# --------------------------------------------------------------------------- end


# --------------------------------------------------------------------------- runners
# The Python runners where they meet their surroundings: a sweep killed with
# SIGKILL half-way and run again, a results folder on a read-only file
# system and on a full one (small tmpfs mounts: run as root), and two sweeps
# started on one folder at once. Counted as above, with a traceback unclear
# (a runner says one line, apps/common/script_errors.py), and
#   clobbered   a folder left with a run that is torn, missing, or twice
# Run alone with --part runners.

RUNNER_SPEC = {"datasets": {"w": {"generate": 600, "seed": 3}},
               "groups": [{"name": "main", "backends": ["cholesky", "aprilsam", "aprilsam-top",
                                                        "ceres:every=20"]}]}


def runner_cases(c, python):
    sweep = os.path.join(HERE, "..", "apps", "sweep", "hamal_sweep.py")
    spec = c.write("rn_spec.json", json.dumps(RUNNER_SPEC))
    runs = len(RUNNER_SPEC["groups"][0]["backends"])

    def command(results):
        return [python, sweep, spec, "--results", results, "--bench",
                os.path.join(c.apps, "hamal_bench"), "--jobs", "1"]

    def finish(proc, name, args):
        try:
            out, _ = proc.communicate(timeout=c.timeout * 4)
            return proc.returncode, out.decode("utf-8", "replace")
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            return None, ""

    def start(results):
        return subprocess.Popen(command(results), stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, start_new_session=True)

    def whole(results, name, args):
        """Every run of the spec once, each with its rows and summary."""
        folder = os.path.join(results, "w")
        done = sorted(os.listdir(folder)) if os.path.isdir(folder) else []
        done = [d for d in done if not d.startswith(".")]
        torn = [d for d in done if not all(os.path.isfile(os.path.join(folder, d, f))
                                           for f in ("rows.csv", "summary.json"))]
        if len(done) != runs or torn:
            c.fault("clobbered", name, args, f"{len(done)} of {runs} runs, torn {torn}")

    def judged(name, args, rc, out, must_name=None):
        if not c.common(name, args, rc, out):
            return False
        if "Traceback" in out:
            c.fault("unclear", name, args, out)
            return False
        if must_name is not None:
            if rc == 0:
                c.fault("false ok", name, args, out)
            elif must_name not in out:
                c.fault("unclear", name, args, out)
        elif rc != 0:
            c.fault("unclear", name, args, out)
        return True

    # Killed with SIGKILL once a run is under way, then run again.
    results = c.path("rn_killed")
    proc = start(results)
    time.sleep(3.0)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    rc, out = finish(start(results), "hamal_sweep", ["(after kill -9)"])
    if judged("hamal_sweep", ["resumed after kill -9"], rc, out):
        whole(results, "hamal_sweep", ["resumed after kill -9"])

    # Two sweeps on one folder at once: one runs, the other waits or says so.
    results = c.path("rn_two")
    first, second = start(results), start(results)
    for proc, which in ((first, "first"), (second, "second")):
        rc, out = finish(proc, "hamal_sweep", [which])
        if rc not in (0, None) and "lock" not in out and "another" not in out:
            c.fault("unclear", "hamal_sweep", [which + " of two on one folder"], out)
        else:
            c.common("hamal_sweep", [which + " of two on one folder"], rc, out)
    rc, out = finish(start(results), "hamal_sweep", ["after two"])
    if judged("hamal_sweep", ["after two on one folder"], rc, out):
        whole(results, "hamal_sweep", ["two on one folder"])

    # A read-only file system, and one that fills up: one line naming the
    # folder, a non-zero status, nothing half-written taken as done.
    for options, must in (("ro,size=1m", "Read-only"), ("size=48k", "No space")):
        mount = c.path("rn_mount_" + options.split(",")[0].replace("=", ""))
        os.makedirs(mount, exist_ok=True)
        if subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", mount],
                          capture_output=True).returncode != 0:
            print(f"bad_input_campaign: cannot mount a tmpfs ({options}): skipped")
            continue
        try:
            results = os.path.join(mount, "results")
            rc, out = finish(start(results), "hamal_sweep", [options])
            judged("hamal_sweep", ["results on tmpfs " + options], rc, out, must_name=must)
        finally:
            subprocess.run(["umount", "-l", mount], capture_output=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default=os.path.join(HERE, "..", "build"))
    parser.add_argument("--timeout", type=float, default=60)
    parser.add_argument("--verbose", action="store_true")
    parser.add_argument("--part", choices=("all", "tools", "python", "carmen", "outputs",
                                           "runners"),
                        default="all",
                        help="the tools' cases, the Python module's, or both; carmen: only "
                        "the CARMEN block; outputs: only the block of outputs that are inputs")
    parser.add_argument("--python", default="/usr/bin/python3" if os.path.exists(
        "/usr/bin/python3") else sys.executable, help="the python3 the module is built for")
    a = parser.parse_args()
    if a.part == "carmen":
        sys.exit(carmen_only(a.build, a.timeout, a.verbose))
    if a.part != "python" and os.geteuid() != 0:  # runners: mount
        sys.exit("bad_input_campaign: mknod needs root (device twins of /dev/null and /dev/full)")
    c = Campaign(os.path.abspath(a.build), a.timeout, a.verbose)
    if a.part in ("all", "tools", "outputs"):
        tool_outputs(c)
    if a.part in ("all", "tools"):
        c.go()
    if a.part in ("all", "python"):
        python_cases(c, a.python)
    if a.part in ("all", "runners"):
        runner_cases(c, a.python)
    shutil.rmtree(c.dir, ignore_errors=True)
    for kind, command, output in c.faults:
        print(f"{kind}: {command}\n    {output}")
    print(", ".join(f"{k} {v}" for k, v in c.counts.items()))
    sys.exit(1 if c.faults else 0)


if __name__ == "__main__":
    main()
