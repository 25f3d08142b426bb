#!/usr/bin/env python3
"""Three back-ends on M3500 under the thesis protocol, from Python: a plain
table (the columns of hamal_bench's summary) and a plot of the step times.

    PYTHONPATH=build/python python3 python/examples/m3500_comparison.py \
        --backend "aprilsam;aprilsam-top;cholesky" --output m3500_step_times.png

or at a Python prompt (python/README.md, "From a fresh clone"):

    >>> import m3500_comparison as c
    >>> runs = c.compare()
    >>> print(c.table(runs)); c.plot(runs, "m3500_step_times.png")
"""

import argparse

import numpy as np

import hamal

DEFAULT_BACKENDS = ("aprilsam", "aprilsam-top", "cholesky")


def compare(data=None, backends=DEFAULT_BACKENDS, max_steps=0):
    """One hamal.Run per back-end spec over the dataset (M3500 by default)."""
    graph = hamal.read_graph(data or hamal.dataset("M3500.toro"))
    return [hamal.run(graph, spec, max_steps) for spec in backends]


def table(runs):
    """A plain-text table: one row per run."""
    header = ["back-end", "steps", "cumulative s", "p50 ms", "p99 ms", "max ms", "batches",
              "final chi2", "not ok"]
    rows = [header]
    for r in runs:
        ms = r.seconds * 1e3
        rows.append([r.spec, str(len(r.results)), f"{r.seconds.sum():.3f}",
                     f"{np.percentile(ms, 50):.2f}", f"{np.percentile(ms, 99):.2f}", f"{ms.max():.2f}",
                     str(r.batches), f"{r.chi2:.5f}", str(r.not_ok)])
    widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
    lines = ["  ".join(cell.rjust(w) if i else cell.ljust(w) for i, (cell, w) in enumerate(zip(row, widths)))
             for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def plot(runs, path):
    """Step time against step, one line per back-end, log scale, written to `path`."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for r in runs:
        ax.plot(np.arange(len(r.seconds)), np.maximum(r.seconds * 1e3, 1e-4), lw=0.6, label=r.spec)
    ax.set_yscale("log")
    ax.set_xlabel("step (pose)")
    ax.set_ylabel("update time (ms)")
    ax.set_title("M3500, thesis protocol: time of each update")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", help="the graph file (default: M3500.toro in the data directory)")
    parser.add_argument("--backend", dest="backends", default=";".join(DEFAULT_BACKENDS),
                        help="';'-separated specs")
    parser.add_argument("--max-steps", type=int, default=0, help="stop after this many steps (0: all)")
    parser.add_argument("--output", default="m3500_step_times.png", help="the plot (.png, .pdf, .svg)")
    args = parser.parse_args()
    runs = compare(args.data, [s for s in args.backends.split(";") if s.strip()], args.max_steps)
    print(table(runs))
    print("plot:", plot(runs, args.output))


if __name__ == "__main__":
    main()
