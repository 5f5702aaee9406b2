"""Independent check of a simplified `lamina solid` (shares no code with lamina): the mesh and
the exact surface of the veins within the tolerance of each other, both ways.

    check_hausdorff.py SOLID.stl --report solid.json --network NET.json
                       [--tolerance T] [--samples 200000] [--min-reduction 0] [--cell C]
                       [--volume-tolerance 0.001] [--volume-samples 1e6] [--balance 0.2]

The exact solid is rebuilt from the network alone: each edge the hull of a ball at each end
(lamina's documented end-radius rule, from check_solid), scaled by the report's scale, stood up
when upright (+y becomes +z), centred on the z axis from the balls' exact box, lowest point at
z = 0 (as `solid` places it). Checks:
- manifold3d reads the mesh as one valid manifold (status NoError);
- mesh to surface: at every vertex, edge midpoint and triangle centre, and random points on the
  triangles, the distance to the exact surface is at most T. Outside the solid the least of the
  hulls' distances is the distance; inside it is where only one hull is that near; elsewhere
  (where hulls overlap) a surface point is found, and its distance bounds the distance from
  above: where a straight line out of either of the two nearest hulls leaves the union
  (bisection), the end of steps along the union's gradient or out of the deepest hull (their
  total length), a point where the two nearest hulls' surfaces meet outside the others (a
  crease, by Gauss-Newton), and for points still not placed, lines in 64 directions, then
  2048;
- every triangle whole, densely: at the 45 points (i, j, k) / 8 of it, then a local search
  from its worst point inside it; no point more than T outside the union (the least hull
  distance is the distance there), nor deeper than T inside any one hull (a lower bound of its
  distance to the surface: a triangle lying on one vein but inside another that joins it);
- surface to mesh: random points on the exact surface (on each hull, outside the others),
  --samples of them spread by area, are within T of the mesh (trimesh's closest point);
- both ways, a point beyond T in a gap between facing veins (outward directions more than
  120 degrees apart) narrower than the mesher's cell diagonal (sqrt(3) x --cell, default the
  report's march_cell_mm, the grid it marched on, else its cell_mm) fails like any other, and
  is also counted apart: such a gap can fall between the grid points, where the mesher must
  look closer (the marched mesh bridges it); with --excuse-gaps those points are reported and
  not failed (the check before the mesher split cells at gaps);
- the volume (trimesh) within --volume-tolerance of the exact union's, three standard errors
  of the estimate included: each hull's volume is exact (the frustum of the tangent cone and
  two caps), and points drawn in a box about its axis, one uniformly in each cell of a k^3
  grid of it, kept inside it, count for it where no hull of a lower index holds them; four
  independent estimates give the mean and its standard error;
- the mesh on both sides of the surface: of its 45 points a triangle, weighted by area, the
  share inside the solid within 0.5 +- --balance (a mesh whose corners sit on the surface and
  chords under it lies mostly inside);
- what an STL's 32-bit corners and a slicer's plate make of it: no edge shorter than T/100 nor
  triangle lower than that, no vertex below z = 0, and manifold3d with float32 corners keeps
  every triangle, in the report's parts, with its genus;
- with --min-reduction R, the report's marched triangles are at least R times the mesh's.
T defaults to the report's simplified.tolerance_mm. Veins only. Exit 0 pass, 1 fail.
"""
import argparse
import json
import sys

import manifold3d
import numpy as np
import trimesh

from scipy.spatial import cKDTree
from check_solid import end_radii


def cones_of(net, report):
    scale = report["scale"]
    P = np.array([n["p"] for n in net["nodes"]], float) * scale
    if report["upright"]:
        P = np.stack([P[:, 0], -P[:, 2], P[:, 1]], 1)
    cones = [(P[e["a"]], P[e["b"]], r[0] * scale, r[1] * scale)
             for e, r in zip(net["edges"], end_radii(net))]
    lo = np.min([np.minimum(c[0] - c[2], c[1] - c[3]) for c in cones], 0)
    hi = np.max([np.maximum(c[0] + c[2], c[1] + c[3]) for c in cones], 0)
    shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    return [(c[0] + shift, c[1] + shift, c[2], c[3]) for c in cones]


