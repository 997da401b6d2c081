#!/usr/bin/python3
"""Chart for `brittle bench elements` (docs/results/data/elements.csv): P1 against P2 tets, the
first frequency's error against the degrees of freedom and the impact time against that error,
per case. Writes docs/results/data/elements.png next to the CSV and prints the figures
docs/results/ quotes."""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path="docs/results/data/elements.csv"):
    rows = list(csv.DictReader(open(path, newline="")))
    cases = list(dict.fromkeys(r["case"] for r in rows))
    colours = dict(zip(cases, ["tab:blue", "tab:orange", "tab:green", "tab:red"]))
    fig, (err_ax, time_ax) = plt.subplots(1, 2, figsize=(11, 4.4))
    for c in cases:
        for element, style in (("p1", "o-"), ("p2", "s--")):
            sel = sorted((r for r in rows if r["case"] == c and r["element"] == element), key=lambda r: int(r["dofs"]))
            if not sel:
                continue
            label = f"{c} {element.upper()}"
            err = [max(100 * abs(float(r["error"])), 1e-3) for r in sel]
            err_ax.loglog([int(r["dofs"]) for r in sel], err, style, color=colours[c], label=label)
            time_ax.loglog(err, [float(r["median_impact_ms"]) for r in sel], style, color=colours[c], label=label)
    for ax in (err_ax, time_ax):
        ax.grid(True, which="both", alpha=0.3)
    err_ax.axhline(2.0, color="grey", lw=0.8, ls=":")
    time_ax.axvline(2.0, color="grey", lw=0.8, ls=":")
    err_ax.set_xlabel("degrees of freedom (3 × FEM nodes)")
    err_ax.set_ylabel("|first-frequency error| vs converged (%)")
    time_ax.set_xlabel("|first-frequency error| (%)")
    time_ax.set_ylabel("impact time, median (ms)")
    err_ax.legend(fontsize=8)
    fig.suptitle("P1 against P2 tets: accuracy per DOF, and impact time per accuracy (dotted: the 2 % target)")
    out = Path(path).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")
    print("case  element   tets    dofs   f1 (Hz)   error    impact ms")
    for r in rows:
        print(f"{r['case']:5s} {r['element']:7s} {int(r['tets']):6d} {int(r['dofs']):7d} {float(r['first_frequency_hz']):9.1f} "
              f"{100 * float(r['error']):+7.2f} % {float(r['median_impact_ms']):8.2f}")


if __name__ == "__main__":
    main(*sys.argv[1:])
