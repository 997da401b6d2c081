#!/usr/bin/python3
"""Chart 5, for `brittle bench exact-modes` (docs/results/data/exact_modes.csv): per fragment,
the database match against the fragment's own modal analysis at runtime (the exact path), both
against the reference bake of the fragment's exact surface. Left: time per fragment against its
size (tets of its own mesh). Right: the error of the first three frequencies against the same
size. Medians per size bin as lines. Writes docs/results/data/exact_modes.png next to the CSV
and prints the figures docs/results/ quotes, with the largest size bin whose median exact time
stays within the budget (--budget-ms, default 20 ms).

When the CSV has the match's predicted error (packs from version 4: the database's leave-one-out
calibration, MatchErrors.h), it also writes <csv name>_calibration.png: the predicted median and
90th percentile against the measured error of each match, and prints how well they are calibrated
(the share of measured errors within each: 0.5 and 0.9 if calibrated) and the rank correlation of
predicted and measured errors. The same for the bodies' own frequencies when the pack has their
calibration (brittle calibrate-errors): <csv name>_ritz_calibration.png (the Ritz values) and
<csv name>_checked_calibration.png (checked on the fragment's mesh)."""
import argparse
import csv
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def number(text):
    try:
        value = float(text)
    except ValueError:
        return math.nan
    return value