class Hulls:
    """The cones as arrays, for a union limited to `reach`: each point meets only the hulls
    whose bounding sphere, grown by `reach`, holds it (found with a k-d tree of the points);
    elsewhere the value is `reach`, so a value of `reach` means at least that far."""

    def __init__(self, cones, reach):
        self.A = np.array([c[0] for c in cones])
        self.B = np.array([c[1] for c in cones])
        self.RA = np.array([c[2] for c in cones])
        self.RB = np.array([c[3] for c in cones])
        self.centre = (self.A + self.B) / 2
        self.bound = np.linalg.norm(self.B - self.A, axis=1) / 2 + np.maximum(self.RA, self.RB)
        self.reach = reach

    def pairs(self, p):
        """(point, hull) index pairs that may be within reach."""
        tree = cKDTree(p)
        hits = tree.query_ball_point(self.centre, self.bound + self.reach)
        counts = np.array([len(h) for h in hits])
        hull = np.repeat(np.arange(len(hits)), counts)
        point = np.concatenate([np.asarray(h, dtype=np.int64) for h in hits]) if counts.sum() \
            else np.zeros(0, np.int64)
        return point, hull

    def distance(self, p, hull):
        """Signed distance from each p[i] to hull[i] (the hull of two balls, exact)."""
        a, b, ra, rb = self.A[hull], self.B[hull], self.RA[hull], self.RB[hull]
        ab = b - a
        L = np.linalg.norm(ab, axis=1)
        ball = L <= np.abs(ra - rb)
        Ls = np.where(ball, 1.0, L)
        u = ab / Ls[:, None]
        pa = p - a
        t = (pa * u).sum(1)
        q = np.sqrt(np.maximum((pa * pa).sum(1) - t * t, 0))
        # f(s) = sqrt((t - s)^2 + q^2) - ra - (rb - ra) s / L over s in [0, L]: stationary at
        # s = t - q k / sqrt(1 - k^2), k = (ra - rb) / L.
        k = np.where(ball, 0.0, (ra - rb) / Ls)
        s = np.clip(t - q * k / np.sqrt(1 - k * k), 0, Ls)
        cone = np.sqrt((t - s) ** 2 + q * q) - (ra + (rb - ra) * s / Ls)
        balls = np.minimum(np.linalg.norm(p - a, axis=1) - ra, np.linalg.norm(p - b, axis=1) - rb)
        return np.where(ball, balls, cone)

    def two_least(self, p, ids=False):
        """The least and second least hull distances at each point (at most reach), and with
        ids=True the hulls giving them (-1 for none)."""
        d1 = np.full(len(p), self.reach)
        d2 = np.full(len(p), self.reach)
        i1 = np.full(len(p), -1)
        i2 = np.full(len(p), -1)
        if len(p):
            point, hull = self.pairs(p)
            d = self.distance(p[point], hull)
            order = np.lexsort((d, point))
            point, hull, d = point[order], hull[order], d[order]
            first = np.ones(len(point), bool)
            first[1:] = point[1:] != point[:-1]
            second = np.zeros(len(point), bool)
            second[1:] = first[:-1] & ~first[1:]
            for mask, dk, ik in ((first, d1, i1), (second, d2, i2)):
                close = mask & (d < self.reach)
                dk[point[close]] = d[close]
                ik[point[close]] = hull[close]
        return (d1, i1, d2, i2) if ids else (d1, d2)

    def union(self, p):
        return self.two_least(p)[0]

    def hull_gradient(self, p, hull, h=1e-6):
        """Unit gradient of each point's own hull's distance (central differences)."""
        g = np.stack([self.distance(p + h * e, hull) - self.distance(p - h * e, hull)
                      for e in np.eye(3)], 1)
        return g / np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)


def exit_along(p, g, length, hulls):
    """For points p inside the union: the distance along the unit directions g to a point
    outside it, if one lies within `length` (inf otherwise). The first of a few trial lengths
    that is outside, then bisection between it and the inside."""
    out = np.full(len(p), np.inf)
    hi = np.full(len(p), np.inf)
    for f in (1 / 16, 1 / 8, 1 / 4, 1 / 2, 1):
        todo = np.isinf(hi)
        if not todo.any():
            break
        L = length[todo] * f
        outside = hulls.union(p[todo] + g[todo] * L[:, None]) >= 0
        idx = np.nonzero(todo)[0][outside]
        hi[idx] = L[outside]
    found = np.isfinite(hi)
    if not found.any():
        return out
    lo = np.zeros(found.sum())
    h = hi[found]
    q, d = p[found], g[found]
    for _ in range(30):
        mid = (lo + h) / 2
        outside = hulls.union(q + d * mid[:, None]) >= 0
        h = np.where(outside, mid, h)
        lo = np.where(outside, lo, mid)
    out[found] = h
    return out


