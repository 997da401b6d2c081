#!/usr/bin/python3
"""Charts for `brittle bench search` (docs/results/data/search.csv,
docs/results/data/descriptor_cost.csv).

Writes, next to the CSV:
  search_recall_vs_time.png   recall@1 against median query time, one panel per descriptor: the
                              project's indexes (FLANN kd-forest, hnswlib on floats and on binary
                              codes) beside FAISS's (HNSW, IVF, binary flat and HNSW), per size
  search_latency_vs_size.png  median query time against database size: brute force and, per index
                              family, the fastest setting with recall >= 0.99
  search_physical_error.png   median frequency error of the match against median query time
and prints the figures docs/results/ quotes.
"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TEXT = {"descriptor", "index", "query_source", "frames"}
# Index families: the project's own (solid) and FAISS's (dashed).
FAMILIES = {"brute-force": ("black", ""), "kd-forest": ("tab:blue", "-"), "autotuned": ("tab:cyan", "-"),
            "hnsw": ("tab:orange", "-"), "hnsw-binary": ("tab:red", "-"),
            "hnsw-pooled": ("tab:brown", "-"), "hnsw-principal": ("tab:gray", "-"), "ivf": ("tab:purple", "-"),
            "hnsw, frames as one set": ("navajowhite", "-"), "hnsw-binary, frames as one set": ("lightcoral", "-"),
            "hnsw-pooled, frames as one set": ("rosybrown", "-"),
            "hnsw-principal, frames as one set": ("silver", "-"),
            "faiss-hnsw": ("tab:green", "--"),
            "faiss-ivf": ("tab:olive", "--"), "faiss-binary-flat": ("darkviolet", "--"),
            "faiss-binary-hnsw": ("tab:pink", "--")}
COLORS = {"moment": "tab:blue", "voxel": "tab:orange", "voxel-improved": "tab:green"}
TARGET_US = 10.0  # the query target at recall@1 >= 0.99


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            if k not in TEXT and k != "stage":
                r[k] = float(v)
        # A graph that searched a fragment's candidate frames in one walk (its ":set" rows) is its
        # own family beside the frame-by-frame search (the default, and every row before it).
        if r["index"] in ("hnsw", "hnsw-binary", "hnsw-pooled") and r.get("frames", "each") == "set":
            r["index"] += ", frames as one set"
    return rows


def label(r):
    if r["index"] == "kd-forest":
        return f"kd {int(r['trees'])}x{int(r['checks'])}"
    if r["index"].split(",")[0] in ("hnsw", "hnsw-binary", "hnsw-pooled", "faiss-hnsw", "faiss-binary-hnsw"):
        return f"{r['index']} M{int(r['trees'])} ef{int(r['checks'])}"
    if r["index"] in ("ivf", "faiss-ivf"):
        return f"{r['index']} {int(r['trees'])}/{int(r['checks'])}"
    return r["index"]


def main():
    src = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/results/data/search.csv")
    rows = load(src)
    out = src.parent
    sizes = sorted({int(r["entries"]) for r in rows})
    kinds = [k for k in COLORS if any(r["descriptor"] == k for r in rows)]
    markers = ["o", "s", "^", "D", "v", "P"]

    fig, axes = plt.subplots(1, len(kinds), figsize=(6 * len(kinds), 5.5), squeeze=False)
    for ax, kind in zip(axes[0], kinds):
        labelled = set()  # each family in the legend once, at whichever size it first appears
        for si, n in enumerate(sizes):
            for family, (color, style) in FAMILIES.items():
                pts = [r for r in rows if r["descriptor"] == kind and int(r["entries"]) == n and r["index"] == family]
                if not pts:
                    continue
                pts.sort(key=lambda r: r["query_median_us"])
                ax.plot([r["query_median_us"] for r in pts], [r["recall_at_1"] for r in pts],
                        style + markers[si % len(markers)], color=color,
                        label=None if family in labelled else family, alpha=0.85)
                labelled.add(family)
        ax.axhline(0.99, color="grey", ls=":", lw=1)
        ax.axvline(TARGET_US, color="grey", ls=":", lw=1)
        ax.set_xscale("log")
        ax.set_xlabel("median query time per fragment (µs, search only)")
        ax.set_ylabel("recall@1 against exact search")
        size_key = ", ".join(f"{markers[i % len(markers)]} {n}" for i, n in enumerate(sizes))
        ax.set_title(f"{kind} (markers: {size_key} entries)", fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"Descriptor search: accuracy against speed\nsolid: brittle's indexes, dashed: FAISS "
                 f"(target: 0.99 at ≤ {TARGET_US:g} µs)")
    fig.tight_layout()
    fig.savefig(out / "search_recall_vs_time.png", dpi=120)

    # Colour: the index family; marker: the descriptor.
    kind_marker = {"moment": "o", "voxel": "s", "voxel-improved": "^"}
    fig, ax = plt.subplots(figsize=(10, 6))
    for kind in kinds:
        for family, (color, style) in FAMILIES.items():
            best = []
            for n in sizes:
                ok = [r for r in rows if r["descriptor"] == kind and int(r["entries"]) == n
                      and r["index"] == family and r["recall_at_1"] >= 0.99]
                if ok:
                    best.append((n, min(r["query_median_us"] for r in ok)))
            if best:
                what = "exact" if family == "brute-force" else "fastest with recall ≥ 0.99"
                ax.plot(*zip(*best), (style or ":") + kind_marker[kind], color=color, alpha=0.85,
                        label=f"{kind}: {family} ({what})")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("database entries")
    ax.set_ylabel("median query time (µs)")
    ax.set_title("Query latency against database size (solid: brittle's indexes, dashed: FAISS)")
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "search_latency_vs_size.png", dpi=120)

    phys = [r for r in rows if r["physics_queries"] > 0]
    if phys:
        fig, ax = plt.subplots(figsize=(8, 5))
        for kind in kinds:
            pts = [r for r in phys if r["descriptor"] == kind]
            ax.scatter([r["query_median_us"] for r in pts], [100 * r["frequency_err_median"] for r in pts],
                       s=[10 + 12 * sizes.index(int(r["entries"])) ** 2 for r in pts], color=COLORS[kind],
                       label=kind, alpha=0.7)
        ax.set_xscale("log")
        ax.set_xlabel("median query time (µs)")
        ax.set_ylabel("median max error of f1..f3 (%)")
        ax.set_title("Physical error of the match (marker size: database size)")
        ax.legend()
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()
        fig.savefig(out / "search_physical_error.png", dpi=120)

    print("entries  descriptor      index                       recall  median_us  p99_us  brute_us  mass%  inertia%  freq%")
    for r in rows:
        print(f"{int(r['entries']):7d}  {r['descriptor']:14s}  {label(r):26s}  {r['recall_at_1']:.3f}  "
              f"{r['query_median_us']:9.1f}  {r['query_p99_us']:6.1f}  {r['brute_median_us']:8.1f}  "
              f"{100 * r['mass_err_median']:5.2f}  {100 * r['inertia_err_median']:7.2f}  "
              f"{100 * r['frequency_err_median']:5.2f}")
    cost = out / "descriptor_cost.csv"
    if cost.exists():
        with open(cost, newline="") as f:
            for r in csv.DictReader(f):
                print(f"descriptor cost {r['stage']:16s} median {float(r['median_us']):9.1f} us "
                      f"({float(r['mean_triangles']):.0f} triangles, "
                      f"{float(r['median_us_per_1k_triangles']):.1f} us per 1k triangles)")


if __name__ == "__main__":
    main()
