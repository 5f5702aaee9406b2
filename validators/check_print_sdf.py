"""Independent check of `lamina print` (slicing straight from the network; shares no code with
lamina): each layer image against the true section of the veins, found by supersampling.

    check_print_sdf.py JOB.sl1 --report print.json --network NET.json
                       [--every 3 | --layers 857,864] [--supersample 8|16|32] [--iou 0.999]
                       [--area-tol 0.0005] [--mesh MESH.sl1]

The solid is rebuilt here from the network alone: each edge the convex hull of a ball at each
end; at a node with a radius, its two thickest edges (ties by edge order) take the node's radius
at that end, the others keep their own (lamina's documented rule). Scaled by print.json's
solid.scale, stood up when solid.upright (+y becomes +z), centred on the z axis from the balls'
exact box with its lowest point at z = 0, then placed as print.json's placements say. For every
--every'th layer, each pixel's true coverage is the fraction of 89, 377 or 1597 points (a Fibonacci lattice) inside
the section (points within a pixel of the surface only; the rest are wholly in or out). Checks:
- the grey image's IoU with the true coverage, sum(min) / sum(max), at least --iou;
- the image's area (sum grey / 255 x pixel area) within --area-tol of the true area, on layers
  of at least 1 mm2, and in total over the checked layers.
--mesh: another archive on the same pixels (`solid` then `slice`), reported beside JOB on each
checked layer against the same true section (masks at half grey and grey IoU, area), to tell
which of the two a disagreement between them comes from; it is not checked.
Veins only (no --lamina or --base: their outlines are not rebuilt here). Exit 0 pass, 1 fail,
2 a bad --layers, --every or --mesh.
"""
import argparse
import io
import json
import sys
import zipfile

import numpy as np

from PIL import Image

from check_solid import end_radii


