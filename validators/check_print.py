"""Independent check of a print job made by `lamina slice` (shares no code with lamina).

    check_print.py JOB.sl1 --report print.json --mesh MODEL.stl [--samples 12]
                   [--area-tol 0.001] [--volume-tol 0.01] [--min-area 1.0]

- The archive is laid out as PrusaSlicer writes SL1 files: config.ini and prusaslicer.ini with
  the keys readers use, one NAME%05d.png per layer (numFast of them), each an 8-bit grey image
  of the display's size.
- Sampled layers (and every layer for the volume): the image's area, sum(grey / 255) x pixel
  area, agrees with manifold3d's cross-section of the mesh at the layer's middle height, placed
  as print.json says (quarter turn, offset), within --area-tol (layers of at least --min-area mm2).
- Volume: sum of image areas x layer height agrees with the mesh volume x copies within
  --volume-tol; print.json's volume, cost, mass and build time follow from it.
Exit 0 on pass, 1 on fail.
"""
import argparse
import configparser
import io
import json
import re
import sys
import zipfile

import manifold3d
import numpy as np
import trimesh
from PIL import Image


def ini(text):
    cp = configparser.ConfigParser(interpolation=None)
    cp.read_string("[s]\n" + text)
    return dict(cp["s"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("job")
    ap.add_argument("--report", required=True)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--samples", type=int, default=12)
    ap.add_argument("--area-tol", type=float, default=0.001)
    ap.add_argument("--volume-tol", type=float, default=0.01)
    ap.add_argument("--min-area", type=float, default=1.0)
    a = ap.parse_args()
    report = json.load(open(a.report))
    ok = True

    def fail(msg):
        nonlocal ok
        print(f"FAIL {a.job}: {msg}")
        ok = False

    z = zipfile.ZipFile(a.job)
    names = z.namelist()
    for need in ("config.ini", "prusaslicer.ini"):
        if need not in names:
            fail(f"no {need}")
            return 1
    config = ini(z.read("config.ini").decode())
    printer = ini(z.read("prusaslicer.ini").decode())
    for key in ("expTime", "expTimeFirst", "layerHeight", "numFade", "numFast", "jobDir", "printTime",
                "usedMaterial"):
        if key.lower() not in config:
            fail(f"config.ini has no {key}")
    for key in ("display_pixels_x", "display_pixels_y", "display_width", "display_height",
                "layer_height", "exposure_time", "initial_exposure_time", "printer_technology"):
        if key not in printer:
            fail(f"prusaslicer.ini has no {key}")
    if not ok:
        return 1
    job = config["jobdir"]
    pattern = re.compile(re.escape(job) + r"(\d{5})\.png$")
    layers = sorted(int(m.group(1)) for m in map(pattern.match, names) if m)
    n = int(config["numfast"])
    if layers != list(range(n)):
        fail(f"layer images are not {job}00000.png .. for numFast = {n} layers")
        return 1
    if n != report["layers"]:
        fail(f"{n} layers in the archive, {report['layers']} in print.json")
    w, h = int(printer["display_pixels_x"]), int(printer["display_pixels_y"])
    px = float(printer["display_width"]) / w
    if abs(float(printer["display_height"]) / h - px) > 1e-9:
        fail("pixels are not square")
    layer = float(config["layerheight"])

    mesh = trimesh.load(a.mesh, force="mesh", process=True)
    model = manifold3d.Manifold(manifold3d.Mesh(
        vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
        tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))
    if model.status() != manifold3d.Error.NoError:
        fail(f"{a.mesh} is not a manifold ({model.status()})")
        return 1
    placed = []
    for p in report["placements"]:
        m = model.rotate((0.0, 0.0, 90.0)) if p["turned"] else model
        placed.append(m.translate(tuple(p["offset"])))

    areas = np.zeros(n)
    for i in range(n):
        img = Image.open(io.BytesIO(z.read(f"{job}{i:05d}.png")))
        if img.mode != "L" or img.size != (w, h):
            fail(f"layer {i}: {img.mode} {img.size}, expected 8-bit grey {w}x{h}")
            return 1
        areas[i] = np.asarray(img, dtype=np.float64).sum() / 255.0 * px * px
    worst = 0.0
    checked = 0
    for i in np.unique(np.linspace(0, n - 1, a.samples).round().astype(int)):
        zc = (i + 0.5) * layer
        ref = sum(m.slice(zc).area() for m in placed)
        if ref < a.min_area:
            continue
        rel = abs(areas[i] - ref) / ref
        worst = max(worst, rel)
        checked += 1
        if rel > a.area_tol:
            fail(f"layer {i} (z {zc:.3f}): image area {areas[i]:.5f} mm2, manifold3d {ref:.5f} "
                 f"({rel * 100:.3f} %)")
    volume = areas.sum() * layer
    mesh_volume = sum(m.volume() for m in placed)
    vrel = abs(volume - mesh_volume) / mesh_volume
    print(f"{a.job}: {n} layers of {w}x{h}; {checked} sampled layers within {worst * 100:.4f} % of "
          f"manifold3d; volume {volume:.3f} mm3 vs mesh {mesh_volume:.3f} ({vrel * 100:.3f} %)")
    if checked == 0:
        fail("no sampled layer was large enough to compare")
    if vrel > a.volume_tol:
        fail(f"layer volume {volume} is {vrel * 100:.2f} % from the mesh volume {mesh_volume}")
    ml = volume / 1000.0
    if abs(report["volume_ml"] - ml) > 1e-6 * max(ml, 1e-9):
        fail(f"print.json volume {report['volume_ml']} mL, the images give {ml}")
    cost = report["volume_ml"] / 1000.0 * report["resin_cost_per_litre"]
    if abs(report["resin_cost"] - cost) > 1e-9 * max(cost, 1.0):
        fail(f"print.json cost {report['resin_cost']}, volume x price gives {cost}")
    if abs(report["mass_g"] - report["volume_ml"] * report["density_g_ml"]) > 1e-9:
        fail("print.json mass is not volume x density")
    if abs(report["height_mm"] - n * layer) > 1e-9:
        fail(f"print.json height {report['height_mm']}, {n} layers of {layer} make {n * layer}")
    speed = re.match(r"([0-9.]+) mm/h", report["build_time_from"])
    if speed and abs(report["build_time_h"] - report["height_mm"] / float(speed.group(1))) > 1e-9:
        fail("print.json build time is not height / speed")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
