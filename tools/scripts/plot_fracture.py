#!/usr/bin/python3
"""Chart for `brittle bench fracture` (docs/results/data/fracture.csv): fragment count and the
largest fragment's mass share against impact speed, every seed as a dot, the median as a line
and the 10–90 % band shaded. Writes docs/results/data/fracture.png next to the CSV and prints
the figures docs/results/ quotes."""
import csv
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

TITLES = {"plate": "glass plate, 100 g steel ball", "brick": "concrete brick dropped on a corner"}


def quantile(values, q):
    return float(np.quantile(np.asarray(values, dtype=float), q))


def main(path="docs/results/data/fracture.csv"):
    rows = list(csv.DictReader(open(path, newline="")))
    cases = [c for c in ("plate", "brick") if any(r["case"] == c for r in rows)]
    fig, axes = plt.subplots(2, len(cases), figsize=(5.5 * len(cases), 7.5), squeeze=False)
    rng = np.random.default_rng(1)
    for col, case in enumerate(cases):
        mine = [r for r in rows if r["case"] == case]
        speeds = sorted({float(r["speed_mps"]) for r in mine})
        by = {v: [r for r in mine if float(r["speed_mps"]) == v] for v in speeds}
        for row, (key, label) in enumerate([("fragments", "fragments"),
                                            ("largest_mass_fraction", "largest fragment / body mass")]):
            ax = axes[row][col]
            values = {v: [float(r[key]) for r in by[v]] for v in speeds}
            for v in speeds:
                jitter = np.exp(rng.uniform(-0.04, 0.04, len(values[v])))
                ax.scatter(v * jitter, values[v], s=8, alpha=0.35, color="tab:blue")
            ax.plot(speeds, [statistics.median(values[v]) for v in speeds], "o-", color="tab:red", label="median")
            ax.fill_between(speeds, [quantile(values[v], 0.1) for v in speeds], [quantile(values[v], 0.9) for v in speeds],
                            color="tab:red", alpha=0.15, label="10–90 %")
            ax.set_xscale("log")
            if key == "fragments":
                ax.set_yscale("log")
                tets = mine[0]["tets"]
                ax.set_title(f"{TITLES.get(case, case)} ({tets} tets, {mine[0]['modes']} modes)", fontsize=10)
            else:
                ax.set_ylim(0, 1.05)
            ax.set_xlabel("impact speed (m/s)")
            ax.set_ylabel(label)
            ax.legend(fontsize=8)
    seeds = len({r["seed"] for r in rows})
    fig.suptitle(f"Fracture statistics against impact speed ({seeds} seeds per speed)")
    out = Path(path).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")
    for case in cases:
        mine = [r for r in rows if r["case"] == case]
        for v in sorted({float(r["speed_mps"]) for r in mine}):
            sel = [r for r in mine if float(r["speed_mps"]) == v]
            n = [int(r["fragments"]) for r in sel]
            lf = [float(r["largest_mass_fraction"]) for r in sel]
            broken = sum(int(r["broken"]) for r in sel)
            print(f"{case} {v:6.1f} m/s: broken {broken}/{len(sel)}, fragments median {statistics.median(n):.0f} "
                  f"(p10 {quantile(n, 0.1):.0f}, p90 {quantile(n, 0.9):.0f}), largest {statistics.median(lf):.2f} "
                  f"(p10 {quantile(lf, 0.1):.2f}, p90 {quantile(lf, 0.9):.2f}), "
                  f"impact {statistics.median(float(r['impact_ms']) for r in sel):.1f} ms")


if __name__ == "__main__":
    main(*sys.argv[1:])
