"""Checks that lamina read a DXF's geometry faithfully, with ezdxf's own geometry as the truth.

    check_dxf_import.py DRAWING.dxf NETWORK.json [--tol 0.05] [--hatch]

ezdxf reads the drawing, expands every INSERT (nested, MINSERT arrays) and every polyline (into
LINEs and bulge ARCs) into virtual entities, and flattens each LINE, ARC, CIRCLE, ELLIPSE and
SPLINE of model space with the entity's own exact construction (not ezdxf's Bézier paths, which
approximate arcs), 50 times finer than the chord tolerance, in millimetres by the file's
$INSUNITS. With --hatch, so is every edge of every HATCH boundary path (model space and inserted
blocks: lines, bulged polyline segments, arcs, ellipses and splines by their construction tools,
taken from the HATCH's OCS and elevation to world coordinates).
Then, in both directions:
  - every node of lamina's network lies within the tolerance of that geometry;
  - every point of that geometry (sampled every tolerance/2) lies within the tolerance of one of
    lamina's edges, so nothing was dropped and every chord stays within the tolerance.
Shares no code with lamina.
"""
import argparse
import json
import math
import sys

import ezdxf
import numpy as np
from scipy.spatial import cKDTree
from ezdxf import units as ezunits
from ezdxf.entities.boundary_paths import BoundaryPathType, EdgeType
from ezdxf.math import OCS, ConstructionArc, bulge_to_arc

CURVES = {"LINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE"}


def expand(entities, hatch):
    for e in entities:
        kind = e.dxftype()
        if kind == "INSERT":
            for cell in e.multi_insert():
                yield from expand(cell.virtual_entities(), hatch)
        elif kind in ("LWPOLYLINE", "POLYLINE"):
            yield from expand(e.virtual_entities(), hatch)
        elif kind in CURVES or (hatch and kind == "HATCH"):
            yield e


def flatten(e, step):
    if e.dxftype() == "HATCH":
        return hatch_edges(e, step)
    if e.dxftype() == "LINE":
        return [[e.dxf.start, e.dxf.end]]
    if e.dxftype() in ("ARC", "CIRCLE"):
        return [list(e.flattening(sagitta=step))]
    return [list(e.flattening(distance=step))]


def hatch_edges(h, step):
    """Every edge of every boundary path, each a polyline in world coordinates."""
    ocs = OCS(h.dxf.extrusion)
    z = h.dxf.elevation.z
    out = []
    for path in h.paths:
        if path.type == BoundaryPathType.POLYLINE:
            v = [(x, y, b) for x, y, b in path.vertices]
            for i, (x0, y0, b) in enumerate(v):
                x1, y1, _ = v[(i + 1) % len(v)]
                if b:
                    c, a0, a1, r = bulge_to_arc((x0, y0), (x1, y1), b)
                    arc = ConstructionArc(c, r, math.degrees(a0), math.degrees(a1))
                    out.append(list(arc.flattening(sagitta=step)))
                else:
                    out.append([(x0, y0), (x1, y1)])
        else:
            for edge in path.edges:
                if edge.type == EdgeType.LINE:
                    out.append([edge.start, edge.end])
                elif edge.type == EdgeType.ARC:
                    out.append(list(edge.construction_tool().flattening(sagitta=step)))
                else:
                    out.append(list(edge.construction_tool().flattening(distance=step)))
    return [[ocs.to_wcs((p[0], p[1], z)) for p in line] for line in out]


def reference_polylines(dxf_path, tol, hatch=False):
    doc = ezdxf.readfile(dxf_path)
    unit = doc.header.get("$INSUNITS", 0)
    scale = ezunits.conversion_factor(unit, ezunits.MM) if unit else 1.0
    lines = []
    for e in expand(doc.modelspace(), hatch):
        for line in flatten(e, tol / 50 / scale):
            pts = np.array([tuple(v) for v in line], float)
            if len(pts):
                lines.append(pts * scale)
    return lines