def binned(x, y, edges):
    centres, medians = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = [v for u, v in zip(x, y) if lo <= u < hi and math.isfinite(v)]
        if sel:
            centres.append(math.sqrt(lo * hi))
            medians.append(float(np.median(sel)))
    return centres, medians


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("csv", nargs="?", default="docs/results/data/exact_modes.csv")
    parser.add_argument("--budget-ms", type=float, default=20.0)
    args = parser.parse_args()
    rows = [r for r in csv.DictReader(open(args.csv, newline="")) if int(r["parent_tets"]) > 0]
    # With `--entries N,...` each fragment has a row per database size: chart the whole database.
    if rows and "database_entries" in rows[0]:
        largest = max(int(r["database_entries"]) for r in rows)
        rows = [r for r in rows if int(r["database_entries"]) == largest]
    if not rows:
        raise SystemExit("no fragment rows in " + args.csv)
    tets = [int(r["parent_tets"]) for r in rows]
    match_ms = [1e3 * number(r["match_s"]) for r in rows]
    exact_ms = [1e3 * number(r["exact_s"]) for r in rows]
    match_err = [100 * number(r["match_freq_err"]) for r in rows]
    exact_err = [100 * number(r["exact_freq_err"]) for r in rows]
    # The fragment's own frequencies from its moments (polynomial Ritz, degree 5), when measured.
    has_poly = "polynomial5_freq_err" in rows[0]
    poly_ms = [1e3 * number(r["polynomial5_s"]) for r in rows] if has_poly else []
    poly_err = [100 * number(r["polynomial5_freq_err"]) for r in rows] if has_poly else []
    poly = [(poly_ms, poly_err, "polynomial Ritz, degree 5 (own moments)", "tab:green")] if has_poly else []
    # ... corrected by the fragment's own linear-tet mesh (meshFrequencyRatios), when measured: its
    # time is the correction's, on top of the Ritz.
    has_ratio = "mesh_ratio_freq_err" in rows[0]
    ratio_ms = [1e3 * number(r["mesh_ratio_s"]) for r in rows] if has_ratio else []
    ratio_err = [100 * number(r["mesh_ratio_freq_err"]) for r in rows] if has_ratio else []
    if has_ratio:
        poly.append((ratio_ms, ratio_err, "degree 5 corrected by its own mesh", "tab:purple"))
    edges = np.geomspace(max(1, min(tets)) * 0.999, max(tets) * 1.001, 9)

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    for values, label, colour in [(match_ms, "database match", "tab:blue"), (exact_ms, "exact path (own modes)", "tab:red")] + \
            [(t, label, colour) for t, _, label, colour in poly]:
        left.scatter(tets, values, s=10, alpha=0.35, color=colour)
        left.plot(*binned(tets, values, edges), "o-", color=colour, label=label)
    left.axhline(args.budget_ms, color="grey", ls="--", lw=1, label=f"budget {args.budget_ms:g} ms")
    left.set_xscale("log")
    left.set_yscale("log")
    left.set_xlabel("fragment size (tets of the broken body it holds a part of)")
    left.set_ylabel("time per fragment (ms)")
    left.legend(fontsize=8)
    for values, label, colour in [(match_err, "database match", "tab:blue"), (exact_err, "exact path (own modes)", "tab:red")] + \
            [(e, label, colour) for _, e, label, colour in poly]:
        left_ok = [(t, v) for t, v in zip(tets, values) if math.isfinite(v)]
        right.scatter([t for t, _ in left_ok], [max(v, 1e-3) for _, v in left_ok], s=10, alpha=0.35, color=colour)
        right.plot(*binned(tets, values, edges), "o-", color=colour, label=label)
    right.set_xscale("log")
    right.set_yscale("log")
    right.set_xlabel("fragment size (tets of the broken body it holds a part of)")
    right.set_ylabel("first-3-frequency error vs reference bake (%)")
    right.legend(fontsize=8)
    modes = sorted({r["modes"] for r in rows})
    fig.suptitle(f"Chart 5: database match against the fragment's own modal analysis ({len(rows)} fragments, "
                 f"{'/'.join(modes)} modes)")
    fig.tight_layout()
    out = Path(args.csv).with_suffix(".png")
    fig.savefig(out, dpi=100)
    print(f"chart: {out}")

    def med(v):
        v = [x for x in v if math.isfinite(x)]
        return float(np.median(v)) if v else math.nan

    print(f"fragments: {len(rows)}, tets {min(tets)}..{max(tets)}")
    print(f"median time: match {med(match_ms):.2f} ms, exact {med(exact_ms):.2f} ms")
    print(f"median frequency error: match {med(match_err):.1f} %, exact {med(exact_err):.1f} %")
    if has_poly:
        finite = sorted(v for v in poly_err if math.isfinite(v))
        p90 = finite[int(0.9 * (len(finite) - 1))] if finite else math.nan
        print(f"polynomial Ritz (degree 5): median error {med(poly_err):.1f} % (p90 {p90:.1f} %), median time {med(poly_ms):.2f} ms")
    if has_ratio:
        finite = sorted(v for v in ratio_err if math.isfinite(v))
        p90 = finite[int(0.9 * (len(finite) - 1))] if finite else math.nan
        print(f"  corrected by its own mesh: median error {med(ratio_err):.1f} % (p90 {p90:.1f} %), median time {med(ratio_ms):.2f} ms")
        # The size the World compares with meshRatioMaxDof: the check's own cut (check_dof, CutCells::Prisms);
        # data from before it have the exact path's (p1_dof).
        dof = [number(r["check_dof"] if "check_dof" in r else r["p1_dof"]) for r in rows]
        if "mesh_ratio_p2_freq_err" in rows[0]:
            p2 = sorted(100 * number(r["mesh_ratio_p2_freq_err"]) for r in rows if math.isfinite(number(r["mesh_ratio_p2_freq_err"])))
            p2_ms = [1e3 * number(r["mesh_ratio_p2_s"]) for r in rows]
            print(f"  corrected by its own mesh in P2 tets: median error {float(np.median(p2)):.1f} % "
                  f"(p90 {p2[int(0.9 * (len(p2) - 1))]:.1f} %), median time {med(p2_ms):.2f} ms")
            if "check_predicted_p90" in rows[0]:
                # FractureSettings::frequencyErrorTarget: a piece whose checked body is predicted over
                # the target is checked again in P2 (every piece here is within the later check's limit).
                for target in (0.25, 0.5, 1.0):
                    up = [math.isfinite(number(r["check_predicted_p90"])) and number(r["check_predicted_p90"]) > target for r in rows]
                    err = sorted(100 * number(r["mesh_ratio_p2_freq_err" if u else "mesh_ratio_freq_err"]) for r, u in zip(rows, up))
                    cost = sum(1e-3 * x for x, u in zip(p2_ms, up) if u)
                    print(f"  escalated to P2 over a target of {target:g}: {sum(up)} of {len(rows)} pieces, median error "
                          f"{float(np.median(err)):.1f} % (p90 {err[int(0.9 * (len(err) - 1))]:.1f} %), P2 time {cost:.1f} s in all")
        for cap in (800, 900, 1500, 3000, 6000):
            capped = sorted(e if d <= cap else p for e, p, d in zip(ratio_err, poly_err, dof) if math.isfinite(e) and math.isfinite(p))
            taken = sum(1 for d in dof if d <= cap)
            print(f"  corrected up to {cap} DOF ({taken} of {len(rows)}): median {float(np.median(capped)):.1f} %, "
                  f"p90 {capped[int(0.9 * (len(capped) - 1))]:.1f} %")
    centres, medians = binned(tets, exact_ms, edges)
    for c, m, me in zip(centres, medians, binned(tets, match_ms, edges)[1]):
        print(f"  ~{c:7.0f} tets: exact {m:8.2f} ms, match {me:6.2f} ms")
    within = [t for t, m in zip(tets, exact_ms) if math.isfinite(m) and m <= args.budget_ms]
    fit = np.polyfit(np.log([t for t, m in zip(tets, exact_ms) if math.isfinite(m)]),
                     np.log([m for m in exact_ms if math.isfinite(m)]), 1)
    crossing = math.exp((math.log(args.budget_ms) - fit[1]) / fit[0])
    print(f"exact time ~ tets^{fit[0]:.2f}; the fit crosses {args.budget_ms:g} ms at {crossing:.0f} tets "
          f"(largest fragment within the budget: {max(within) if within else 0} tets)")
    stem = Path(args.csv).stem
    if "predicted_err_p90" in rows[0]:
        calibration(rows, Path(args.csv).with_name(stem + "_calibration.png"))
    if "ritz_predicted_p90" in rows[0]:  # the bodies' own frequencies (World::frequencyError)
        calibration(rows, Path(args.csv).with_name(stem + "_ritz_calibration.png"), "ritz_predicted_median", "ritz_predicted_p90",
                    "polynomial5_freq_err", "Ritz values (degree 5)")
        calibration(rows, Path(args.csv).with_name(stem + "_checked_calibration.png"), "check_predicted_median", "check_predicted_p90",
                    "mesh_ratio_freq_err", "Ritz values checked on the fragment's mesh")


