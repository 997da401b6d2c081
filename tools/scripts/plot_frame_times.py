#!/usr/bin/python3
"""Frame-time benchmark chart of played scenes: `plot_frame_times.py STATS.json... --out PNG`.

Reads the statistics `brittle play --out-stats F --frames-every 1` writes (one entry per frame:
bullet_s, fracture_s, bodies, time_s) and draws, per scene, the frame time over the simulated time
split into rigid-body simulation (Bullet) and fracture (contact scan, runtime impacts, new
bodies), with the number of bodies over time beside it. Prints a Markdown table per scene:
frame time median / p99 / max, the totals and the share of fracture, and the bodies at the start,
the end and the most. Frames missing from the JSON (--frames-every > 1) are left out of the
series, never invented; the table's percentiles come from the JSON's own summary, computed over
every frame.
"""
import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("stats", nargs="+", help="JSON statistics of brittle play")
    parser.add_argument("--out", default="docs/results/data/frame_times.png")
    args = parser.parse_args()
    docs = [json.load(open(p)) for p in args.stats]
    fig, axes = plt.subplots(len(docs), 2, figsize=(12, 2.8 * len(docs)), squeeze=False)
    print("| scene | frames | frame time median / p99 / max (ms) | Bullet / fracture (s) | fracture share | bodies start → end (max) |")
    print("|---|---|---|---|---|---|")
    for row, doc in zip(axes, docs):
        frames = doc.get("frames", [])
        t = [f["time_s"] for f in frames]
        bullet = [1e3 * f["bullet_s"] for f in frames]
        fracture = [1e3 * f["fracture_s"] for f in frames]
        bodies = [f["bodies"] for f in frames]
        ax = row[0]
        ax.plot(t, [b + c for b, c in zip(bullet, fracture)], lw=0.8, color="black", label="frame (Bullet + fracture)")
        ax.plot(t, bullet, lw=0.6, color="tab:blue", label="Bullet")
        ax.plot(t, [max(c, 1e-4) for c in fracture], lw=0.6, color="tab:red", label="fracture")
        ax.set_yscale("log")
        ax.set_ylabel("ms")
        ax.set_title(f"{doc['scene']}: frame time", fontsize=10)
        ax.legend(fontsize=7, loc="upper right")
        ax2 = row[1]
        ax2.step(t, bodies, where="post", color="tab:green")
        ax2.set_ylabel("bodies")
        ax2.set_title(f"{doc['scene']}: bodies in the simulation", fontsize=10)
        for a in row:
            a.set_xlabel("simulated time (s)")
        s = doc["summary"]
        ft = s["frame_time_s"]
        start = sum(1 for b in doc.get("bodies", []) if b["first_sample"] == 0)
        print(f"| {doc['scene']} | {doc['frame_count']} | {1e3 * ft['median']:.2f} / {1e3 * ft['p99']:.1f} / "
              f"{1e3 * ft['max']:.0f} | {s['bullet_s']:.2f} / {s['fracture_s']:.2f} | {100 * s['fracture_share']:.0f} % | "
              f"{start} → {s['bodies_at_end']} ({s['bodies_max']}) |")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=90)
    print(f"chart: {args.out}")


if __name__ == "__main__":
    main()