def hull_distance(p, a, b, ra, rb):
    """Signed distance from points p (n x 3) to the hull of balls (a, ra), (b, rb): the least
    over t of |p - c(t)| - r(t), found by minimising over the axis in closed form."""
    ab = b - a
    L = np.linalg.norm(ab)
    if L <= abs(ra - rb):
        return np.minimum(np.linalg.norm(p - a, axis=1) - ra, np.linalg.norm(p - b, axis=1) - rb)
    u = ab / L
    pa = p - a
    t = pa @ u
    q = np.sqrt(np.maximum((pa * pa).sum(1) - t * t, 0))
    # f(s) = sqrt((t - s)^2 + q^2) - ra - (rb - ra) s / L over s in [0, L]; stationary where
    # (s - t) / dist = (rb - ra) / L = -k, i.e. s = t - q k / sqrt(1 - k^2).
    k = (ra - rb) / L
    s = np.clip(t - q * k / np.sqrt(1 - k * k), 0, L)
    return np.sqrt((t - s) ** 2 + q * q) - (ra + (rb - ra) * s / L)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("job")
    ap.add_argument("--report", required=True)
    ap.add_argument("--network", required=True)
    ap.add_argument("--every", type=int, default=3)
    ap.add_argument("--layers", help="comma-separated layer numbers, instead of --every")
    ap.add_argument("--mesh", help="an archive to report beside JOB against the same sections")
    ap.add_argument("--supersample", type=int, default=16)
    ap.add_argument("--iou", type=float, default=0.999)
    ap.add_argument("--area-tol", type=float, default=0.0005)
    a = ap.parse_args()
    report = json.load(open(a.report))
    net = json.load(open(a.network))
    solid = report["solid"]
    if solid.get("lamina_mm") or solid.get("base"):
        print(f"{a.job}: lamina or base given; this check rebuilds veins only")
        return 1
    printer = report["printer"]
    px, lh = printer["pixel_mm"], printer["layer_mm"]
    W, H = printer["pixels_x"], printer["pixels_y"]
    scale = solid["scale"]
    ends = end_radii(net)
    P = np.array([n["p"] for n in net["nodes"]], float) * scale
    if solid["upright"]:
        P = np.stack([P[:, 0], -P[:, 2], P[:, 1]], 1)
    cones = [(P[e["a"]], P[e["b"]], r[0] * scale, r[1] * scale) for e, r in zip(net["edges"], ends)]
    lo = np.min([np.minimum(c[0] - c[2], c[1] - c[3]) for c in cones], 0)
    hi = np.max([np.maximum(c[0] + c[2], c[1] + c[3]) for c in cones], 0)
    shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    cones = [(c[0] + shift, c[1] + shift, c[2], c[3]) for c in cones]

    zlo = np.array([min(c[0][2] - c[2], c[1][2] - c[3]) for c in cones])
    zhi = np.array([max(c[0][2] + c[2], c[1][2] + c[3]) for c in cones])

    def sdf(p):
        # Only the cones that reach the plane (all points share one height).
        z0 = p[0, 2] if len(p) else 0.0
        d = np.full(len(p), np.inf)
        for k in np.nonzero((zlo <= z0) & (zhi >= z0))[0]:
            d = np.minimum(d, hull_distance(p, *cones[k]))
        return d

    z = zipfile.ZipFile(a.job)
    names = sorted(n for n in z.namelist() if n.endswith(".png") and not n.startswith("thumbnail"))
    if len(names) != report["layers"]:
        print(f"{a.job}: {len(names)} layer images, print.json says {report['layers']}")
        return 1
    # A Fibonacci lattice of N points in the pixel: every point has its own x and its own y, so
    # an edge along a pixel row or column is resolved to 1/N (a square grid would give 1/n).
    N, step = {8: (89, 55), 16: (377, 233), 32: (1597, 987)}.get(a.supersample, (377, 233))
    k = np.arange(N)
    sub_x = (k + 0.5) / N - 0.5
    sub_y = ((k * step) % N + 0.5) / N - 0.5
    failures, worst, tot_img, tot_true = [], (2.0, -1), 0.0, 0.0
    checked = 0
    if a.layers:
        try:
            chosen = [int(x) for x in a.layers.split(",")]
        except ValueError:
            print(f"--layers {a.layers}: not a list of layer numbers")
            return 2
        if any(not 0 <= i < len(names) for i in chosen):
            print(f"--layers {a.layers}: the archive has layers 0..{len(names) - 1}")
            return 2
    elif a.every < 1:
        print(f"--every {a.every}: must be 1 or more")
        return 2
    else:
        chosen = range(0, len(names), a.every)
    if a.mesh:
        try:
            zm = zipfile.ZipFile(a.mesh)
        except (OSError, zipfile.BadZipFile) as e:
            print(f"{a.mesh}: not an SL1 archive ({e})")
            return 2
        mesh_names = sorted(n for n in zm.namelist() if n.endswith(".png") and not n.startswith("thumbnail"))
        if len(mesh_names) != len(names):
            print(f"{a.mesh}: {len(mesh_names)} layer images, {a.job} has {len(names)}")
            return 1
    for i in chosen:
        img = np.asarray(Image.open(io.BytesIO(z.read(names[i]))), dtype=np.float64) / 255.0
        zc = (i + 0.5) * lh
        truth = np.zeros((H, W))
        for pl in report["placements"]:
            off = np.array(pl["offset"])
            x0, y0 = pl["min"]
            x1, y1 = pl["max"]
            c0, c1 = max(int(x0 / px) - 2, 0), min(int(x1 / px) + 3, W)
            r0, r1 = max(int(H - y1 / px) - 2, 0), min(int(H - y0 / px) + 3, H)
            cols, rows = np.meshgrid(np.arange(c0, c1), np.arange(r0, r1))
            X = (cols + 0.5) * px - off[0]
            Y = (H - rows - 0.5) * px - off[1]
            if pl["turned"]:
                X, Y = Y, -X
            pts = np.stack([X.ravel(), Y.ravel(), np.full(X.size, zc - off[2])], 1)
            d = sdf(pts).reshape(X.shape)
            cov = (d < 0).astype(float)
            edge = np.abs(d) < px
            if edge.any():
                ex, ey = X[edge], Y[edge]
                sx = (ex[:, None] + sub_x[None, :] * px).ravel()
                sy = (ey[:, None] + sub_y[None, :] * px).ravel()
                sp = np.stack([sx, sy, np.full(sx.size, zc - off[2])], 1)
                inside = (sdf(sp) < 0).reshape(-1, N).mean(1)
                cov[edge] = inside
            truth[r0:r1, c0:c1] = np.maximum(truth[r0:r1, c0:c1], cov)
        checked += 1
        if a.mesh:
            mesh = np.asarray(Image.open(io.BytesIO(zm.read(mesh_names[i]))), dtype=np.float64) / 255.0
            if mesh.shape != truth.shape:
                print(f"{a.mesh}: layer {i} is {mesh.shape}, the display {truth.shape}")
                return 1

            def against(im):
                mi, mt = im >= 0.5, truth >= 0.5
                union = max(int((mi | mt).sum()), 1)
                grey = np.minimum(im, truth).sum() / max(np.maximum(im, truth).sum(), 1e-12)
                off = 100 * (im.sum() - truth.sum()) / max(truth.sum(), 1e-12)
                return (f"masks {(mi & mt).sum() / union:.5f} ({int((mi ^ mt).sum())} of {union} pixels), "
                        f"grey {grey:.5f}, area {off:+.3f} %")

            print(f"  layer {i} against the true section: {a.job}: {against(img)}; {a.mesh}: {against(mesh)}")
        ai, at = img.sum() * px * px, truth.sum() * px * px
        tot_img += ai
        tot_true += at
        if at == 0 and ai == 0:
            continue
        iou = np.minimum(img, truth).sum() / np.maximum(img, truth).sum()
        worst = min(worst, (iou, i))
        if iou < a.iou:
            failures.append(f"layer {i}: IoU {iou:.5f} with the true section, below {a.iou}")
        if at >= 1.0 and abs(ai - at) > a.area_tol * at:
            failures.append(f"layer {i}: area {ai:.5f} mm2, true {at:.5f} mm2 ({100 * (ai - at) / at:+.4f} %)")
    total = (tot_img - tot_true) / tot_true
    if abs(total) > a.area_tol:
        failures.append(f"checked layers' area {100 * total:+.4f} % from the true sections'")
    if failures:
        for f in failures[:20]:
            print(f"{a.job}: {f}")
        print(f"{a.job}: {len(failures)} failure(s)")
        return 1
    print(f"{a.job}: ok ({checked} of {len(names)} layers against {N}-point supersampled true sections: "
          f"worst IoU {worst[0]:.5f} at layer {worst[1]}, area {100 * total:+.4f} %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
