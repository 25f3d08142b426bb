#!/usr/bin/env python3
"""Non-zeros during Householder QR of A and Cholesky of A^T A (thesis sec. 3.3,
figs. 3.2 and 3.3).

The graph of fig. 3.2: 100 (x, y, theta) nodes, node i joined by a factor to
each of the three nodes ahead of it (i+1, i+2, i+3, when they exist: 294
factors), and a prior on node 0 so that the problem is well posed. A is the
whitened Jacobian: one 3-row block per factor with a dense 3x3 block in each
of its two nodes' columns (the prior: one block), 885 x 300 scalars, columns
in node order (the natural ordering, as the figure's graph is a band).

The counts are symbolic (structural non-zeros, no numerical cancellation),
taken after each scalar column k = 0..299 has been processed:

* Householder QR of A: column k's reflector is built from every remaining row
  with a non-zero in column k; applying it gives each of those rows the union
  of their structures (columns > k); the pivot row becomes row k of R (it
  keeps column k) and the other rows lose column k. The count is every
  non-zero of the working matrix: the rows of R made so far plus all the
  rows of A not yet pivoted. It starts at nnz(A) and ends at nnz(R).
* Cholesky of A^T A (right-looking, the same operations as up-looking in
  count of fill): eliminating column k makes the rows of its remaining
  column a clique in the Schur complement. The count is the upper triangle
  (with the diagonal) of the working matrix: the rows of R made so far plus
  the upper triangle of the Schur complement. It starts at nnz(triu(A^T A))
  and ends at nnz(R), the same R as QR's.

  nnz_comparison.py [--output DIR]   writes nnz.csv, nnz.png and nnz.svg
"""

import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from old_spellings import old_spelling  # noqa: E402


def chain_graph(nodes=100, ahead=3, dim=3):
    """Rows of A as sets of scalar columns (fig. 3.2's graph plus a prior on node 0)."""
    def block(n):
        return set(range(n * dim, (n + 1) * dim))

    rows = [block(0) for _ in range(dim)]  # the prior
    for i in range(nodes):
        for j in range(i + 1, min(nodes, i + ahead + 1)):
            rows += [block(i) | block(j) for _ in range(dim)]
    return rows, nodes * dim


def householder_qr_counts(rows, columns):
    """Working-matrix non-zeros after each column of Householder QR."""
    active = [set(r) for r in rows]
    r_rows = []
    counts = []
    for k in range(columns):
        touching = [r for r in active if k in r]
        rest = [r for r in active if k not in r]
        union = set().union(*touching) if touching else set()
        if touching:
            r_rows.append(union)  # row k of R
            others = union - {k}
            # Every other row of the reflector gets the union of columns > k.
            rest += [set(others) for _ in range(len(touching) - 1)] if others else []
        active = [r for r in rest if r]
        counts.append(sum(len(r) for r in r_rows) + sum(len(r) for r in active))
    return counts


def cholesky_counts(rows, columns):
    """Working-matrix (upper triangle) non-zeros after each column of Cholesky of A^T A."""
    # Structure of H = A^T A: column sets per column (symmetric).
    adj = [set() for _ in range(columns)]
    for r in rows:
        for c in r:
            adj[c] |= r
    r_nnz = 0
    counts = []
    for k in range(columns):
        below = {c for c in adj[k] if c > k}
        r_nnz += 1 + len(below)  # row k of R: diagonal + the remaining structure
        for c in below:
            adj[c] |= below  # the clique of the eliminated column
            adj[c].discard(k)
        adj[k] = set()
        schur = sum(len([c for c in adj[j] if c >= j]) for j in range(k + 1, columns))
        counts.append(r_nnz + schur)
    return counts


def compute():
    rows, columns = chain_graph()
    nnz_a = sum(len(r) for r in rows)
    h = [set() for _ in range(columns)]
    for r in rows:
        for c in r:
            h[c] |= r
    nnz_h = sum(len([c for c in h[j] if c >= j]) for j in range(columns))
    return {"rows": len(rows), "columns": columns, "nnz_A": nnz_a, "nnz_triu_AtA": nnz_h,
            "qr": householder_qr_counts(rows, columns),
            "cholesky": cholesky_counts(rows, columns)}


def write(out_dir, plt=None):
    """Writes nnz.csv (and nnz.png / nnz.svg when matplotlib is given); returns the counts."""
    result = compute()
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "nnz.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["step", "householder_qr_nnz", "cholesky_nnz"])
        for k, (q, c) in enumerate(zip(result["qr"], result["cholesky"])):
            w.writerow([k + 1, q, c])
    if plt is not None:
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        steps = range(1, result["columns"] + 1)
        ax.plot(steps, result["qr"], label="Householder QR of A")
        ax.plot(steps, result["cholesky"], label="Cholesky of $A^TA$")
        ax.set_xlabel("elimination step (scalar column)")
        ax.set_ylabel("non-zeros in the working matrix")
        ax.set_title("Fig. 3.3: 100 nodes, each joined to the 3 ahead")
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        for ext in ("png", "svg"):
            fig.savefig(os.path.join(out_dir, "nnz." + ext), dpi=120)
        plt.close(fig)
    return result


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--output", dest="out", default=".")
    old_spelling(p, "--out", "--output")
    args = p.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        plt = None
    r = write(args.out, plt)
    print(f"A: {r['rows']} x {r['columns']}, nnz(A) {r['nnz_A']}, nnz(triu(A^T A)) "
          f"{r['nnz_triu_AtA']}; peak during QR {max(r['qr'])}, during Cholesky "
          f"{max(r['cholesky'])}; nnz(R) {r['qr'][-1]} (QR) = {r['cholesky'][-1]} (Cholesky)")


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import script_errors  # noqa: E402
    sys.exit(script_errors.run("nnz_comparison", main))
