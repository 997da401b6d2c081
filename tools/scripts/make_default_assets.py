#!/usr/bin/env python3
"""Generates the default meshes of assets/meshes/ as OFF files (SI units: metres).

Every mesh is a closed, outward-oriented, 2-manifold triangle mesh. The script checks that before
writing (edges shared by exactly two faces with opposite directions, one fan per vertex, Euler
characteristic 2, no degenerate or intersecting faces, positive volume) and prints each volume
next to its analytic value, so a bad edit of a profile fails here rather than in the bake.

Pure Python 3 (no numpy), deterministic output.

    python3 tools/scripts/make_default_assets.py [--out assets/meshes]
"""

import argparse
import math
import os
import sys
from collections import defaultdict

# ---------------------------------------------------------------------------------------------
# Small vector helpers (tuples of three floats).


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def norm(a):
    return math.sqrt(dot(a, a))


# ---------------------------------------------------------------------------------------------
# Shapes. Each returns (vertices, faces) with faces as counter-clockwise (outward) index triples.


def make_box(sx, sy, sz):
    """Axis-aligned box centred at the origin: 8 vertices, 2 triangles per face."""
    hx, hy, hz = sx / 2, sy / 2, sz / 2
    verts = [(x, y, z) for z in (-hz, hz) for y in (-hy, hy) for x in (-hx, hx)]
    # Vertex index = x + 2y + 4z with x, y, z in {0, 1}. Quads listed counter-clockwise seen from
    # outside.
    quads = [
        (0, 2, 3, 1),  # z = -hz
        (4, 5, 7, 6),  # z = +hz
        (0, 1, 5, 4),  # y = -hy
        (2, 6, 7, 3),  # y = +hy
        (0, 4, 6, 2),  # x = -hx
        (1, 3, 7, 5),  # x = +hx
    ]
    faces = []
    for a, b, c, d in quads:
        faces += [(a, b, c), (a, c, d)]
    return verts, faces


