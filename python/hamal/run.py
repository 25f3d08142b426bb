"""run(): one back-end fed by the thesis protocol (or any StepSource), one
update per step, as hamal_bench runs it (apps/bench/bench_runner.h): only
the update calls are timed, chi2 is computed afterwards over the dataset's
factors (the protocol's gauge prior is not one). compare() runs several
back-ends on one graph, saying how far it is on stderr; table() prints
their summary with every time in the unit that shows it (format_seconds)."""

import math
import sys
import time

import numpy as np

from ._hamal import Backend, Graph, StepSource, ThesisProtocol, backend as make_backend, chi2, read_graph


class Run:
    """What run() returns: per-step results and times, the estimate, chi2."""

    __slots__ = {
        "spec": "The back-end's spec string.",
        "results": "One hamal.UpdateResult per step, in order.",
        "seconds": "The update calls' wall times (s): a float array, one per step.",
        "factors": "The measurement factors of the steps run (the protocol's prior left out).",
        "estimate": "The back-end's estimate after the last step (a hamal.Values).",
        "chi2": "chi2 of `factors` at `estimate`, without robust losses.",
        "wall_seconds": "The whole Python loop (s), making the steps included.",
        "batches": "How many updates were batches (UpdateResult.kind == 'batch').",
        "status": ("The run's hamal.Status: the last update's, or, when that one is ok, the "
                   "back-end's closing verdict (Backend.closing_verdict), e.g. 'uncertain' for "
                   "a robust answer in doubt."),
        "not_ok": "How many updates ended with a Status other than ok (a closing verdict "
                  "that is not counts for the last).",
    }

    def __init__(self, spec, results, factors, estimate, wall_seconds, closing=None):
        self.spec = spec
        self.results = results
        self.seconds = np.array([r.seconds for r in results], dtype=float)
        self.factors = factors
        self.estimate = estimate
        self.chi2 = chi2(factors, estimate)
        self.wall_seconds = wall_seconds
        self.batches = sum(r.kind == "batch" for r in results)
        self.not_ok = sum(not r.status.ok for r in results)
        self.status = results[-1].status if results else None
        if closing is not None and self.status is not None and self.status.ok and not closing.ok:
            self.status = closing
            self.not_ok += 1

    def _repr_html_(self):
        return table_html([self])

    def __repr__(self):
        return (f"<hamal.Run {self.spec}: {len(self.results)} steps, {format_seconds(self.seconds.sum())} "
                f"in updates, chi2 {self.chi2:.10g}, {self.batches} batches, {self.not_ok} not ok>")


def format_seconds(seconds):
    """A duration as text in the unit that shows it, three significant digits:
    '1.23 s', '12.3 ms', '3.40 us', '120 ns' ('0 s' for zero; nan and inf as they are)."""
    s = float(seconds)
    if not math.isfinite(s):
        return f"{s} s"
    if s == 0:
        return "0 s"
    for scale, unit in ((1.0, "s"), (1e-3, "ms"), (1e-6, "us"), (1e-9, "ns")):
        v = abs(s) / scale
        if v >= 0.9995 or unit == "ns":
            break
    text = f"{v:.0f}" if v >= 99.95 else f"{v:.1f}" if v >= 9.995 else f"{v:.2f}"
    return ("-" if s < 0 else "") + text + " " + unit


class _Progress:
    """Steps done of a run, to a stream: rewritten in place on a terminal (at most
    every 0.2 s), else one line per tenth of the steps."""

    def __init__(self, stream, label, total):
        self.stream, self.label, self.total = stream, label, total
        self.tty = bool(getattr(stream, "isatty", lambda: False)())
        self.start = self.last = time.perf_counter()
        self.next_tenth = 1

    def step(self, done):
        now = time.perf_counter()
        if self.tty:
            if now - self.last < 0.2:
                return
            self.stream.write(f"\r{self._line(done, now)}")
        else:
            if self.total <= 0 or done * 10 < self.next_tenth * self.total:
                return
            while done * 10 >= self.next_tenth * self.total:
                self.next_tenth += 1
            self.stream.write(self._line(done, now) + "\n")
        self.last = now
        self.stream.flush()

    def finish(self, done):
        line = f"{self.label}: {done} steps in {format_seconds(time.perf_counter() - self.start)}"
        self.stream.write(("\r" + line + " " * 20 if self.tty else line) + "\n")
        self.stream.flush()

    def _line(self, done, now):
        return (f"{self.label}: step {done}/{self.total} ({100 * done // max(self.total, 1)}%), "
                f"{format_seconds(now - self.start)}")


