#!/usr/bin/python3
"""Chart for `brittle bench resolution` (docs/results/data/resolution.csv): frequency error of
the lowest modes and bake time against the tet count. Writes docs/results/data/resolution.png
next to the CSV and prints the figures docs/results/ quotes."""
import csv
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path="docs/results/data/resolution.csv"):
    rows = list(csv.DictReader(open(path, newline="")))
    tets = sorted({int(r["tets"]) for r in rows})
    by = {t: [r for r in rows if int(r["tets"]) == t] for t in tets}
    fig, (err_ax, time_ax) = plt.subplots(1, 2, figsize=(11, 4.2))
    modes = sorted({int(r["mode"]) for r in rows})
    for m in [modes[0], modes[len(modes) // 2], modes[-1]]:
        err_ax.loglog(tets, [100 * abs(float(next(r for r in by[t] if int(r["mode"]) == m)["error"])) for t in tets],
                      "o-", label=f"mode {m + 1}")
    err_ax.loglog(tets, [100 * max(abs(float(r["error"])) for r in by[t]) for t in tets], "k--", label="worst mode")
    err_ax.set_xlabel("tets")
    err_ax.set_ylabel("|frequency error| vs extrapolated (%)")
    err_ax.legend(fontsize=8)
    time_ax.loglog(tets, [float(by[t][0]["bake_s"]) for t in tets], "o-", label="bake total")
    time_ax.loglog(tets, [float(by[t][0]["meshing_s"]) for t in tets], "x--", label="meshing")
    time_ax.loglog(tets, [float(by[t][0]["modal_s"]) for t in tets], "s:", label="modes (ARPACK)")
    time_ax.set_xlabel("tets")
    time_ax.set_ylabel("time (s)")
    time_ax.legend(fontsize=8)
    fig.suptitle(f"Tet resolution: frequency error and bake time ({len(modes)} modes)")
    out = Path(path).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")
    for t in tets:
        errs = [100 * abs(float(r["error"])) for r in by[t]]
        print(f"{t:7d} tets: frequency error median {statistics.median(errs):.2f} %, worst {max(errs):.2f} %, "
              f"bake {float(by[t][0]['bake_s']):.2f} s")


if __name__ == "__main__":
    main(*sys.argv[1:])