def ranks(values):
    order = np.argsort(values, kind="stable")
    r = np.empty(len(values))
    r[order] = np.arange(len(values))
    return r


def calibration(rows, out, median_column="predicted_err_median", p90_column="predicted_err_p90", measured_column="match_freq_err",
                what="Match"):
    """Predicted against measured error (the match's, by default; or a body's own frequencies'),
    on the fragments with both."""
    pts = [(number(r[median_column]), number(r[p90_column]), number(r[measured_column]),
            r["object"], r.get("predicted_beyond_range") == "1" and median_column == "predicted_err_median") for r in rows]
    pts = [p for p in pts if all(math.isfinite(x) for x in p[:3])]
    if not pts:
        print(f"{what} error calibration: no fragment has both a predicted and a measured error")
        return
    median, p90, measured = (np.array([p[i] for p in pts]) for i in range(3))
    fig, ax = plt.subplots(figsize=(6, 5.5))
    for obj in sorted({p[3] for p in pts}):
        sel = [i for i, p in enumerate(pts) if p[3] == obj]
        ax.scatter(100 * p90[sel], 100 * measured[sel], s=14, alpha=0.6, label=f"{obj}: predicted p90")
    ax.scatter(100 * median, 100 * measured, s=8, marker="x", color="grey", alpha=0.5, label="predicted median")
    top = 100 * max(measured.max(), p90.max()) * 1.1
    ax.plot([0.1, top], [0.1, top], "k--", lw=1, label="measured = predicted")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"predicted error: {what} (%)")
    ax.set_ylabel("measured error, f1..f3 vs reference (%)")
    within50, within90 = float(np.mean(measured <= median)), float(np.mean(measured <= p90))
    ax.set_title(f"{what}: error predicted against measured ({len(pts)} fragments)\n"
                 f"measured within the median {within50:.2f} (0.5 if calibrated), within p90 {within90:.2f} (0.9)",
                 fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    rho = float(np.corrcoef(ranks(p90), ranks(measured))[0, 1]) if len(pts) > 2 else math.nan
    beyond = sum(1 for p in pts if p[4])
    print(f"{what} error calibration ({len(pts)} fragments, {beyond} beyond the calibrated distances): "
          f"measured within the predicted median {within50:.2f}, within the predicted p90 {within90:.2f}; "
          f"median predicted p90 {100 * float(np.median(p90)):.1f} %, median measured {100 * float(np.median(measured)):.1f} %; "
          f"rank correlation {rho:.2f}")
    print(f"chart: {out}")


if __name__ == "__main__":
    main()