def _stream(progress):
    if progress is True:
        return sys.stderr
    return progress or None


def run(source, backend, max_steps=0, progress=False):
    """Runs `backend` (a spec string or a hamal.Backend) over `source` (a Graph,
    stepped by the thesis protocol, or a StepSource), one update per step
    (max_steps > 0: only the first max_steps). progress: False (silent), True
    (to stderr) or a stream to report the steps done to."""
    if isinstance(source, Graph):
        source = ThesisProtocol(source)
    if not isinstance(source, StepSource):
        raise TypeError("source: expected a hamal.Graph or a hamal.StepSource")
    b = make_backend(backend) if isinstance(backend, str) else backend
    if not isinstance(b, Backend):
        raise TypeError("backend: expected a spec string or a hamal.Backend")
    prior = source.prior if isinstance(source, ThesisProtocol) else None
    steps_total = len(source) if max_steps <= 0 else min(max_steps, len(source))
    stream = _stream(progress)
    report = _Progress(stream, b.spec, steps_total) if stream else None
    results, steps = [], []
    start = time.perf_counter()
    for step in source.steps(b, max_steps):
        results.append(b.update(step))
        steps.append(step)
        if report:
            report.step(len(results))
    # The closing verdict before the estimate is read: it may adopt a better
    # answer (as apps/bench/step_runner.h does for every tool).
    closing = b.closing_verdict() if results and results[-1].status.ok else None
    wall = time.perf_counter() - start
    if report:
        report.finish(len(results))
    factors = [f for s in steps for f in s.new_factors if prior is None or f is not prior]
    return Run(b.spec, results, factors, b.estimate(), wall, closing)


def compare(source, backends, max_steps=0, progress=True):
    """One Run per back-end spec over `source` (a Graph or a file path), in order.
    progress: True (default) reports each run's steps on stderr, False is silent,
    or a stream to write them to."""
    graph = read_graph(source) if isinstance(source, str) else source
    return [run(graph, spec, max_steps, progress) for spec in backends]


_HEADER = ["back-end", "steps", "total", "p50", "p99", "max", "batches", "final chi2", "not ok"]


def _rows(runs):
    rows = []
    for r in runs:
        s = r.seconds if len(r.seconds) else np.array([math.nan])
        rows.append([r.spec, str(len(r.results)), format_seconds(s.sum()),
                     format_seconds(np.percentile(s, 50)), format_seconds(np.percentile(s, 99)),
                     format_seconds(s.max()), str(r.batches), f"{r.chi2:.5f}", str(r.not_ok)])
    return rows


def table_html(runs):
    """table(runs) as an HTML table (what a Jupyter notebook shows for a Run)."""
    import html
    cells = lambda row, tag: "".join(f"<{tag}>{html.escape(c)}</{tag}>" for c in row)  # noqa: E731
    return ("<table><thead><tr>" + cells(_HEADER, "th") + "</tr></thead><tbody>"
            + "".join("<tr>" + cells(row, "td") + "</tr>" for row in _rows(runs)) + "</tbody></table>")


def table(runs):
    """A plain-text table, one row per Run: steps, the time of all updates and the
    median, 99th percentile and slowest update (each in the unit that shows it),
    batches, final chi2 and updates not ok."""
    header = _HEADER
    rows = [header] + _rows(runs)
    widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
    lines = ["  ".join(cell.rjust(w) if i else cell.ljust(w) for i, (cell, w) in enumerate(zip(row, widths)))
             for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)
