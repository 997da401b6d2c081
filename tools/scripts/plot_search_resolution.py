#!/usr/bin/python3
"""Chart 4 of the speed/accuracy study: descriptor kind × resolution × database size against the
physical error of the match and the query time. Takes the CSV pairs that `brittle bench search`
wrote for each resolution (search CSV, cost CSV, ...), merges them into
docs/results/data/search_resolution.csv and draws docs/results/data/search_resolution.png: the
median frequency and mass error of the exact match (brute force) against the whole query time,
i.e. describing the fragment from its raw mesh (canonical frames + descriptor of every candidate
frame) plus the search."""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = {"moment": "o", "voxel": "s", "voxel-improved": "^"}


def main(out_csv, *pairs):
    rows = []
    for search, cost in zip(pairs[0::2], pairs[1::2]):
        costs = {r["stage"]: float(r["median_us"]) for r in csv.DictReader(open(cost, newline=""))}
        for r in csv.DictReader(open(search, newline="")):
            kind = r["descriptor"]
            resolution = r["moment_order"] if kind == "moment" else r["voxel_resolution"]
            describe = costs[f"{kind}-total"]
            rows.append({"descriptor": kind, "resolution": int(resolution), "entries": int(r["entries"]),
                         "index": r["index"], "recall_at_1": float(r["recall_at_1"]),
                         "describe_us": describe, "search_us": float(r["query_median_us"]),
                         "query_us": describe + float(r["query_median_us"]),
                         "physics_queries": int(r["physics_queries"]),
                         "mass_err_median": float(r["mass_err_median"]),
                         "frequency_err_median": float(r["frequency_err_median"])})
    rows.sort(key=lambda r: (r["descriptor"], r["resolution"], r["entries"], r["index"]))
    with open(out_csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    exact = [r for r in rows if r["index"] == "brute-force"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for ax, key, label in [(axes[0], "frequency_err_median", "median frequency error of the match (%)"),
                           (axes[1], "mass_err_median", "median mass error of the match (%)")]:
        for kind in MARKERS:
            for entries, color in [(1000, "tab:blue"), (10000, "tab:red")]:
                sel = sorted((r for r in exact if r["descriptor"] == kind and r["entries"] == entries),
                             key=lambda r: r["resolution"])
                if not sel:
                    continue
                ax.plot([r["query_us"] for r in sel], [100 * r[key] for r in sel], marker=MARKERS[kind], color=color,
                        label=f"{kind}, {entries} entries")
                for r in sel:
                    ax.annotate(str(r["resolution"]), (r["query_us"], 100 * r[key]), fontsize=7,
                                textcoords="offset points", xytext=(4, 3))
        ax.set_xscale("log")
        ax.set_xlabel("query time: describe the raw fragment + exact search (µs, median)")
        ax.set_ylabel(label)
        ax.legend(fontsize=7)
    fig.suptitle("Descriptor kind × resolution (labels: moment order, voxels per axis) × database size")
    out = Path(out_csv).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")
    for r in exact:
        print(f"{r['descriptor']:15s} res {r['resolution']:3d} {r['entries']:6d} entries: query {r['query_us']:9.1f} us "
              f"(describe {r['describe_us']:8.1f}, search {r['search_us']:7.1f}), frequency error "
              f"{100 * r['frequency_err_median']:5.1f} %, mass error {100 * r['mass_err_median']:5.2f} % "
              f"({r['physics_queries']} ground truths)")
    for r in rows:
        if r["index"] != "brute-force":
            print(f"{r['descriptor']:15s} res {r['resolution']:3d} {r['entries']:6d} entries {r['index']}: "
                  f"recall {r['recall_at_1']:.2f}, search {r['search_us']:.1f} us, "
                  f"frequency error {100 * r['frequency_err_median']:.1f} %")


if __name__ == "__main__":
    if len(sys.argv) < 4 or len(sys.argv) % 2 != 0:
        sys.exit("usage: plot_search_resolution.py OUT.csv SEARCH.csv COST.csv [SEARCH.csv COST.csv ...]")
    main(*sys.argv[1:])
