"""run(): one back-end fed by the thesis protocol (or any StepSource), one
update per step, as hamal_bench runs it (apps/bench/bench_runner.h): only
the update calls are timed, chi2 is computed afterwards over the dataset's
factors (the protocol's gauge prior is not one)."""

import time

import numpy as np

from ._hamal import Backend, Graph, StepSource, ThesisProtocol, backend as make_backend, chi2


class Run:
    """What run() returns: per-step results and times, the estimate, chi2."""

    def __init__(self, spec, results, factors, estimate, wall_seconds):
        self.spec = spec
        self.results = results              # one hamal.UpdateResult per step
        self.seconds = np.array([r.seconds for r in results])  # update calls alone
        self.factors = factors              # the measurement factors of the steps run
        self.estimate = estimate
        self.chi2 = chi2(factors, estimate)
        self.wall_seconds = wall_seconds    # the whole Python loop, steps made included

    @property
    def batches(self):
        return sum(r.kind == "batch" for r in self.results)

    @property
    def not_ok(self):
        return sum(not r.status.ok() for r in self.results)

    def __repr__(self):
        return (f"<hamal.Run {self.spec}: {len(self.results)} steps, {self.seconds.sum():.3f} s in "
                f"updates, chi2 {self.chi2:.10g}, {self.batches} batches, {self.not_ok} not ok>")


def run(source, backend, max_steps=0):
    """Runs `backend` (a spec string or a hamal.Backend) over `source` (a Graph,
    stepped by the thesis protocol, or a StepSource), one update per step."""
    if isinstance(source, Graph):
        source = ThesisProtocol(source)
    if not isinstance(source, StepSource):
        raise TypeError("source: expected a hamal.Graph or a hamal.StepSource")
    b = make_backend(backend) if isinstance(backend, str) else backend
    if not isinstance(b, Backend):
        raise TypeError("backend: expected a spec string or a hamal.Backend")
    prior = source.prior if isinstance(source, ThesisProtocol) else None
    results, steps = [], []
    start = time.perf_counter()
    for step in source.steps(b, max_steps):
        results.append(b.update(step))
        steps.append(step)
    wall = time.perf_counter() - start
    factors = [f for s in steps for f in s.new_factors if prior is None or f is not prior]
    return Run(b.spec, results, factors, b.estimate(), wall)