def seg_distances(points, a, b, within):
    """Distance from each point to the nearest segment a[i]-b[i]: exact wherever it is at most
    `within`; beyond, a lower bound that is itself beyond `within` (enough to fail the point).

    The segments are cut into pieces at most `piece` long, so a point within `within` of a piece
    lies within `within + piece / 2` of the piece's midpoint: a k-d tree of the midpoints finds
    every piece that can matter, and the distances to those are computed exactly."""
    piece = 4.0 * within
    ab = b - a
    cuts = np.maximum(1, np.ceil(np.linalg.norm(ab, axis=1) / piece)).astype(int)
    seg = np.repeat(np.arange(len(a)), cuts)
    first = np.repeat(np.cumsum(cuts) - cuts, cuts)
    step = np.arange(len(seg)) - first
    t0 = (step / cuts[seg])[:, None]
    t1 = ((step + 1) / cuts[seg])[:, None]
    pa = a[seg] + t0 * ab[seg]
    pb = a[seg] + t1 * ab[seg]
    tree = cKDTree((pa + pb) / 2)
    reach = within + piece / 2 + 1e-9 * piece
    near = tree.query_ball_point(points, reach, return_sorted=False)
    counts = np.fromiter((len(n) for n in near), int, len(points))
    best = tree.query(points)[0] - piece / 2
    best = np.maximum(best, within * (1 + 1e-12) + 1e-300)
    if counts.sum():
        which = np.concatenate([np.asarray(n, int) for n in near if n])
        owner = np.repeat(np.arange(len(points)), counts)
        qa, qb = pa[which], pb[which]
        qab = qb - qa
        len2 = np.maximum((qab * qab).sum(1), 1e-300)
        p = points[owner]
        t = np.clip(((p - qa) * qab).sum(1) / len2, 0.0, 1.0)
        d = np.linalg.norm(p - (qa + t[:, None] * qab), axis=1)
        exact = np.full(len(points), np.inf)
        np.minimum.at(exact, owner, d)
        found = counts > 0
        # Where a candidate is within reach, the exact minimum over the candidates is the
        # distance if it is at most `within` (the nearest piece is then among them).
        ok = found & (exact <= within)
        best[ok] = exact[ok]
    # The points that fail (few, unless lamina is badly wrong): their distance by brute force,
    # for an honest maximum in the message.
    far = np.flatnonzero(best > within)[:2000]
    for i in far:
        t = np.clip(((points[i] - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0, 1)
        best[i] = np.linalg.norm(points[i] - (a + t[:, None] * ab), axis=1).min()
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dxf")
    ap.add_argument("network")
    ap.add_argument("--tol", type=float, default=0.05)
    ap.add_argument("--hatch", action="store_true", help="read HATCH boundaries too")
    a = ap.parse_args()
    ref = reference_polylines(a.dxf, a.tol, a.hatch)
    if not ref:
        print(f"{a.dxf}: no geometry in model space", file=sys.stderr)
        return 1
    ra = np.concatenate([r[:-1] for r in ref if len(r) > 1])
    rb = np.concatenate([r[1:] for r in ref if len(r) > 1])
    with open(a.network) as f:
        net = json.load(f)
    nodes = np.array([n["p"] for n in net["nodes"]], float)
    edges = np.array([[e["a"], e["b"]] for e in net["edges"]], int)
    slack = 1e-9 * max(1.0, float(np.abs(nodes).max()))
    # Lamina's nodes on the true geometry.
    off = seg_distances(nodes, ra, rb, a.tol + slack)
    bad = int((off > a.tol + slack).sum())
    # The true geometry, sampled, near lamina's edges.
    samples = []
    for r in ref:
        for p, q in zip(r[:-1], r[1:]):
            k = max(1, int(np.ceil(np.linalg.norm(q - p) / (a.tol / 2))))
            samples.append(p + np.linspace(0, 1, k, endpoint=False)[:, None] * (q - p))
        samples.append(r[-1:])
    samples = np.concatenate(samples)
    missed = seg_distances(samples, nodes[edges[:, 0]], nodes[edges[:, 1]], a.tol + slack)
    far = int((missed > a.tol + slack).sum())
    print(f"{a.dxf}: {len(nodes)} nodes, {len(edges)} edges; nodes off the drawing: {bad} "
          f"(max {off.max():.4g} mm); drawing points away from the edges: {far} of {len(samples)} "
          f"(max {missed.max():.4g} mm), tolerance {a.tol} mm")
    return 0 if bad == 0 and far == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
