#!/usr/bin/python3
"""Charts for brittle_bench_modal's CSV (docs/results/data/modal_solve.csv).

Writes docs/results/data/modal_solve.png (modal solve time against DOF, per method and mode
count, with the single-factorisation floor) and docs/results/data/tet_meshing.png (Mesh_3 time
against element count), and prints the medians and ratios docs/results/ quotes.
"""
import csv
import math
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k, v in r.items():
            try:
                r[k] = float(v)
            except ValueError:
                r[k] = math.nan
    return rows


def main():
    src = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/results/data/modal_solve.csv")
    rows = load(src)
    out_dir = src.parent
    methods = [
        ("arpack_cholmod_s", "ARPACK + CHOLMOD (bake, incl. checks)", "-o"),
        ("arpack_core_s", "ARPACK + CHOLMOD (solve only)", ":o"),
        ("arpack_eigen_s", "ARPACK + Eigen LDLT", "-s"),
        ("spectra_cholmod_s", "Spectra + CHOLMOD", "-^"),
        ("dense_s", "dense (Eigen)", "-x"),
    ]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharey=True)
    for ax, r in zip(axes, sorted({int(x["modes"]) for x in rows})):
        sel = [x for x in rows if int(x["modes"]) == r]
        dof = [x["dof"] for x in sel]
        for key, label, style in methods:
            pts = [(d, x[key]) for d, x in zip(dof, sel) if not math.isnan(x[key])]
            if pts:
                ax.plot(*zip(*pts), style, label=label)
        ax.plot(dof, [x["cholmod_factor_s"] for x in sel], "k--", label="one CHOLMOD factorisation")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("degrees of freedom (3N)")
        ax.set_title(f"lowest {r} elastic modes (+6 rigid)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("wall time (s)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "modal_solve.png", dpi=120)

    fig, ax = plt.subplots(figsize=(6, 4.5))
    sizes = {}
    for x in rows:
        sizes[int(x["tets"])] = x["mesh_s"]
    ax.plot(list(sizes), list(sizes.values()), "-o")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("tetrahedra")
    ax.set_ylabel("CGAL Mesh_3 time incl. perturb + exude (s)")
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "tet_meshing.png", dpi=120)

    print("| DOF | r | tets | mesh (s) | CHOLMOD factor (s) | ARPACK+CHOLMOD (s) | solve / factor | "
          "ARPACK+Eigen LDLT / ARPACK+CHOLMOD | Spectra / ARPACK (solve only) | dense (s) | max residual |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for x in rows:
        print(f"| {int(x['dof'])} | {int(x['modes'])} | {int(x['tets'])} | {x['mesh_s']:.3f} | {x['cholmod_factor_s']:.3f} | "
              f"{x['arpack_cholmod_s']:.3f} | {x['arpack_over_factor']:.1f} | {x['arpack_eigen_s'] / x['arpack_cholmod_s']:.2f} | "
              f"{x['spectra_cholmod_s'] / x['arpack_core_s']:.2f} | {x['dense_s']:.2f} | {x['max_residual']:.1e} |")
    ratios = [x["arpack_over_factor"] for x in rows]
    print(f"median solve/factorisation ratio: {statistics.median(ratios):.2f}")
    print(f"wrote {out_dir / 'modal_solve.png'} and {out_dir / 'tet_meshing.png'}")


if __name__ == "__main__":
    main()
