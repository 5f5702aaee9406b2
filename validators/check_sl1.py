"""An SL1 print archive read without lamina (zipfile, Pillow, numpy, scipy.ndimage), against
what lamina says of it.

Islands: in each layer, the connected regions of lit pixels (grey >= 128, 8-connected, by
scipy.ndimage.label) none of whose pixels is lit in the layer before; the first layer stands on
the plate. Resin: the sum over layers of grey/255 x pixel area x layer height.

    check_sl1.py ARCHIVE REPORT.json [--expect-islands N] [--expect-first-layer K]

REPORT is either print.json from `lamina slice` (its `islands` list and `volume_ml`) or the
JSON of `lamina sl1 check --json` (its `islands`, `layers`, `volume_ml` and `used_ml`); both
must name the same islands (layer and pixel count) and the same resin volume (1e-9 relative).
"""
import argparse
import configparser
import io
import json
import sys
import zipfile

import numpy as np
from PIL import Image

from islands import island_sizes


def fail(msg):
    print(f"check_sl1: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def ini(z, name):
    text = z.read(name).decode("utf-8", "replace")
    p = configparser.ConfigParser(interpolation=None)
    p.read_string("[s]\n" + text)
    return dict(p["s"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("archive")
    ap.add_argument("report")
    ap.add_argument("--expect-islands", type=int)
    ap.add_argument("--expect-first-layer", type=int)
    args = ap.parse_args()
    z = zipfile.ZipFile(args.archive)
    config = ini(z, "config.ini")
    printer = ini(z, "prusaslicer.ini")
    job = config["jobdir"]
    layers = int(config["numfast"]) + int(config["numslow"])
    names = [f"{job}{k:05d}.png" for k in range(layers)]
    missing = [n for n in names if n not in z.namelist()]
    if missing:
        fail(f"{args.archive}: config.ini says {layers} layers; {missing[0]} is missing")
    pixel = float(printer["display_width"]) / int(printer["display_pixels_x"])
    height = float(config["layerheight"])
    islands, grey_sum, below = [], 0.0, None
    for k, n in enumerate(names):
        image = Image.open(io.BytesIO(z.read(n)))
        image = np.asarray(image if image.mode == "L" else image.convert("L"))
        grey_sum += image.sum(dtype=np.float64) / 255.0
        lit = image >= 128
        if below is not None:
            islands.extend((k, size) for size in island_sizes(lit, below))
        below = lit
    volume = grey_sum * pixel * pixel * height / 1000.0
    report = json.load(open(args.report))
    theirs = sorted((i["layer"], i["pixels"]) for i in report["islands"])
    if theirs != sorted(islands):
        fail(f"islands: lamina {theirs[:10]}, here {sorted(islands)[:10]}")
    if report.get("island_count", len(theirs)) != len(islands):
        fail(f"island_count {report.get('island_count')} but {len(islands)} islands")
    if abs(report["volume_ml"] - volume) > 1e-9 * max(volume, 1e-12):
        fail(f"resin: lamina {report['volume_ml']} mL, here {volume} mL")
    if "used_ml" in report and abs(report["used_ml"] - float(config["usedmaterial"])) > 1e-9:
        fail(f"usedMaterial: lamina read {report['used_ml']}, config.ini says "
             f"{config['usedmaterial']}")
    if args.expect_islands is not None and len(islands) != args.expect_islands:
        fail(f"{len(islands)} islands, expected {args.expect_islands}")
    # The first island's layer, when there is one.
    if args.expect_first_layer is not None and islands and islands[0][0] != args.expect_first_layer:
        fail(f"first island at layer {islands[0][0]}, expected {args.expect_first_layer}")
    print(f"check_sl1: {args.archive}: {layers} layers, {len(islands)} islands "
          f"{islands[:5]}{' ...' if len(islands) > 5 else ''}, resin {volume:.6f} mL from pixels "
          f"(config.ini usedMaterial {config['usedmaterial']}): lamina agrees")


if __name__ == "__main__":
    main()
