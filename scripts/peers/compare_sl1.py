"""Pixel agreement of two SL1 archives layer by layer: IoU of the masks thresholded at half
grey, and the difference of their areas (sum of grey / 255). Prints the worst and mean figures.

    compare_sl1.py OURS.sl1 THEIRS.sl1
"""
import io
import json
import re
import sys
import zipfile

import numpy as np
from PIL import Image


def layers(path):
    z = zipfile.ZipFile(path)
    found = {}
    for n in z.namelist():
        m = re.match(r".*?(\d{5})\.png$", n)
        if m and "/" not in n:
            found[int(m.group(1))] = n
    return z, [found[i] for i in sorted(found)]


za, la = layers(sys.argv[1])
zb, lb = layers(sys.argv[2])
n = min(len(la), len(lb))
ious, diffs, big = [], [], []
for i in range(n):
    a = np.asarray(Image.open(io.BytesIO(za.read(la[i]))), dtype=np.float64)
    b = np.asarray(Image.open(io.BytesIO(zb.read(lb[i]))), dtype=np.float64)
    ma, mb = a >= 128, b >= 128
    union = (ma | mb).sum()
    iou = (ma & mb).sum() / union if union else 1.0
    area_a, area_b = a.sum() / 255.0, b.sum() / 255.0
    d = abs(area_a - area_b) / max(area_b, 1e-9)
    ious.append(iou)
    diffs.append(d)
    big.append(area_b)
ious, diffs, big = np.array(ious), np.array(diffs), np.array(big)
# Layers of at least 1000 pixels: tiny sections make relative figures meaningless.
sel = big >= 1000
print(json.dumps({
    "layers": [len(la), len(lb)],
    "compared": int(sel.sum()),
    "iou_min": float(ious[sel].min()), "iou_mean": float(ious[sel].mean()),
    "layers_iou_below_0.99": int((ious[sel] < 0.99).sum()),
    "area_diff_max": float(diffs[sel].max()), "area_diff_mean": float(diffs[sel].mean()),
    "layers_area_off_over_0.1pct": int((diffs[sel] > 0.001).sum()),
}))
