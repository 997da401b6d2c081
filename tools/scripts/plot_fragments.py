#!/usr/bin/python3
"""Pictures of broken objects: `plot_fragments.py DIR... --out PNG_DIR`.

Each DIR holds the fragment meshes `brittle impact --out DIR` wrote (fragment-NN.off). Writes
PNG_DIR/<DIR name>.png: the fragments in an exploded view (each pushed away from the body's centre
of volume in proportion to its distance), one colour per fragment.
"""
import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_off(path):
    lines = [l for l in Path(path).read_text().splitlines() if l.strip() and not l.startswith("#")]
    if lines[0].strip() != "OFF":
        raise ValueError(f"{path}: not an OFF file")
    nv, nf = map(int, lines[1].split()[:2])
    v = np.array([list(map(float, l.split()[:3])) for l in lines[2:2 + nv]])
    f = np.array([list(map(int, l.split()[1:4])) for l in lines[2 + nv:2 + nv + nf]])
    return v, f


def volume_centroid(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    six = np.einsum("ij,ij->i", a, np.cross(b, c))
    vol = six.sum() / 6.0
    return vol, ((a + b + c) * six[:, None]).sum(0) / (24.0 * vol)


def plot(directory, out_dir, explode=0.35):
    pieces = [read_off(p) for p in sorted(Path(directory).glob("fragment-*.off"))]
    if not pieces:
        return None
    stats = [volume_centroid(v, f) for v, f in pieces]
    total = sum(s[0] for s in stats)
    centre = sum(s[0] * s[1] for s in stats) / total
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    cmap = plt.get_cmap("tab20")
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for i, ((v, f), (vol, c)) in enumerate(zip(pieces, stats)):
        shifted = v + explode * (c - centre)
        lo, hi = np.minimum(lo, shifted.min(0)), np.maximum(hi, shifted.max(0))
        ax.add_collection3d(Poly3DCollection(shifted[f], facecolor=cmap(i % 20), edgecolor="k", linewidth=0.05, alpha=0.95))
    span = (hi - lo).max() / 2
    mid = (hi + lo) / 2
    for setter, m in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), mid):
        setter(m - span, m + span)
    ax.set_title(f"{Path(directory).name}: {len(pieces)} fragments (exploded view)")
    ax.set_axis_off()
    out = Path(out_dir) / f"{Path(directory).name}.png"
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dirs", nargs="+")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    Path(args.out).mkdir(parents=True, exist_ok=True)
    for d in args.dirs:
        out = plot(d, args.out)
        print(f"picture: {out}" if out else f"{d}: no fragments (not broken)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
