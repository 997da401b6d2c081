#!/usr/bin/python3
"""Pictures of played scenes: `plot_replay.py REPLAY.glb... --out PNG_DIR [--times 0,0.5,1]`.

Reads the glTF 2.0 binary replay `brittle play --out` writes (one mesh and one node per body,
translation/rotation/scale keyed per frame; a body outside its lifetime has scale 0) and draws
the scene at a few instants of the replay side by side (default: start, the middle, the end):
the floor at z = 0 as a grey square, every live body as its triangles, one colour per body.
Writes PNG_DIR/<replay name>.png. Only what the player writes is read: float32 positions,
uint32 or uint16 indices, linear float32 samplers.
"""
import argparse
import json
import struct
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

COMPONENT = {5126: np.float32, 5125: np.uint32, 5123: np.uint16, 5121: np.uint8}
WIDTH = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def read_glb(path):
    data = Path(path).read_bytes()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2:
        raise ValueError(f"{path}: not a glTF 2.0 binary")
    offset, doc, binary = 12, None, b""
    while offset < length:
        size, kind = struct.unpack_from("<I4s", data, offset)
        chunk = data[offset + 8:offset + 8 + size]
        if kind == b"JSON":
            doc = json.loads(chunk)
        elif kind == b"BIN\x00":
            binary = chunk
        offset += 8 + size
    return doc, binary


def accessor(doc, binary, index):
    a = doc["accessors"][index]
    view = doc["bufferViews"][a["bufferView"]]
    dtype = COMPONENT[a["componentType"]]
    width = WIDTH[a["type"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    values = np.frombuffer(binary, dtype=dtype, count=a["count"] * width, offset=start)
    return values.reshape(a["count"], width) if width > 1 else values


def quaternion_matrix(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def sample(times, values, t):
    """The keyed value at time t (linear between keys; quaternions renormalised)."""
    i = int(np.searchsorted(times, t, side="right")) - 1
    if i < 0:
        return values[0]
    if i >= len(times) - 1:
        return values[-1]
    u = (t - times[i]) / (times[i + 1] - times[i])
    v = (1 - u) * values[i] + u * values[i + 1]
    return v / np.linalg.norm(v) if len(v) == 4 else v


def scene_at(doc, binary, t):
    """(world triangles, node index) of every body alive at time t."""
    tracks = {}
    for animation in doc.get("animations", []):
        for channel in animation["channels"]:
            s = animation["samplers"][channel["sampler"]]
            tracks[(channel["target"]["node"], channel["target"]["path"])] = (
                accessor(doc, binary, s["input"]), accessor(doc, binary, s["output"]))
    bodies = []
    for n, node in enumerate(doc["nodes"]):
        if "mesh" not in node:
            continue
        def value(path, default):
            if (n, path) in tracks:
                return sample(*tracks[(n, path)], t)
            return np.array(node.get(path, default), dtype=float)
        scale = value("scale", [1, 1, 1])
        if np.all(np.abs(scale) < 1e-12):
            continue  # not alive at t
        rotation = quaternion_matrix(value("rotation", [0, 0, 0, 1]))
        translation = value("translation", [0, 0, 0])
        primitive = doc["meshes"][node["mesh"]]["primitives"][0]
        positions = accessor(doc, binary, primitive["attributes"]["POSITION"]).astype(float)
        faces = accessor(doc, binary, primitive["indices"]).astype(int).reshape(-1, 3)
        world = (positions * scale) @ rotation.T + translation
        bodies.append((world[faces], n))
    return bodies


def plot(path, out_dir, fractions):
    doc, binary = read_glb(path)
    end = max((float(accessor(doc, binary, s["input"]).max()) for a in doc.get("animations", []) for s in a["samplers"]),
              default=0.0)
    instants = [f * end for f in fractions]
    frames = [scene_at(doc, binary, t) for t in instants]
    # The view frames the scene's start (fragments that fly farther leave the picture).
    start = np.concatenate([tri.reshape(-1, 3) for tri, _ in frames[0]])
    lo, hi = start.min(0), start.max(0)
    centre, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-3) * 1.6
    colours = plt.get_cmap("tab20")
    fig = plt.figure(figsize=(4.2 * len(instants), 4.4))
    for k, (t, bodies) in enumerate(zip(instants, frames)):
        ax = fig.add_subplot(1, len(instants), k + 1, projection="3d")
        floor = [[centre[0] - half, centre[1] - half, 0], [centre[0] + half, centre[1] - half, 0],
                 [centre[0] + half, centre[1] + half, 0], [centre[0] - half, centre[1] + half, 0]]
        ax.add_collection3d(Poly3DCollection([floor], facecolor=(0.85, 0.85, 0.85, 0.5), edgecolor="none"))
        for tris, n in bodies:
            ax.add_collection3d(Poly3DCollection(tris, facecolor=colours(n % 20), edgecolor="none"))
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(0.0, 2 * half)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=25, azim=-60)
        ax.set_title(f"t = {t:.2f} s, {len(bodies)} bodies", fontsize=9)
        ax.set_axis_off()
    fig.suptitle(Path(path).stem)
    out = Path(out_dir) / (Path(path).stem + ".png")
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("replays", nargs="+")
    parser.add_argument("--out", required=True)
    parser.add_argument("--times", default="0,0.5,1", help="instants as fractions of the replay's length")
    args = parser.parse_args()
    Path(args.out).mkdir(parents=True, exist_ok=True)
    fractions = [float(x) for x in args.times.split(",")]
    for replay in args.replays:
        print(f"picture: {plot(replay, args.out, fractions)}")


if __name__ == "__main__":
    main()