def make_icosphere(radius, level):
    """Icosphere: an icosahedron subdivided `level` times, vertices projected onto the sphere.
    Chosen over a UV sphere because it has no sliver triangles at the poles."""
    t = (1 + math.sqrt(5)) / 2
    base = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
            (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    verts = [tuple(c / norm(v) for c in v) for v in base]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        midpoint = {}

        def mid(i, j):
            key = (min(i, j), max(i, j))
            if key not in midpoint:
                m = tuple((verts[i][k] + verts[j][k]) / 2 for k in range(3))
                verts.append(tuple(c / norm(m) for c in m))
                midpoint[key] = len(verts) - 1
            return midpoint[key]

        new_faces = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new_faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new_faces
    return [tuple(radius * c for c in v) for v in verts], faces


def make_revolution(profile, segments):
    """Surface of revolution about the z axis. `profile` is a list of (r, z) from a point on the
    axis to another point on the axis, with r > 0 in between; the ends become triangle fans (the
    poles), the rest quads split in two. Orientation is fixed afterwards from the signed volume."""
    assert profile[0][0] == 0 and profile[-1][0] == 0
    assert all(r > 0 for r, _ in profile[1:-1])
    verts = [(0.0, 0.0, profile[0][1])]
    ring_start = []
    for r, z in profile[1:-1]:
        ring_start.append(len(verts))
        for k in range(segments):
            a = 2 * math.pi * k / segments
            verts.append((r * math.cos(a), r * math.sin(a), z))
    verts.append((0.0, 0.0, profile[-1][1]))
    first_pole, last_pole = 0, len(verts) - 1
    faces = []
    for k in range(segments):
        k1 = (k + 1) % segments
        faces.append((first_pole, ring_start[0] + k1, ring_start[0] + k))
        for i in range(len(ring_start) - 1):
            a, b = ring_start[i], ring_start[i + 1]
            faces += [(a + k, a + k1, b + k1), (a + k, b + k1, b + k)]
        faces.append((last_pole, ring_start[-1] + k, ring_start[-1] + k1))
    if signed_volume(verts, faces) < 0:
        faces = [(a, c, b) for a, b, c in faces]
    return verts, faces


def revolved_polyhedron_volume(profile, segments):
    """Exact volume of make_revolution's polyhedron: each band between two rings is a frustum of
    regular polygons (its quads are planar trapezoids), with cross-section area c·r², r linear in
    z, c = (N/2)·sin(2π/N). As N → ∞, c → π and this becomes the smooth solid's volume."""
    c = segments / 2 * math.sin(2 * math.pi / segments)
    v = 0.0
    for (r1, z1), (r2, z2) in zip(profile, profile[1:]):
        v += (z2 - z1) * (r1 * r1 + r1 * r2 + r2 * r2) / 3
    return abs(c * v), abs(math.pi * v)


def smooth_curve(points, samples_per_span):
    """Uniform Catmull-Rom spline through (z, r) control points; the end
    tangents reuse the end points, so the curve stays inside the control polygon's range."""
    out = []
    n = len(points)
    for i in range(n - 1):
        p0 = points[max(i - 1, 0)]
        p1, p2 = points[i], points[i + 1]
        p3 = points[min(i + 2, n - 1)]
        for s in range(samples_per_span):
            t = s / samples_per_span
            t2, t3 = t * t, t * t * t
            out.append(tuple(
                0.5 * (2 * p1[k] + (-p0[k] + p2[k]) * t + (2 * p0[k] - 5 * p1[k] + 4 * p2[k] - p3[k]) * t2 +
                       (-p0[k] + 3 * p1[k] - 3 * p2[k] + p3[k]) * t3) for k in range(2)))
    out.append(points[-1])
    return out


def vase_profile():
    """(r, z) profile of a hollow vase: bottom, outer wall, rounded lip, inner wall, floor.
    Height 0.25 m; the wall is the outer curve shifted inward by `wall`, which keeps the true
    (normal) thickness >= 6 mm where the wall is sloped (checked in main)."""
    wall = 0.008        # horizontal wall offset (m)
    floor = 0.012       # bottom thickness (m)
    foot = 0.004        # radius of the rounded outer foot edge (m)
    height = 0.25
    # Outer silhouette (z, r): foot, belly, neck, flared mouth.
    control = [(0.0, 0.050), (0.03, 0.066), (0.085, 0.080), (0.14, 0.068), (0.19, 0.040),
               (0.225, 0.036), (height - wall / 2, 0.044)]
    outer = smooth_curve(control, 3)  # (z, r) samples from z = 0 up to the lip
    r0 = outer[0][1]

    profile = [(0.0, 0.0)]
    # Outer bottom: flat disc rings, then a quarter-circle foot edge into the outer wall.
    for r in (0.35 * r0, 0.7 * r0):
        profile.append((r, 0.0))
    for j in range(4):
        a = -math.pi / 2 + (math.pi / 2) * j / 4
        profile.append((r0 - foot + foot * math.cos(a), foot + foot * math.sin(a)))
    for z, r in outer[1:]:
        if z > foot:
            profile.append((r, z))
    # Rounded lip: a half circle from the outer wall's top over to the inner wall's top.
    z_top, r_top = outer[-1]
    for j in range(1, 9):
        a = math.pi * j / 8
        profile.append((r_top - wall / 2 + (wall / 2) * math.cos(a), z_top + (wall / 2) * math.sin(a)))
    # Inner wall, going down, then the floor back to the axis.
    for z, r in reversed(outer[:-1]):
        if z > floor:
            profile.append((r - wall, z))
    r_floor = interpolate_r(outer, floor) - wall
    profile.append((r_floor, floor))
    for r in (0.66 * r_floor, 0.33 * r_floor):
        profile.append((r, floor))
    profile.append((0.0, floor))
    return profile


def interpolate_r(curve, z):
    for (z1, r1), (z2, r2) in zip(curve, curve[1:]):
        if z1 <= z <= z2:
            return r1 + (r2 - r1) * (z - z1) / (z2 - z1)
    raise ValueError("z outside the curve")


def min_wall_thickness(profile):
    """Smallest distance between two profile points that are far apart along the profile, i.e.
    the thinnest part of the solid in the (r, z) half-plane, axis ends excluded."""
    pts = profile
    arc = [0.0]
    for a, b in zip(pts, pts[1:]):
        arc.append(arc[-1] + math.dist(a, b))
    best = math.inf
    for i, p in enumerate(pts):
        for j in range(len(pts) - 1):
            # Points within one wall thickness of arc length are neighbours, not opposite walls.
            if abs(arc[i] - arc[j]) < 0.03 or abs(arc[i] - arc[j + 1]) < 0.03:
                continue
            best = min(best, point_segment_distance_2d(p, pts[j], pts[j + 1]))
    return best


def point_segment_distance_2d(p, a, b):
    ab = (b[0] - a[0], b[1] - a[1])
    ap = (p[0] - a[0], p[1] - a[1])
    t = max(0.0, min(1.0, (ap[0] * ab[0] + ap[1] * ab[1]) / (ab[0] ** 2 + ab[1] ** 2)))
    return math.dist(p, (a[0] + t * ab[0], a[1] + t * ab[1]))


# ---------------------------------------------------------------------------------------------
# Checks.


def signed_volume(verts, faces):
    v = 0.0
    for a, b, c in faces:
        v += dot(verts[a], cross(verts[b], verts[c]))
    return v / 6


def check_closed_manifold(verts, faces):
    """Raises if the mesh is not a closed, consistently oriented, vertex-manifold genus-0 surface."""
    directed = defaultdict(int)
    for f in faces:
        if len(set(f)) != 3:
            raise ValueError(f"face {f} repeats a vertex")
        for i in range(3):
            directed[(f[i], f[(i + 1) % 3])] += 1
    for (a, b), n in directed.items():
        if n != 1:
            raise ValueError(f"directed edge {a}->{b} used {n} times (inconsistent orientation)")
        if directed.get((b, a), 0) != 1:
            raise ValueError(f"edge {a}-{b} is a boundary edge (mesh is open)")
    # One fan per vertex: the edges opposite a vertex form a single cycle.
    link = defaultdict(dict)
    for a, b, c in faces:
        link[a][b] = c
        link[b][c] = a
        link[c][a] = b
    for v, nxt in link.items():
        start = next(iter(nxt))
        cur, steps = start, 0
        while True:
            cur = nxt[cur]
            steps += 1
            if cur == start:
                break
        if steps != len(nxt):
            raise ValueError(f"vertex {v} is non-manifold ({len(nxt)} neighbours, fan of {steps})")
    if len(link) != len(verts):
        raise ValueError("unreferenced vertices")
    edges = len(directed) // 2
    euler = len(verts) - edges + len(faces)
    if euler != 2:
        raise ValueError(f"Euler characteristic {euler}, expected 2 (genus 0)")
    for f in faces:
        area2 = norm(cross(sub(verts[f[1]], verts[f[0]]), sub(verts[f[2]], verts[f[0]])))
        if area2 < 1e-14:
            raise ValueError(f"face {f} is degenerate")


def unit(a):
    n = norm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


# Distances below this (metres) count as touching. The meshes are 0.01–1 m across, so this is far
# below any real feature and far above rounding error.
kTouch = 1e-12


def point_in_triangle(x, tri, n):
    """x lies in tri's plane (unit normal n); closed test."""
    for i in range(3):
        a, b = tri[i], tri[(i + 1) % 3]
        if dot(cross(sub(b, a), sub(x, a)), n) < -kTouch * norm(sub(b, a)):
            return False
    return True


def project_2d(points, n):
    """Drops the coordinate along n's dominant axis (the projection keeps the plane's topology)."""
    axis = max(range(3), key=lambda k: abs(n[k]))
    keep = [k for k in range(3) if k != axis]
    return [(p[keep[0]], p[keep[1]]) for p in points]


def segments_intersect_2d(a, b, c, d):
    def orient(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    def on_segment(p, q, r):
        return min(p[0], q[0]) - kTouch <= r[0] <= max(p[0], q[0]) + kTouch and \
            min(p[1], q[1]) - kTouch <= r[1] <= max(p[1], q[1]) + kTouch

    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    tol = kTouch * kTouch
    if ((o1 > tol and o2 < -tol) or (o1 < -tol and o2 > tol)) and \
       ((o3 > tol and o4 < -tol) or (o3 < -tol and o4 > tol)):
        return True
    return (abs(o1) <= tol and on_segment(a, b, c)) or (abs(o2) <= tol and on_segment(a, b, d)) or \
        (abs(o3) <= tol and on_segment(c, d, a)) or (abs(o4) <= tol and on_segment(c, d, b))


def point_in_triangle_2d(x, tri):
    signs = []
    for i in range(3):
        a, b = tri[i], tri[(i + 1) % 3]
        signs.append((b[0] - a[0]) * (x[1] - a[1]) - (b[1] - a[1]) * (x[0] - a[0]))
    return all(s >= 0 for s in signs) or all(s <= 0 for s in signs)


def coplanar_triangles_intersect(p, q, n):
    p2, q2 = project_2d(p, n), project_2d(q, n)
    for i in range(3):
        for j in range(3):
            if segments_intersect_2d(p2[i], p2[(i + 1) % 3], q2[j], q2[(j + 1) % 3]):
                return True
    return point_in_triangle_2d(p2[0], q2) or point_in_triangle_2d(q2[0], p2)


def segment_hits_triangle(a, b, tri, n):
    """Closed segment [a, b] against closed triangle tri with unit normal n."""
    da, db = dot(n, sub(a, tri[0])), dot(n, sub(b, tri[0]))
    if (da > kTouch and db > kTouch) or (da < -kTouch and db < -kTouch):
        return False
    if abs(da) <= kTouch and abs(db) <= kTouch:
        t2 = project_2d(tri, n)
        a2, b2 = project_2d([a, b], n)
        return point_in_triangle_2d(a2, t2) or any(
            segments_intersect_2d(a2, b2, t2[i], t2[(i + 1) % 3]) for i in range(3))
    t = da / (da - db)
    x = tuple(a[k] + t * (b[k] - a[k]) for k in range(3))
    return point_in_triangle(x, tri, n)


def triangles_intersect(p, q):
    """Exact-in-spirit test for two triangles that share no vertex (with a kTouch tolerance, so
    touching counts as intersecting): non-coplanar triangles meet iff an edge of one meets the
    other; coplanar ones are tested in 2D."""
    n_p = unit(cross(sub(p[1], p[0]), sub(p[2], p[0])))
    n_q = unit(cross(sub(q[1], q[0]), sub(q[2], q[0])))
    if all(abs(dot(n_q, sub(v, q[0]))) <= kTouch for v in p):
        return coplanar_triangles_intersect(p, q, n_q)
    return any(segment_hits_triangle(p[i], p[(i + 1) % 3], q, n_q) for i in range(3)) or \
        any(segment_hits_triangle(q[i], q[(i + 1) % 3], p, n_p) for i in range(3))


def check_no_self_intersection(verts, faces):
    """Broad phase on a uniform grid of face bounding boxes, then triangles_intersect for faces
    that share no vertex. Faces sharing a vertex or an edge are not tested: the manifold check
    already rules out the ways they could overlap that matter for meshing (folds show up as
    inconsistent orientation or a negative volume)."""
    lo = [min(v[k] for v in verts) for k in range(3)]
    hi = [max(v[k] for v in verts) for k in range(3)]
    cells_per_axis = max(1, int(round(len(faces) ** (1 / 3))))
    size = [max((hi[k] - lo[k]) / cells_per_axis, 1e-9) for k in range(3)]
    grid = defaultdict(list)
    boxes = []
    for fi, f in enumerate(faces):
        b_lo = [min(verts[i][k] for i in f) for k in range(3)]
        b_hi = [max(verts[i][k] for i in f) for k in range(3)]
        boxes.append((b_lo, b_hi))
        rng = [range(int((b_lo[k] - lo[k]) / size[k]), int((b_hi[k] - lo[k]) / size[k]) + 1) for k in range(3)]
        for x in rng[0]:
            for y in rng[1]:
                for z in rng[2]:
                    grid[(x, y, z)].append(fi)
    tested = set()
    for cell in grid.values():
        for i_pos, fi in enumerate(cell):
            for fj in cell[i_pos + 1:]:
                key = (min(fi, fj), max(fi, fj))
                if key in tested:
                    continue
                tested.add(key)
                if set(faces[fi]) & set(faces[fj]):
                    continue
                (alo, ahi), (blo, bhi) = boxes[fi], boxes[fj]
                if any(ahi[k] < blo[k] or bhi[k] < alo[k] for k in range(3)):
                    continue
                if triangles_intersect([verts[i] for i in faces[fi]], [verts[i] for i in faces[fj]]):
                    raise ValueError(f"faces {faces[fi]} and {faces[fj]} intersect")
    return len(tested)


# ---------------------------------------------------------------------------------------------
# Output.


def write_off(path, verts, faces, comment):
    with open(path, "w", encoding="ascii", newline="\n") as out:
        out.write("OFF\n")
        out.write(f"# {comment}\n")
        out.write(f"{len(verts)} {len(faces)} 0\n")
        for v in verts:
            out.write(" ".join(f"{c:.7g}" if abs(c) > 1e-15 else "0" for c in v) + "\n")
        for f in faces:
            out.write(f"3 {f[0]} {f[1]} {f[2]}\n")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    default_out = os.path.normpath(os.path.join(here, "..", "..", "assets", "meshes"))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=default_out, help="output directory (default: assets/meshes)")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    segments = 48
    profile = vase_profile()
    thickness = min_wall_thickness(profile)
    if thickness < 0.006:
        sys.exit(f"vase wall is {thickness * 1e3:.2f} mm thin, expected >= 6 mm")
    vase_poly, vase_smooth = revolved_polyhedron_volume(profile, segments)
    sphere_exact = 4 / 3 * math.pi * 0.1 ** 3

    # name, (verts, faces), analytic volume of this polyhedron, reference note, description
    shapes = [
        ("plate.off", make_box(0.3, 0.3, 0.01), 0.3 * 0.3 * 0.01, "box", "glass pane 0.3 x 0.3 x 0.01 m"),
        ("beam.off", make_box(1.0, 0.1, 0.1), 1.0 * 0.1 * 0.1, "box", "beam 1 x 0.1 x 0.1 m"),
        ("brick.off", make_box(0.215, 0.1025, 0.065), 0.215 * 0.1025 * 0.065, "box",
         "brick 0.215 x 0.1025 x 0.065 m"),
        ("vase.off", make_revolution(profile, segments), vase_poly,
         f"revolved polygon (smooth solid {vase_smooth * 1e6:.2f} cm^3)",
         f"hollow vase, height 0.25 m, wall >= {thickness * 1e3:.1f} mm, {segments} segments"),
        ("ball.off", make_icosphere(0.1, 3), None, f"sphere r = 0.1 m: {sphere_exact * 1e6:.2f} cm^3",
         "icosphere r = 0.1 m, level 3"),
    ]
    failed = False
    for name, (verts, faces), analytic, note, description in shapes:
        try:
            check_closed_manifold(verts, faces)
            pairs = check_no_self_intersection(verts, faces)
            volume = signed_volume(verts, faces)
            if volume <= 0:
                raise ValueError(f"signed volume {volume} is not positive (inward-facing)")
            if analytic is not None and abs(volume - analytic) > 1e-9 * analytic:
                raise ValueError(f"volume {volume} differs from the analytic {analytic}")
        except ValueError as e:
            print(f"{name}: FAILED: {e}", file=sys.stderr)
            failed = True
            continue
        path = os.path.join(args.out, name)
        write_off(path, verts, faces, description + " (generated by tools/scripts/make_default_assets.py)")
        ref = f"analytic {analytic * 1e6:.4f} cm^3 ({note})" if analytic is not None else note
        print(f"{name}: {len(verts)} vertices, {len(faces)} faces, {os.path.getsize(path) / 1024:.0f} KiB, "
              f"volume {volume * 1e6:.4f} cm^3, {ref}; {pairs} face pairs tested, closed, "
              f"oriented, manifold, no self-intersection")
    if failed:
        sys.exit(1)


if __name__ == "__main__":
    main()
