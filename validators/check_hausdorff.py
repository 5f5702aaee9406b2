"""Independent check of a simplified `lamina solid` (shares no code with lamina): the mesh and
the exact surface of the veins within the tolerance of each other, both ways.

    check_hausdorff.py SOLID.stl --report solid.json --network NET.json
                       [--tolerance T] [--samples 200000] [--min-reduction 0]

The exact solid is rebuilt from the network alone: each edge the hull of a ball at each end
(lamina's documented end-radius rule, from check_solid), scaled by the report's scale, stood up
when upright (+y becomes +z), centred on the z axis from the balls' exact box, lowest point at
z = 0 (as `solid` places it). Checks:
- manifold3d reads the mesh as one valid manifold (status NoError);
- mesh to surface: at every vertex, edge midpoint and triangle centre, and random points on the
  triangles, the distance to the exact surface is at most T. Outside the solid the least of the
  hulls' distances is the distance; inside it is where only one hull is that near; elsewhere
  (where hulls overlap) the surface is reached by steps along the distance's gradient, whose
  total length bounds the distance from above;
- surface to mesh: random points on the exact surface (on each hull, outside the others),
  --samples of them spread by area, are within T of the mesh (trimesh's closest point);
- with --min-reduction R, the report's marched triangles are at least R times the mesh's.
T defaults to the report's simplified.tolerance_mm. Veins only. Exit 0 pass, 1 fail.
"""
import argparse
import json
import sys

import manifold3d
import numpy as np
import trimesh

from check_print_sdf import hull_distance
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


def two_least(p, cones):
    """The least and second least hull distances at each point."""
    d1 = np.full(len(p), np.inf)
    d2 = np.full(len(p), np.inf)
    for c in cones:
        d = hull_distance(p, *c)
        d2 = np.where(d < d1, d1, np.minimum(d2, d))
        d1 = np.minimum(d1, d)
    return d1, d2


def union(p, cones):
    return two_least(p, cones)[0]


def distance_bound(p, cones, tol):
    """An upper bound of each point's distance to the surface (inf when none within 2 tol)."""
    d1, d2 = two_least(p, cones)
    out = np.where(d1 >= 0, d1, np.inf)
    exact = (d1 < 0) & (d2 > -d1)
    out[exact] = -d1[exact]
    walk = np.nonzero((d1 < 0) & ~exact & (d1 > -2 * tol))[0]
    if len(walk):
        q, f = p[walk].copy(), d1[walk].copy()
        walked = np.zeros(len(walk))
        h = 1e-5
        for _ in range(8):
            inside = f < 0
            if not inside.any():
                break
            g = np.stack([union(q + h * e, cones) - union(q - h * e, cones)
                          for e in np.eye(3)], 1)
            g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
            s = np.where(inside, -f + 1e-7, 0.0)
            q += g * s[:, None]
            walked += s
            f = union(q, cones)
        walked[f < 0] = np.inf
        out[walk] = walked
    return out


def surface_samples(cones, n, rng):
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
        # Tangent circles: on each ball at -r sin along the axis, radius r cos.
        ca, cb = a - u * ra * sin, b - u * rb * sin
        slant = np.hypot(np.linalg.norm(cb - ca), ra * cos - rb * cos)
        lateral = np.pi * (ra * cos + rb * cos) * slant
        cap_a = 2 * np.pi * ra * ra * (1 - sin)
        cap_b = 2 * np.pi * rb * rb * (1 + sin)
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
        w = np.array([np.pi * (ra + rb) * cos * np.linalg.norm(cb - ca),
                      2 * np.pi * ra * ra * (1 - sin), 2 * np.pi * rb * rb * (1 + sin)])
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
                    keep = (d @ u) >= -sin if side > 0 else (d @ u) <= -sin
                    got.append(c + d[keep] * r)
                pts.append(np.concatenate(got)[:mk])
    p = np.concatenate(pts)
    return p[union(p, cones) >= -1e-9]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--report", required=True)
    ap.add_argument("--network", required=True)
    ap.add_argument("--tolerance", type=float)
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--min-reduction", type=float, default=0.0)
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
    cones = cones_of(net, report)
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
    out = np.concatenate([distance_bound(c, cones, tol) for c in np.array_split(pts, max(1, len(pts) // 50000))])
    mesh_to_surface = float(out.max())
    if mesh_to_surface > tol:
        worst = pts[int(np.argmax(out))]
        failures.append(f"mesh to surface {mesh_to_surface * 1000:.2f} um > {tol * 1000:.2f} um "
                        f"at ({worst[0]:.4f}, {worst[1]:.4f}, {worst[2]:.4f})")

    surf = surface_samples(cones, a.samples, rng)
    _, dist, _ = trimesh.proximity.closest_point(mesh, surf)
    surface_to_mesh = float(dist.max())
    if surface_to_mesh > tol:
        worst = surf[int(np.argmax(dist))]
        failures.append(f"surface to mesh {surface_to_mesh * 1000:.2f} um > {tol * 1000:.2f} um "
                        f"at ({worst[0]:.4f}, {worst[1]:.4f}, {worst[2]:.4f})")
    marched = simplified.get("marched", 0)
    reduction = marched / max(len(F), 1)
    if a.min_reduction and reduction < a.min_reduction:
        failures.append(f"{marched} marched triangles to {len(F)}: {reduction:.1f}x, "
                        f"below {a.min_reduction}x")
    print(f"check_hausdorff: {a.mesh}: {len(F)} triangles ({reduction:.1f}x fewer than marched); "
          f"mesh to surface {mesh_to_surface * 1000:.2f} um at {len(pts)} points, surface to mesh "
          f"{surface_to_mesh * 1000:.2f} um at {len(surf)} points; tolerance {tol * 1000:.2f} um")
    for f in failures:
        print(f"check_hausdorff: FAILED: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
