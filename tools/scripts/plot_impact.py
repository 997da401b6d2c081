#!/usr/bin/python3
"""Chart for `brittle bench impact` (docs/results/data/impact_latency.csv): median time per
stage of one impact, pruned, for each tet count and mode count, with the unpruned total beside
it. Writes docs/results/data/impact_latency.png next to the CSV and prints the figures
docs/results/ quotes."""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STAGES = ["contact", "modal", "stress", "propagation", "surfaces", "matching"]


def main(path="docs/results/data/impact_latency.csv"):
    # Crossing cracks only (the World's default); `--cracks end` rows are read from the CSV.
    rows = [r for r in csv.DictReader(open(path, newline="")) if r.get("cracks", "cross") == "cross"]
    settings = sorted({(int(r["tets"]), int(r["modes"])) for r in rows})
    value = {(int(r["tets"]), int(r["modes"]), int(r["prune"]), r["stage"]): float(r["median_ms"]) for r in rows}
    p99 = {(int(r["tets"]), int(r["modes"]), int(r["prune"]), r["stage"]): float(r["p99_ms"]) for r in rows}
    fig, ax = plt.subplots(figsize=(8, 4.5))
    labels = [f"{t} tets\n{m} modes" for t, m in settings]
    bottom = [0.0] * len(settings)
    for stage in STAGES:
        heights = [value.get((t, m, 1, stage), 0.0) for t, m in settings]
        ax.bar(range(len(settings)), heights, bottom=bottom, label=stage, width=0.6)
        bottom = [b + h for b, h in zip(bottom, heights)]
    unpruned = [value.get((t, m, 0, "total"), 0.0) for t, m in settings]
    ax.plot(range(len(settings)), unpruned, "kx", label="total without pruning")
    ax.set_xticks(range(len(settings)), labels)
    ax.set_yscale("log")
    ax.set_ylabel("median time per impact (ms)")
    ax.axhline(1.0, color="grey", ls="--", lw=0.8)
    ax.legend(fontsize=8)
    ax.set_title("Impact latency per stage (glass slab, 100 g ball at 50 m/s; one core)")
    out = Path(path).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"chart: {out}")
    for t, m in settings:
        tot, tot0 = value[(t, m, 1, "total")], value[(t, m, 0, "total")]
        print(f"{t} tets {m} modes: median {tot:.2f} ms, p99 {p99[(t, m, 1, 'total')]:.2f} ms; to initiation "
              f"{value[(t, m, 1, 'to_initiation')]:.2f} ms; unpruned {tot0:.2f} ms ({tot0 / tot:.1f}x); stress "
              f"{value[(t, m, 1, 'stress')]:.2f} vs {value[(t, m, 0, 'stress')]:.2f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