def crease_distance(p, a, b, hulls):
    """For each point: its distance to a point where hulls a and b's surfaces meet outside
    every other hull (so a point of the union's surface), found by Gauss-Newton on the two
    distances with the least step from p (inf where none is found)."""
    ok = (a >= 0) & (b >= 0)
    a, b = np.where(ok, a, 0), np.where(ok, b, 0)
    q = p.copy()
    for _ in range(12):
        fa, fb = hulls.distance(q, a), hulls.distance(q, b)
        ga, gb = hulls.hull_gradient(q, a), hulls.hull_gradient(q, b)
        aa, ab, bb = (ga * ga).sum(1), (ga * gb).sum(1), (gb * gb).sum(1)
        det = aa * bb - ab * ab
        ok &= det > 1e-6
        det = np.where(ok, det, 1.0)
        lam = (-fa * bb + fb * ab) / det
        mu = (-fb * aa + fa * ab) / det
        q += np.where(ok[:, None], lam[:, None] * ga + mu[:, None] * gb, 0.0)
    on = ok & (np.abs(hulls.distance(q, a)) < 1e-9) & (np.abs(hulls.distance(q, b)) < 1e-9)
    on &= hulls.union(q) > -1e-9
    return np.where(on, np.linalg.norm(q - p, axis=1), np.inf)


