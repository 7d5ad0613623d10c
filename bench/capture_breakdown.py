#!/usr/bin/env python3
"""Where a quad mesh loses its feature capture: splits the sharp-edge length that no quad edge
comes near into its causes, read off the integer-seamless map the quads were extracted from.

  quadify part.obj -o part_quads.obj --map part_map.obj
  bench/capture_breakdown.py part_map.obj part_quads.obj            # one Markdown row
  bench/capture_breakdown.py part_map.obj part_quads.obj --json out.json --header

Feature capture (as `quadify check --reference`): the share of the sharp-edge length (dihedral
angle above --angle) within --tolerance × the bounding-box diagonal of a quad edge, sampled at
0.001 of the diagonal. The sharp edges are those of the map's triangles (the repaired input), so
the figure can differ a little from `quadify check` against the file as read. Each sharp edge is
  aligned     on an integer iso-line of the map (the quads have it as edges, up to chords),
  parallel    along an iso-line that is not an integer one (a feature line the rounding released),
  unaligned   neither (a feature disabled by the wedge check or the τ bound, or never given);
and the missed length of the aligned ones is split by the nearest quad edge:
  chord       both its ends on the feature curve (the curve bends away between them),
  chain end   one end on it (the iso-line leaves the curve where the next feature is unaligned),
  other       neither.
Standard library only.
"""
import argparse
import json
import math
import sys
from collections import defaultdict


def read_obj(path, with_uv):
    vertices, uvs, faces = [], [], []
    with open(path) as f:
        for line in f:
            s = line.split()
            if not s:
                continue
            if s[0] == "v":
                vertices.append(tuple(float(x) for x in s[1:4]))
            elif s[0] == "vt" and with_uv:
                uvs.append(tuple(float(x) for x in s[1:3]))
            elif s[0] == "f":
                corners = [t.split("/") for t in s[1:]]
                v = [int(c[0]) - 1 for c in corners]
                t = [int(c[1]) - 1 if len(c) > 1 and c[1] else -1 for c in corners]
                faces.append((v, t))
    return vertices, uvs, faces


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(dot(a, a))


def segment_distance(p, a, b):
    d = sub(b, a)
    dd = dot(d, d)
    t = 0.0 if dd == 0 else max(0.0, min(1.0, dot(sub(p, a), d) / dd))
    return norm(sub(p, (a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2])))


class SegmentGrid:
    """Segments in a uniform grid of cells as large as the longest one: a point's nearest segment
    within one cell size lies in the 27 cells around it."""

    def __init__(self, segments):
        self.segments = segments
        self.cell = max(norm(sub(b, a)) for a, b in segments) or 1.0
        self.cells = defaultdict(list)
        for i, (a, b) in enumerate(segments):
            m = tuple((a[k] + b[k]) / 2 for k in range(3))
            self.cells[self.key(m)].append(i)

    def key(self, p):
        return tuple(int(math.floor(p[k] / self.cell)) for k in range(3))

    def nearest(self, p):
        """(distance, segment index) of the nearest segment within half a cell, else (inf, -1)."""
        kx, ky, kz = self.key(p)
        best = (math.inf, -1)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for i in self.cells.get((kx + dx, ky + dy, kz + dz), ()):
                        d = segment_distance(p, *self.segments[i])
                        if d < best[0]:
                            best = (d, i)
        return best


ANGLE_DEG = 40     # sharp above this dihedral angle (quadify check's --feature-angle default)
TOLERANCE = 1e-3   # captured within this × bbox diagonal (QuadMetricsOptions::feature_capture_tolerance)
CAUSES = ("unaligned", "parallel", "chain end", "chord", "other")


