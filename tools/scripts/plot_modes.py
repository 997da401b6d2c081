#!/usr/bin/python3
"""Chart for `brittle bench modes` (docs/results/data/modes.csv): peak-stress error against the
full-FEM reference, with and without the static correction, and the impact time, against the
number of modes. Writes docs/results/data/modes.png next to the CSV and prints the figures
docs/results/ quotes."""
import csv
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path="docs/results/data/modes.csv"):
    rows = list(csv.DictReader(open(path, newline="")))
    points = sorted({int(r["point"]) for r in rows})
    fig, (err_ax, time_ax) = plt.subplots(1, 2, figsize=(11, 4.2))
    for p in points:
        sel = sorted((r for r in rows if int(r["point"]) == p), key=lambda r: int(r["modes"]))
        modes = [int(r["modes"]) for r in sel]
        err_ax.plot(modes, [100 * abs(float(r["corrected_error"])) for r in sel], "o-", color=f"C{p}",
                    label=f"point {p}, static correction")
        err_ax.plot(modes, [100 * abs(float(r["uncorrected_error"])) for r in sel], "x--", color=f"C{p}",
                    label=f"point {p}, modes alone")
        time_ax.plot(modes, [float(r["impact_ms"]) for r in sel], "o-", color=f"C{p}", label=f"point {p}, corrected")
        time_ax.plot(modes, [float(r["impact_ms_without_correction"]) for r in sel], "x--", color=f"C{p}",
                     label=f"point {p}, modes alone")
    err_ax.axhline(15, color="grey", ls=":", lw=0.8)
    err_ax.set_xscale("log")
    err_ax.set_yscale("log")
    err_ax.set_xlabel("modes")
    err_ax.set_ylabel("|peak σ₁ error| vs full FEM (%)")
    err_ax.legend(fontsize=7)
    time_ax.set_xscale("log")
    time_ax.set_xlabel("modes")
    time_ax.set_ylabel("impact time, median (ms)")
    tets = rows[0]["tets"]
    fig.suptitle(f"Glass plate 0.3 × 0.3 × 0.01 m, {tets} tets, 100 g steel ball: modes against accuracy and time")
    out = Path(path).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")
    for m in sorted({int(r["modes"]) for r in rows}):
        sel = [r for r in rows if int(r["modes"]) == m]
        c = [100 * float(r["corrected_error"]) for r in sel]
        u = [100 * float(r["uncorrected_error"]) for r in sel]
        t = statistics.median(float(r["impact_ms"]) for r in sel)
        print(f"{m:4d} modes: corrected {min(c):+.1f} .. {max(c):+.1f} %, alone {min(u):+.1f} .. {max(u):+.1f} %, "
              f"impact {t:.2f} ms (median over points)")
    print(f"reference: {statistics.median(float(r['reference_s']) for r in rows):.1f} s per point")


if __name__ == "__main__":
    main(*sys.argv[1:])