def distance_bound(p, hulls, tol):
    """An upper bound of each point's distance to the surface (inf when none within 2 tol)."""
    d1, i1, d2, i2 = hulls.two_least(p, ids=True)
    out = np.where(d1 >= 0, d1, np.inf)
    exact = (d1 < 0) & (d2 > -d1)
    out[exact] = -d1[exact]
    walk = np.nonzero((d1 < 0) & ~exact & (d1 > -2 * tol))[0]
    if len(walk):
        # Straight out of either of the two nearest hulls: where the line leaves the union
        # is a surface point, so its distance bounds the distance from above.
        for ids in (i1, i2):
            ok = ids[walk] >= 0
            idx = walk[ok]
            g = hulls.hull_gradient(p[idx], ids[idx])
            out[idx] = np.minimum(out[idx], exit_along(p[idx], g, np.full(len(idx), 2 * tol), hulls))
        q, f = p[walk].copy(), d1[walk].copy()
        walked = np.zeros(len(walk))
        h = 1e-5
        for _ in range(8):
            inside = f < 0
            if not inside.any():
                break
            g = np.stack([hulls.union(q + h * e) - hulls.union(q - h * e)
                          for e in np.eye(3)], 1)
            g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
            s = np.where(inside, -f + 1e-7, 0.0)
            q += g * s[:, None]
            walked += s
            f = hulls.union(q)
        walked[f < 0] = np.inf
        out[walk] = np.minimum(out[walk], walked)
        # Steps out of the deepest hull, each by its depth: zig-zags into a crease.
        q, f, n = p[walk].copy(), d1[walk].copy(), i1[walk].copy()
        walked = np.zeros(len(walk))
        for _ in range(16):
            inside = (f < 0) & (walked <= 2 * tol)
            if not inside.any():
                break
            g = hulls.hull_gradient(q[inside], n[inside])
            s = -f[inside] + 1e-7
            q[inside] += g * s[:, None]
            walked[inside] += s
            fi, ni, _, _ = hulls.two_least(q[inside], ids=True)
            f[inside], n[inside] = fi, ni
        walked[f < 0] = np.inf
        out[walk] = np.minimum(out[walk], walked)
        # Where the two nearest hulls' surfaces meet (a crease between two veins).
        left = walk[out[walk] > tol]
        if len(left):
            out[left] = np.minimum(out[left], crease_distance(p[left], i1[left], i2[left], hulls))
        # What is left: straight lines in many directions (64, then 2048 for the few still
        # over: the way out of a thin crease between three hulls is narrow).
        for count in (64, 2048):
            left = walk[out[walk] > tol]
            if not len(left):
                break
            k = np.arange(count) + 0.5
            z = 1 - 2 * k / count
            phi = np.pi * (1 + 5 ** 0.5) * k
            dirs = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], 1)
            for part in np.array_split(left, max(1, len(left) * count // 200000)):
                P = np.repeat(p[part], len(dirs), 0)
                G = np.tile(dirs, (len(part), 1))
                e = exit_along(P, G, np.full(len(P), 2 * tol), hulls).reshape(len(part), len(dirs))
                out[part] = np.minimum(out[part], e.min(1))
    return out


def surface_samples(cones, hulls, n, rng):
    """Points on each hull's surface, by area, kept where no other hull holds them."""
    areas, parts = [], []
    for a, b, ra, rb in cones:
        L = np.linalg.norm(b - a)
        if L <= abs(ra - rb):
            # One ball holds the other.
            big = (a, ra) if ra >= rb else (b, rb)
            parts.append(("ball", big))
            areas.append(4 * np.pi * big[1] ** 2)
            continue
        u = (b - a) / L
        sin = (ra - rb) / L
        cos = np.sqrt(1 - sin * sin)
        # Tangent circles: on each ball at r sin along the axis (towards b), radius r cos;
        # each ball's cap lies beyond its circle.
        ca, cb = a + u * ra * sin, b + u * rb * sin
        slant = np.hypot(np.linalg.norm(cb - ca), ra * cos - rb * cos)
        lateral = np.pi * (ra * cos + rb * cos) * slant
        cap_a = 2 * np.pi * ra * ra * (1 + sin)
        cap_b = 2 * np.pi * rb * rb * (1 - sin)
        parts.append(("cone", (a, b, ra, rb, u, sin, cos, ca, cb)))
        areas.append(lateral + cap_a + cap_b)
    areas = np.array(areas)
    counts = rng.multinomial(n, areas / areas.sum())
    pts = []
    for (kind, data), m in zip(parts, counts):
        if m == 0:
            continue
        v = rng.normal(size=(m * 3, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        if kind == "ball":
            c, r = data
            pts.append(c + v[:m] * r)
            continue
        a, b, ra, rb, u, sin, cos, ca, cb = data
        # Rejection on the caps, area-weighted on the lateral surface.
        w = np.array([np.pi * (ra + rb) * cos * np.hypot(np.linalg.norm(cb - ca), (ra - rb) * cos),
                      2 * np.pi * ra * ra * (1 + sin), 2 * np.pi * rb * rb * (1 - sin)])
        which = rng.choice(3, size=m, p=w / w.sum())
        e1 = np.cross(u, [1, 0, 0] if abs(u[0]) < 0.9 else [0, 1, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(u, e1)
        for k, (c, r, side) in enumerate([(None, None, 0), (a, ra, -1), (b, rb, 1)]):
            mk = int((which == k).sum())
            if mk == 0:
                continue
            if k == 0:
                # Radius varies linearly along the slant: sample t with density ~ radius.
                r0, r1 = ra * cos, rb * cos
                x = rng.random(mk)
                t = x if abs(r1 - r0) < 1e-12 else (
                    (np.sqrt(r0 * r0 + (r1 * r1 - r0 * r0) * x) - r0) / (r1 - r0))
                phi = rng.random(mk) * 2 * np.pi
                rad = r0 + (r1 - r0) * t
                centre = ca[None, :] + (cb - ca)[None, :] * t[:, None]
                pts.append(centre + rad[:, None] * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2))
            else:
                got = []
                while sum(len(g) for g in got) < mk:
                    d = rng.normal(size=(mk * 2, 3))
                    d /= np.linalg.norm(d, axis=1, keepdims=True)
                    keep = (d @ u) >= sin if side > 0 else (d @ u) <= sin
                    got.append(c + d[keep] * r)
                pts.append(np.concatenate(got)[:mk])
    p = np.concatenate(pts)
    return p[hulls.union(p) >= -1e-9]


def hull_volume(a, b, ra, rb):
    """Exact volume of the hull of two balls: the frustum of their tangent cone and two caps."""
    L = np.linalg.norm(b - a)
    if L <= abs(ra - rb):
        return 4 / 3 * np.pi * max(ra, rb) ** 3
    s = (ra - rb) / L
    # The tangent circles lie r s along the axis from each centre (towards b), of radius
    # r sqrt(1 - s^2); each ball's cap beyond its circle.
    h = L * (1 - s * s)
    frustum = np.pi * h * (ra * ra + ra * rb + rb * rb) * (1 - s * s) / 3
    cap = lambda r, t: np.pi * t * t * (3 * r - t) / 3
    return frustum + cap(ra, ra * (1 + s)) + cap(rb, rb * (1 - s))


def union_volume(cones, hulls, n, rng, runs=4):
    """The union's volume by sampling each hull on its own (whose volume is exact): points
    drawn in a box about its axis, one uniformly in each cell of a k x k x k grid of it, and
    kept inside it, count 1/m for it where m hulls hold them (so a region m hulls share is
    counted once in all, and a hull mostly inside others weighs about 1/2, not 0 or 1). `runs`
    independent estimates of about n points each: returns (their mean, its standard error)."""
    vols = np.array([hull_volume(*c) for c in cones])
    A, B, RA, RB = hulls.A, hulls.B, hulls.RA, hulls.RB
    L = np.linalg.norm(B - A, axis=1)
    u = (B - A) / np.where(L > 0, L, 1)[:, None]
    u[L == 0] = [1.0, 0.0, 0.0]
    e1 = np.cross(u, np.where(np.abs(u[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]))
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(u, e1)
    R = np.maximum(RA, RB)
    lo, hi = np.minimum(-RA, L - RB), np.maximum(L + RB, RA)
    box = (hi - lo) * 4 * R * R
    # Each hull's neighbours (bounding spheres that meet), as CSR.
    tree = cKDTree(hulls.centre)
    near = tree.query_ball_point(hulls.centre, hulls.bound + hulls.bound.max())
    lower = [[j for j in near[i] if j != i and np.linalg.norm(hulls.centre[i] - hulls.centre[j])
              <= hulls.bound[i] + hulls.bound[j]] for i in range(len(cones))]
    start = np.concatenate([[0], np.cumsum([len(x) for x in lower])]).astype(np.int64)
    flat = np.array([j for x in lower for j in x], np.int64)
    k = np.maximum(4, np.round(np.cbrt(n * box / box.sum()))).astype(np.int64)
    count = k ** 3
    estimates = []
    for _ in range(runs):
        inside = np.zeros(len(cones))
        owned = np.zeros(len(cones))
        first = 0
        while first < len(cones):
            # About 200,000 points a chunk: each meets every neighbour of its hull.
            last = first + max(1, int(np.searchsorted(np.cumsum(count[first:]), 200_000)))
            ids = np.arange(first, min(last, len(cones)))
            first = ids[-1] + 1
            h = np.repeat(ids, count[ids])
            # Each point's cell in its hull's grid.
            c = np.arange(len(h)) - np.repeat(np.cumsum(count[ids]) - count[ids], count[ids])
            kh = k[h]
            x = (np.stack([c % kh, c // kh % kh, c // (kh * kh)], 1) + rng.random((len(h), 3))) \
                / kh[:, None]
            p = (A[h] + u[h] * (lo[h] + x[:, 0] * (hi[h] - lo[h]))[:, None]
                 + e1[h] * (R[h] * (2 * x[:, 1] - 1))[:, None]
                 + e2[h] * (R[h] * (2 * x[:, 2] - 1))[:, None])
            keep = hulls.distance(p, h) <= 0
            p, h = p[keep], h[keep]
            np.add.at(inside, h, 1)
            cnt = start[h + 1] - start[h]
            pt = np.repeat(np.arange(len(h)), cnt)
            offset = np.arange(len(pt)) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            other = flat[start[h][pt] + offset]
            m = 1 + np.bincount(pt[hulls.distance(p[pt], other) <= 0], minlength=len(h))
            np.add.at(owned, h, 1 / m)
        estimates.append(float((vols * owned / np.maximum(inside, 1)).sum()))
    return float(np.mean(estimates)), float(np.std(estimates, ddof=1) / np.sqrt(runs))


def slot_width(p, hulls):
    """For each point: the width of the gap it lies in between facing veins, that is its
    distance outside its nearest hull plus the distance to the nearest hull whose outward
    direction there is more than 120 degrees from the nearest one's (inf where none, and for a
    point inside the solid)."""
    width = np.full(len(p), np.inf)
    if len(p) == 0:
        return width
    d1, i1, _, _ = hulls.two_least(p, ids=True)
    has = i1 >= 0
    own = np.zeros((len(p), 3))
    own[has] = hulls.hull_gradient(p[has], i1[has])
    point, hull = hulls.pairs(p)
    keep = has[point]
    point, hull = point[keep], hull[keep]
    d = hulls.distance(p[point], hull)
    facing = (hulls.hull_gradient(p[point], hull) * own[point]).sum(1) < -0.5
    np.minimum.at(width, point[facing], d[facing])
    # A point inside the solid is in no gap (a surface sample is on it, to rounding).
    return np.where(d1 < -1e-6, np.inf, width + np.maximum(d1, 0))


def lattice(n):
    """Barycentric weights (i, j, k) / n, i + j + k = n."""
    return np.array([(i, j, n - i - j) for i in range(n + 1) for j in range(n + 1 - i)],
                    float) / n


def dense_worst(T, hulls, tol, n=8):
    """Each triangle sampled at the points (i, j, k) / n (45 for n = 8: a region of a fifth of
    a triangle holds several), then the worst of them improved by a local search inside the
    triangle (projected steps on the barycentric weights): per triangle, the most its points
    lie outside the union (the distance there) and the deepest they lie inside one hull (a
    lower bound of the distance to the surface). Returns (outside, inside, weights of each,
    and the share of each triangle's points inside the union)."""
    W = lattice(n)
    out = np.full(len(T), -np.inf)
    deep = np.full(len(T), -np.inf)
    wo = np.zeros((len(T), 3))
    wi = np.zeros((len(T), 3))
    held = np.zeros(len(T))
    step = max(1, 400000 // len(W))
    for s in range(0, len(T), step):
        part = T[s:s + step]
        P = np.einsum("mk,fkd->fmd", W, part).reshape(-1, 3)
        d = hulls.union(P).reshape(len(part), len(W))
        out[s:s + step], deep[s:s + step] = d.max(1), (-d).max(1)
        held[s:s + step] = (d < 0).mean(1)
        wo[s:s + step], wi[s:s + step] = W[d.argmax(1)], W[d.argmin(1)]
    # Local search from the worst sample, on triangles within half the tolerance of failing:
    # a move of the weights by h along each of six directions, kept when it is worse, h halved
    # when none is.
    dirs = np.array([[1, -1, 0], [-1, 1, 0], [0, 1, -1], [0, -1, 1], [1, 0, -1], [-1, 0, 1]], float)
    for value, w, sign in ((out, wo, 1.0), (deep, wi, -1.0)):
        idx = np.nonzero(value > 0.5 * tol)[0]
        if not len(idx):
            continue
        tri, cur, best = T[idx], w[idx].copy(), value[idx].copy()
        h = np.full(len(idx), 0.5 / n)
        for _ in range(24):
            cand = cur[:, None, :] + h[:, None, None] * dirs[None, :, :]
            ok = (cand >= 0).all(2)
            cand = np.clip(cand, 0, None)
            cand /= cand.sum(2, keepdims=True)
            P = np.einsum("fmk,fkd->fmd", cand, tri).reshape(-1, 3)
            v = sign * hulls.union(P).reshape(len(idx), len(dirs))
            v = np.where(ok, v, -np.inf)
            k = v.argmax(1)
            better = v[np.arange(len(idx)), k] > best
            cur[better] = cand[np.arange(len(idx)), k][better]
            best = np.maximum(best, v[np.arange(len(idx)), k])
            h = np.where(better, h, h / 2)
        value[idx], w[idx] = best, cur
    return out, deep, wo, wi, held


def point_triangle(p, a, b, c):
    """Distance from each p[i] to triangle (a[i], b[i], c[i]), exact (the closest point by the
    Voronoi regions of the corners, edges and face)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = p - b
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = p - c
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        # The face, then each edge and corner where its region holds p (later ones win).
        denom = va + vb + vc
        q = a + ab * (vb / denom)[:, None] + ac * (vc / denom)[:, None]
        bc_t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        for region, point in (
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + ab * (d1 / (d1 - d3))[:, None]),
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + ac * (d2 / (d2 - d6))[:, None]),
            ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), b + (c - b) * bc_t[:, None]),
            ((d1 <= 0) & (d2 <= 0), a),
            ((d3 >= 0) & (d4 <= d3), b),
            ((d6 >= 0) & (d5 <= d6), c),
        ):
            q = np.where(region[:, None], point, q)
    # A degenerate triangle (no face region): its nearest edge or corner.
    bad = ~np.isfinite(q).all(1)
    if bad.any():
        seg = [segment_distance(p[bad], u[bad], v[bad]) for u, v in ((a, b), (b, c), (c, a))]
        out = np.linalg.norm(p - np.where(bad[:, None], p, q), axis=1)
        out[bad] = np.minimum.reduce(seg)
        return out
    return np.linalg.norm(p - q, axis=1)


def segment_distance(p, a, b):
    ab = b - a
    t = np.clip(((p - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0, 1)
    return np.linalg.norm(p - a - ab * t[:, None], axis=1)


def mesh_distance(V, F, p, pieces=100_000, batch=125_000, chunk=2_000_000):
    """Unsigned distance from each p[i] to the triangle mesh (V, F), exact. Each triangle is
    cut in two at the middle of its longest side until no piece reaches farther than `small`
    from its centre (`small` chosen so there are at most about `pieces` of them); the nearest
    few pieces' exact distance bounds a point's from above, so only pieces whose centre is
    within that bound plus `small` can hold a nearer point: those are found in a k-d tree of
    the centres and measured exactly, `batch` points and `chunk` (point, piece) pairs at a
    time. Never fewer pieces than twice the triangles: a mesh of more triangles than `pieces`
    could never be cut within it, and the search for `small` would not end."""
    pieces = max(pieces, 2 * len(F))
    T = V[F]

    def reach_of(t):
        return np.linalg.norm(t - t.mean(1)[:, None], axis=2).max(1)

    def halves(t):
        # Corners turned so that the longest side is 0-1, then cut at its middle.
        side = np.stack([np.linalg.norm(t[:, (k + 1) % 3] - t[:, k], axis=1) for k in range(3)], 1)
        k = side.argmax(1)
        idx = np.stack([k, (k + 1) % 3, (k + 2) % 3], 1)
        t = np.take_along_axis(t, idx[:, :, None], axis=1)
        m = (t[:, 0] + t[:, 1]) / 2
        return np.concatenate([np.stack([t[:, 0], m, t[:, 2]], 1),
                               np.stack([m, t[:, 1], t[:, 2]], 1)])

    def cut(small):
        tri = T
        done = []
        while len(tri):
            big = reach_of(tri) > small
            done.append(tri[~big])
            if sum(len(d) for d in done) + 2 * big.sum() > pieces:
                return None
            tri = halves(tri[big])
        return np.concatenate(done)

    small = max(float(np.median(reach_of(T))) / 2, 1e-9)
    while (tri := cut(small)) is None:
        small *= 1.5
    tree = cKDTree(tri.mean(1))
    _, first = tree.query(p, k=min(4, len(tri)))
    first = first.reshape(len(p), -1)
    best = np.min([point_triangle(p, *tri[first[:, j]].transpose(1, 0, 2))
                   for j in range(first.shape[1])], axis=0)
    for s in range(0, len(p), batch):
        q = p[s:s + batch]
        hits = tree.query_ball_point(q, best[s:s + len(q)] + small + 1e-12)
        counts = np.fromiter((len(h) for h in hits), np.int64, len(hits))
        point = np.repeat(np.arange(len(q)), counts)
        piece = np.concatenate([np.asarray(h, np.int64) for h in hits if h] or [np.zeros(0, int)])
        for c in range(0, len(point), chunk):
            pi, ti = point[c:c + chunk], piece[c:c + chunk]
            d = point_triangle(q[pi], tri[ti, 0], tri[ti, 1], tri[ti, 2])
            np.minimum.at(best, s + pi, d)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--report", required=True)
    ap.add_argument("--network", required=True)
    ap.add_argument("--tolerance", type=float)
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--min-reduction", type=float, default=0.0)
    ap.add_argument("--cell", type=float, help="the mesher's grid cell (default: the report's)")
    ap.add_argument("--show", type=int, default=0, help="list this many of the worst gap points")
    ap.add_argument("--volume-tolerance", type=float, default=0.001,
                    help="the mesh's volume within this fraction of the exact union's, the "
                         "estimate's three standard errors included")
    ap.add_argument("--volume-samples", type=float, default=1e6,
                    help="points drawn in the hulls' boxes for each of 4 volume estimates")
    ap.add_argument("--balance", type=float, default=0.2,
                    help="the share of the mesh's points inside the solid within 0.5 +- this")
    ap.add_argument("--excuse-gaps", action="store_true",
                    help="points over T in gaps narrower than the cell's diagonal do not fail")
    a = ap.parse_args()
    report = json.load(open(a.report))
    net = json.load(open(a.network))
    if report.get("lamina_mm") or report.get("base"):
        print(f"{a.mesh}: lamina or base given; this check rebuilds veins only")
        return 1
    simplified = report.get("simplified") or {}
    tol = a.tolerance if a.tolerance is not None else simplified.get("tolerance_mm")
    if tol is None:
        print(f"{a.mesh}: no tolerance given and the report has none")
        return 1
    failures = []
    mesh = trimesh.load(a.mesh, force="mesh", process=True)
    m = manifold3d.Manifold(manifold3d.Mesh(
        vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
        tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))
    if m.status() != manifold3d.Error.NoError:
        failures.append(f"manifold3d: {m.status()}")
    cell = a.cell if a.cell is not None else report.get("march_cell_mm", report["cell_mm"])
    # A gap between facing veins narrower than the longest edge of the mesher's tetrahedra
    # (the cell's diagonal) can fall between its grid points: marching bridges it.
    narrow = 3 ** 0.5 * cell
    cones = cones_of(net, report)
    hulls = Hulls(cones, max(4 * tol, 2 * narrow))
    rng = np.random.default_rng(7)

    V, F = np.asarray(mesh.vertices), np.asarray(mesh.faces)
    T = V[F]
    w = rng.dirichlet([1, 1, 1], size=(len(F), 3))
    pts = np.concatenate([
        V,
        (T[:, 0] + T[:, 1]) / 2, (T[:, 1] + T[:, 2]) / 2, (T[:, 2] + T[:, 0]) / 2,
        T.mean(1),
        np.einsum("fkj,fjd->fkd", w, T).reshape(-1, 3),
    ])
    out = np.concatenate([distance_bound(c, hulls, tol)
                          for c in np.array_split(pts, max(1, len(pts) // 200000))])
    surf = surface_samples(cones, hulls, a.samples, rng)
    dist = mesh_distance(V, F, surf)

    # Beyond the tolerance in a gap narrower than that: reported apart.
    slots, worst = [], {}
    for name, d, q in (("mesh to surface", out, pts), ("surface to mesh", dist, surf)):
        over = np.nonzero(d > tol)[0]
        in_slot = np.zeros(len(d), bool)
        in_slot[over] = slot_width(q[over], hulls) < narrow
        if in_slot.any():
            slots.append(f"{name}: {int(in_slot.sum())} points, up to "
                         f"{float(d[in_slot].max()) * 1000:.2f} um")
            if a.show:
                for k in np.nonzero(in_slot)[0][np.argsort(-d[in_slot])][:a.show]:
                    print(f"  {name} {d[k] * 1000:.2f} um at ({q[k][0]:.5f}, {q[k][1]:.5f}, "
                          f"{q[k][2]:.5f})")
        rest = np.where(in_slot, 0.0, d) if a.excuse_gaps else d
        worst[name] = float(rest.max())
        if worst[name] > tol:
            k = int(np.argmax(rest))
            failures.append(f"{name} {rest[k] * 1000:.2f} um > {tol * 1000:.2f} um at "
                            f"({q[k][0]:.4f}, {q[k][1]:.4f}, {q[k][2]:.4f}); "
                            f"{int((rest > tol).sum())} points over")
    # Every triangle's interior, densely: outside the union its distance is exact; inside one
    # hull deeper than T a point is surely farther than T from the surface.
    dout, ddeep, wo, wi, held = dense_worst(T, hulls, tol)
    for name, v, w in (("outside", dout, wo), ("inside", ddeep, wi)):
        k = int(np.argmax(v))
        worst[f"dense {name}"] = float(v[k])
        if v[k] > tol:
            q = w[k] @ T[k]
            failures.append(
                f"triangle {k} (of {len(F)}) has a point {v[k] * 1000:.2f} um {name} the "
                f"surface > {tol * 1000:.2f} um at ({q[0]:.4f}, {q[1]:.4f}, {q[2]:.4f}); "
                f"{int((v > tol).sum())} triangles over")
    e = np.stack([np.linalg.norm(T[:, (k + 1) % 3] - T[:, k], axis=1) for k in range(3)], 1)
    area2 = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    height = area2 / e.max(1)
    shorts, lows = int((e < tol / 100).sum()) // 2, int((height < tol / 100).sum())
    parts = len(m.decompose())
    shape = (f"{shorts} edges shorter than T/100, {lows} triangles lower than that, lowest "
             f"vertex {V[:, 2].min() * 1000:.4f} um, manifold3d (float32) {parts} part(s) "
             f"of {m.num_tri()} of {len(F)} triangles, genus {m.genus()}")
    # What an STL's 32-bit corners and a slicer's plate make of it: no edge shorter than T/100
    # nor triangle lower (they round to nothing), nothing below the plate, and manifold3d with
    # float32 corners keeping every triangle in the report's parts and genus.
    if shorts or lows:
        failures.append(f"{shorts} edges shorter than T/100 and {lows} triangles lower than that")
    if V[:, 2].min() < 0:
        failures.append(f"a vertex {-V[:, 2].min() * 1000:.4f} um below the plate (z = 0)")
    if (parts, m.num_tri(), m.genus()) != (report["parts"], len(F), report["genus"]):
        failures.append(f"manifold3d with float32 corners: {parts} part(s), {m.num_tri()} of "
                        f"{len(F)} triangles, genus {m.genus()}; the report says "
                        f"{report['parts']} part(s), genus {report['genus']}")
    # Volume against the exact union's (sampled hull by hull), and the mesh on both sides of
    # the surface: the area-weighted share of its points inside the solid.
    exact, error = union_volume(cones, hulls, int(a.volume_samples), rng)
    off = (mesh.volume - exact) / exact
    inside = float((held * area2).sum() / area2.sum())
    balance = (f"volume {mesh.volume:.6g} mm3 against the exact union's {exact:.6g} +- "
               f"{error:.2g} mm3 ({off * 100:+.4f} %), {inside * 100:.1f} % of the mesh inside "
               f"the solid")
    if abs(off) + 3 * error / exact > a.volume_tolerance:
        failures.append(f"volume {off * 100:+.4f} % (+- {3 * error / exact * 100:.4f} %) off "
                        f"the exact union's, over {a.volume_tolerance * 100:g} %")
    if abs(inside - 0.5) > a.balance:
        failures.append(f"{inside * 100:.1f} % of the mesh lies inside the solid, outside "
                        f"{(0.5 - a.balance) * 100:g}-{(0.5 + a.balance) * 100:g} %")
    mesh_to_surface, surface_to_mesh = worst["mesh to surface"], worst["surface to mesh"]
    marched = simplified.get("marched", 0)
    reduction = marched / max(len(F), 1)
    if a.min_reduction and reduction < a.min_reduction:
        failures.append(f"{marched} marched triangles to {len(F)}: {reduction:.1f}x, "
                        f"below {a.min_reduction}x")
    print(f"check_hausdorff: {a.mesh}: {len(F)} triangles ({reduction:.1f}x fewer than marched); "
          f"mesh to surface {mesh_to_surface * 1000:.2f} um at {len(pts)} points, surface to mesh "
          f"{surface_to_mesh * 1000:.2f} um at {len(surf)} points; tolerance {tol * 1000:.2f} um; "
          f"each triangle at 45 points and searched from its worst: "
          f"{worst['dense outside'] * 1000:.2f} um outside at most, "
          f"{worst['dense inside'] * 1000:.2f} um deep in one vein at most; {shape}; {balance}")
    if slots:
        print(f"check_hausdorff: beyond the tolerance in gaps between facing veins narrower "
              f"than {narrow * 1000:.1f} um (the cell's diagonal; marching bridges them"
              f"{', excused' if a.excuse_gaps else ''}): " + "; ".join(slots))
    for f in failures:
        print(f"check_hausdorff: FAILED: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
