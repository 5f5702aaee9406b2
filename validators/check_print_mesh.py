"""Independent check that `lamina print` (layers straight from the network's distance) and
`lamina solid` then `lamina slice` (layers cut from the mesh) light the same pixels (shares no
code with lamina; numpy and Pillow).

    check_print_mesh.py PRINT.sl1 MESH.sl1 [--min-pixels 1000] [--iou-mean 0.999]
                        [--iou-min 0.997] [--area-mean 0.0005] [--volume-tol 0.0005]

Both archives must hold the same number of layer images of the same size. On every layer with
at least --min-pixels lit pixels (sum of grey / 255) in the mesh's image:
- IoU of the two masks thresholded at half grey: at least --iou-min on each such layer, and
  at least --iou-mean on average over them;
- the relative difference of their areas (sum of grey): at most --area-mean on average.
Over all layers, the two volumes (sum of grey) agree within --volume-tol.
Prints the worst layers, and the grey IoU (sum of the lesser grey over sum of the greater, which
no threshold makes jump) for information. Exit 0 pass, 1 fail, 2 an input is not a zip.
"""
import argparse
import io
import re
import sys
import zipfile

import numpy as np
from PIL import Image


def layer_images(path):
    """The archive and its layer PNGs at the top level, in layer order (NNNNN.png)."""
    try:
        z = zipfile.ZipFile(path)
    except (OSError, zipfile.BadZipFile) as e:
        print(f"{path}: not an SL1 archive ({e})", file=sys.stderr)
        sys.exit(2)
    found = {}
    for name in z.namelist():
        m = re.fullmatch(r"[^/]*?(\d{5})\.png", name)
        if m:
            found[int(m.group(1))] = name
    order = sorted(found)
    if order != list(range(len(order))):
        sys.exit(f"{path}: layer images are not numbered 0..{len(order) - 1}")
    return z, [found[i] for i in order]


def grey(z, name):
    img = Image.open(io.BytesIO(z.read(name)))
    if img.mode != "L":
        sys.exit(f"{name}: not 8-bit grey ({img.mode})")
    return np.asarray(img, dtype=np.float64)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("print_sl1")
    ap.add_argument("mesh_sl1")
    ap.add_argument("--min-pixels", type=float, default=1000)
    ap.add_argument("--iou-mean", type=float, default=0.999)
    ap.add_argument("--iou-min", type=float, default=0.997)
    ap.add_argument("--area-mean", type=float, default=0.0005)
    ap.add_argument("--volume-tol", type=float, default=0.0005)
    a = ap.parse_args()

    za, la = layer_images(a.print_sl1)
    zb, lb = layer_images(a.mesh_sl1)
    failures = []
    if len(la) != len(lb):
        failures.append(f"{len(la)} layers from the network, {len(lb)} from the mesh")
    rows = []
    vol_a = vol_b = 0.0
    for i in range(min(len(la), len(lb))):
        ga, gb = grey(za, la[i]), grey(zb, lb[i])
        if ga.shape != gb.shape:
            failures.append(f"layer {i}: images {ga.shape} and {gb.shape}")
            continue
        area_a, area_b = ga.sum() / 255.0, gb.sum() / 255.0
        vol_a += area_a
        vol_b += area_b
        if area_b < a.min_pixels:
            continue
        ma, mb = ga >= 128, gb >= 128
        union = (ma | mb).sum()
        iou = (ma & mb).sum() / union if union else 1.0
        soft = np.minimum(ga, gb).sum() / np.maximum(ga, gb).sum()
        rows.append((iou, abs(area_a - area_b) / area_b, i, int((ma ^ mb).sum()), int(union), soft))
    if not rows:
        failures.append(f"no layer has {a.min_pixels:g} lit pixels")
    else:
        ious = np.array([r[0] for r in rows])
        areas = np.array([r[1] for r in rows])
        softs = np.array([r[5] for r in rows])
        for iou, _, i, flipped, union, soft in sorted(rows)[:3]:
            print(f"  layer {i}: IoU {iou:.5f} ({flipped} of {union} pixels differ), grey IoU {soft:.5f}")
        print(f"  grey IoU: min {softs.min():.5f} (layer {rows[int(softs.argmin())][2]}), mean {softs.mean():.5f}")
        for iou, _, i, flipped, union, _ in rows:
            if iou < a.iou_min:
                failures.append(f"layer {i}: IoU {iou:.5f} below {a.iou_min} ({flipped} of {union} pixels differ)")
        if ious.mean() < a.iou_mean:
            failures.append(f"mean IoU {ious.mean():.5f} below {a.iou_mean}")
        if areas.mean() > a.area_mean:
            failures.append(f"areas differ by {areas.mean() * 100:.3f} % on average, over {a.area_mean * 100:g} %")
    vol_diff = abs(vol_a - vol_b) / max(vol_b, 1e-9)
    if vol_diff > a.volume_tol:
        failures.append(f"volumes (sum of grey) differ by {vol_diff * 100:.3f} %, over {a.volume_tol * 100:g} %")
    if failures:
        for f in failures:
            print(f"{a.print_sl1} vs {a.mesh_sl1}: {f}")
        print(f"{a.print_sl1} vs {a.mesh_sl1}: {len(failures)} failure(s)")
        sys.exit(1)
    print(f"{a.print_sl1} vs {a.mesh_sl1}: ok ({len(rows)} layers of {a.min_pixels:g}+ pixels: IoU min "
          f"{ious.min():.5f}, mean {ious.mean():.5f}; areas {areas.mean() * 100:.3f} % apart on average, "
          f"volumes {vol_diff * 100:.3f} %)")


if __name__ == "__main__":
    main()
