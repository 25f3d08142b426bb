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

import hamal

DEFAULT_BACKENDS = ("aprilsam", "aprilsam-top", "cholesky")


def compare(data=None, backends=DEFAULT_BACKENDS, max_steps=0, progress=True):
    """One hamal.Run per back-end spec over the dataset (M3500 by default); each
    run's progress goes to stderr unless progress=False (hamal.compare)."""
    return hamal.compare(data or hamal.dataset("M3500.toro"), backends, max_steps, progress)


def table(runs):
    """A plain-text table: one row per run (hamal.table)."""
    return hamal.table(runs)


def plot(runs, path):
    """Step time against step, one line per back-end, log scale, written to `path`
    (hamal.plot.step_times)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    hamal.plot.step_times(runs, ax=ax)
    ax.set_title("M3500, thesis protocol: time of each update")
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
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = parser.parse_args()
    runs = compare(args.data, [s for s in args.backends.split(";") if s.strip()], args.max_steps,
                   progress=not args.quiet)
    print(table(runs))
    print("plot:", plot(runs, args.output))


if __name__ == "__main__":
    main()