def breakdown(map_path, quads_path, angle_deg=ANGLE_DEG, tolerance=TOLERANCE):
    """Figures of the map and its quads: sharp_edges, capture (-1 without sharp edges, as quadify
    check), length (share per kind of sharp edge) and missed (share per cause, CAUSES)."""
    V, T, F = read_obj(map_path, True)
    Q, _, QF = read_obj(quads_path, False)
    if not T or any(t < 0 for _, ts in F for t in ts):
        raise ValueError(f"{map_path}: no per-corner UVs (write it with quadify --map)")
    lo = [min(v[k] for v in V) for k in range(3)]
    hi = [max(v[k] for v in V) for k in range(3)]
    diag = norm(sub(tuple(hi), tuple(lo)))
    normals = []
    for vs, _ in F:
        n = cross(sub(V[vs[1]], V[vs[0]]), sub(V[vs[2]], V[vs[0]]))
        length = norm(n)
        normals.append(tuple(x / length for x in n) if length > 0 else None)
    edge_faces = defaultdict(list)  # (a, b), a < b -> [(face, corner of a's side)]
    for f, (vs, _) in enumerate(F):
        for k in range(3):
            a, b = vs[k], vs[(k + 1) % 3]
            edge_faces[(min(a, b), max(a, b))].append((f, k))
    cos_threshold = math.cos(math.radians(angle_deg))
    sharp = {}
    for e, fs in edge_faces.items():
        if len(fs) != 2 or normals[fs[0][0]] is None or normals[fs[1][0]] is None:
            continue
        if dot(normals[fs[0][0]], normals[fs[1][0]]) >= cos_threshold:
            continue
        f, k = fs[0]
        ua, ub = T[F[f][1][k]], T[F[f][1][(k + 1) % 3]]
        kind = "unaligned"
        for c in range(2):
            if abs(ua[c] - ub[c]) < 1e-9:
                kind = "aligned" if abs(ua[c] - round(ua[c])) < 1e-9 else "parallel"
                if kind == "aligned":
                    break
        sharp[e] = kind
    if not sharp:
        return {"sharp_edges": 0, "capture": -1, "length": {}, "missed": {k: 0.0 for k in CAUSES}}
    quad_edges = set()
    for vs, _ in QF:
        for k in range(len(vs)):
            a, b = vs[k], vs[(k + 1) % len(vs)]
            if a != b:
                quad_edges.add((min(a, b), max(a, b)))
    segments = [(Q[a], Q[b]) for a, b in quad_edges if Q[a] != Q[b]]
    if not segments:
        raise ValueError(f"{quads_path}: no quad edges")
    grid = SegmentGrid(segments)
    feature_grid = SegmentGrid([(V[a], V[b]) for a, b in sharp])
    on_curve = 1e-6 * diag
    ends_on_curve = {}  # quad segment -> how many of its ends lie on a sharp edge

    def ends_on_feature(j):
        if j not in ends_on_curve:
            ends_on_curve[j] = sum(feature_grid.nearest(q)[0] <= on_curve for q in segments[j])
        return ends_on_curve[j]

    spacing = 1e-3 * diag
    length = defaultdict(float)
    missed = defaultdict(float)
    total = 0.0
    for (a, b), kind in sharp.items():
        pa, pb = V[a], V[b]
        edge_length = norm(sub(pb, pa))
        n = max(1, math.ceil(edge_length / spacing))
        length[kind] += edge_length
        total += edge_length
        for i in range(n):
            t = (i + 0.5) / n
            p = tuple(pa[k] + t * (pb[k] - pa[k]) for k in range(3))
            d, j = grid.nearest(p)
            if d <= tolerance * diag:
                continue
            cause = kind
            if kind == "aligned":
                cause = ("other", "chain end", "chord")[ends_on_feature(j) if j >= 0 else 0]
            missed[cause] += edge_length / n
    share = lambda x: x / total if total > 0 else 0.0
    return {
        "sharp_edges": len(sharp),
        "capture": 1 - share(sum(missed.values())),
        "length": {k: share(v) for k, v in length.items()},
        "missed": {k: share(missed.get(k, 0.0)) for k in CAUSES},
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("map", help="the integer-seamless map (quadify --map MAP.obj)")
    parser.add_argument("quads", help="the quad mesh extracted from it")
    parser.add_argument("--angle", type=float, default=ANGLE_DEG, help="sharp above this dihedral angle (degrees)")
    parser.add_argument("--tolerance", type=float, default=TOLERANCE, help="captured within this × bbox diagonal")
    parser.add_argument("--name", default=None, help="row name (default: the quads file's stem)")
    parser.add_argument("--header", action="store_true", help="print the Markdown table's header first")
    parser.add_argument("--json", default=None, help="also write the figures to this JSON file")
    args = parser.parse_args()
    try:
        r = breakdown(args.map, args.quads, args.angle, args.tolerance)
    except (OSError, ValueError, IndexError) as e:
        print(f"capture_breakdown: {e}", file=sys.stderr)
        return 1
    name = args.name or args.quads.rsplit("/", 1)[-1].rsplit(".", 1)[0]
    if args.header:
        print("| mesh | sharp edges | capture | missed: unaligned | parallel | chain end | chord | other |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
    m = r["missed"]
    print(f"| {name} | {r['sharp_edges']} | {r['capture']:.4f} | {m['unaligned']:.4f} | {m['parallel']:.4f} | "
          f"{m['chain end']:.4f} | {m['chord']:.4f} | {m['other']:.4f} |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(r, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
