#!/usr/bin/python3
"""Chart for `brittle bench integrators` (docs/results/data/integrators.csv,
docs/results/data/integrator_timing.csv): peak error and late amplitude of each modal integrator
against ωh, one column per damping ratio. Writes docs/results/data/integrators.png next to the
CSV and prints the figures docs/results/ quotes."""
import csv
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ORDER = ["exact", "explicit-euler", "symplectic-euler", "implicit-euler"]
CAP = 1e6  # blown-up values are drawn at the cap


def main(path="docs/results/data/integrators.csv", timing_path="docs/results/data/integrator_timing.csv"):
    rows = list(csv.DictReader(open(path, newline="")))
    zetas = sorted({float(r["zeta"]) for r in rows})
    fig, axes = plt.subplots(2, len(zetas), figsize=(5 * len(zetas), 7), sharex=True, squeeze=False)
    for col, zeta in enumerate(zetas):
        for name in ORDER:
            sel = [r for r in rows if r["integrator"] == name and float(r["zeta"]) == zeta]
            wh = [float(r["omega_h"]) for r in sel]
            for row, key in enumerate(["peak_error", "late_amplitude"]):
                vals = [min(float(r[key]), CAP) if math.isfinite(float(r[key])) else CAP for r in sel]
                axes[row][col].loglog(wh, [max(v, 1e-16) for v in vals], label=name)
        axes[0][col].set_title(f"damping ratio {zeta:g}")
        axes[0][col].set_ylabel("peak error / peak response")
        axes[1][col].set_ylabel("late amplitude / peak response")
        axes[1][col].set_xlabel("ω h (2π = one step per period)")
        for row in range(2):
            ax = axes[row][col]
            ax.axvline(2 * math.pi, color="grey", ls=":", lw=0.8)
            ax.axvline(2.0, color="grey", ls="--", lw=0.6)
            ax.set_ylim(1e-12, CAP * 3)
        axes[1][col].axhline(1.0, color="k", lw=0.6)
    axes[0][0].legend(fontsize=8)
    fig.suptitle("Modal time integrators: 100 µs half-sine pulse, fixed step, mode frequency swept")
    out = Path(path).with_suffix(".png")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")

    # Figures for docs/results/: where each scheme's error passes 10 %, and whether it ever grew.
    for zeta in zetas:
        for name in ORDER:
            sel = [r for r in rows if r["integrator"] == name and float(r["zeta"]) == zeta]
            bad = [float(r["omega_h"]) for r in sel if not float(r["peak_error"]) <= 0.1]
            grew = [float(r["omega_h"]) for r in sel if not float(r["late_amplitude"]) <= 1.0]
            worst = max(float(r["peak_error"]) for r in sel)
            print(f"zeta {zeta:g} {name:17s} error > 10% from wh = {min(bad) if bad else '-'}; "
                  f"late amplitude > peak from wh = {min(grew) if grew else '-'}; worst error {worst:.3g}")
    if Path(timing_path).exists():
        for r in csv.DictReader(open(timing_path, newline="")):
            print(f"{r['integrator']:17s} {float(r['ns_per_mode_step']):.2f} ns per mode and step "
                  f"({float(r['ratio_to_exact']):.2f} x exact)")


if __name__ == "__main__":
    main(*sys.argv[1:])
