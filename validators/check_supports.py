"""Where supports touch the part, from the archives alone (shares no code with lamina; numpy and
scipy):

    check_supports.py BARE.sl1 BARE.json HELD.sl1 HELD.json [--strict]

BARE is the part printed without supports, HELD with them (`print --supports`); the JSONs are
their `--report`s, read only for where each copy was placed on the display (to line the two up
to the pixel) and the support report's counts. Checks:
- the two prints are placed a whole number of pixels apart, with the same number of layers;
- every pixel the part lights (grey >= 128) has the same grey in HELD: supports are added to the
  layers, not blended into the part;
- HELD has no island (a lit region with nothing lit under it in the layer below);
- contacts: a support pixel (lit in HELD, not lit in BARE) touching a lit part pixel in its
  layer (8 neighbours) or right above or below it; contact pixels joined in 3D (26 neighbours)
  are one contact: holding the part (part right above it), landing on it (part right below),
  or beside it only. Printed: the number of contacts of each kind, their total and largest
  area, against the tips and landings the report counts. With --strict: no more holding
  contacts than tips (those farther than a tip's reach from every island of the bare print
  are listed: a tip may hold a sliver seen only on a grid half a pixel over); no more landings than the report's; none beside the part; none
  larger than the tip's footprint (a disc of the tip's diameter plus a pixel around) on each of
  three layers. A holding contact is at an island when the part right above it is the first
  layer of one of the bare print's islands, or within a tip's reach of one's anchor.
"""
import argparse
import io
import json
import math
import sys
import zipfile

import numpy as np
from scipy import ndimage

from islands import dilated, island_mask, island_sizes


def layers(path):
    z = zipfile.ZipFile(path)
    names = sorted(n for n in z.namelist() if n.endswith(".png") and n[-9:-4].isdigit())
    from PIL import Image

    return [np.array(Image.open(io.BytesIO(z.read(n)))) for n in names]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bare")
    ap.add_argument("bare_report")
    ap.add_argument("held")
    ap.add_argument("held_report")
    ap.add_argument("--strict", action="store_true")
    args = ap.parse_args()
    rb, rh = json.load(open(args.bare_report)), json.load(open(args.held_report))
    px = rb["printer"]["pixel_mm"]
    problems = []
    a, b = layers(args.bare), layers(args.held)
    if len(a) != len(b):
        problems.append(f"{len(a)} layers without supports, {len(b)} with: the part was moved up")
    dx = (rh["placements"][0]["offset"][0] - rb["placements"][0]["offset"][0]) / px
    dy = (rh["placements"][0]["offset"][1] - rb["placements"][0]["offset"][1]) / px
    if abs(dx - round(dx)) > 1e-6 or abs(dy - round(dy)) > 1e-6:
        problems.append(f"placed {dx:.4f}, {dy:.4f} pixels apart: not comparable pixel by pixel")
    dx, dy = int(round(dx)), int(round(dy))
    n = min(len(a), len(b))
    # Held's pixel (r - dy, c + dx) is bare's (r, c); both cropped to what either lights.
    for k in range(n):
        b[k] = np.roll(np.roll(b[k], dy, axis=0), -dx, axis=1)
    rows = np.zeros(a[0].shape[0], dtype=bool)
    cols = np.zeros(a[0].shape[1], dtype=bool)
    for k in range(n):
        any_lit = (a[k] > 0) | (b[k] > 0)
        rows |= any_lit.any(axis=1)
        cols |= any_lit.any(axis=0)
    a_rows = a[0].shape[0]
    r = np.nonzero(rows)[0]
    c = np.nonzero(cols)[0]
    # A margin of two pixels, within the display (a part may touch its edge).
    r0, r1 = max(r.min() - 2, 0), min(r.max() + 3, a[0].shape[0])
    c0, c1 = max(c.min() - 2, 0), min(c.max() + 3, a[0].shape[1])
    part = np.zeros((n, r1 - r0, c1 - c0), dtype=bool)
    held = np.zeros_like(part)
    changed = 0
    for k in range(n):
        ak, bk = a[k][r0:r1, c0:c1], b[k][r0:r1, c0:c1]
        lit = ak >= 128
        changed += int((ak[lit] != bk[lit]).sum())
        part[k] = lit
        held[k] = bk >= 128
    del a, b
    if changed:
        problems.append(f"{changed} lit part pixels differ with supports")
    # Islands of the held print: 8-connected lit regions with nothing lit below.
    islands = sum(len(island_sizes(held[k], held[k - 1])) for k in range(1, n))
    if islands:
        problems.append(f"{islands} island(s) with supports")
    # The bare print's islands, each as its first layer's pixels: a tip may hold one anywhere
    # on it (a wide island is held at several points).
    island_first = np.zeros_like(part)
    for k in range(1, n):
        island_first[k] = island_mask(part[k], part[k - 1])
    support = held & ~part
    # The part grown by a pixel within each layer.
    near_part = dilated(part)
    # Right above or below: the part in the next or previous layer, same pixel.
    vertical = np.zeros_like(part)
    vertical[:-1] |= part[1:]
    vertical[1:] |= part[:-1]
    contact = support & (near_part | vertical)
    lab, contacts = ndimage.label(contact, structure=np.ones((3, 3, 3)))
    sizes = np.bincount(lab.ravel())[1:] if contacts else np.array([0])
    s = rh.get("supports") or {}
    tips, landings = int(s.get("tips", 0)), int(s.get("to_model", 0))
    tip = float(s.get("options", {}).get("tip", 0.4))
    footprint = math.pi * (tip / 2 + px) ** 2 / (px * px)
    print(
        f"check_supports: {args.held}: {contacts} contact(s) for {tips} tip(s) and {landings} "
        f"landing(s); contact area {int(sizes.sum()) * px * px:.4f} mm² in all, the largest "
        f"{int(sizes.max()) * px * px:.4f} mm² (a tip's footprint {footprint * px * px:.4f} mm² a "
        f"layer); {int(support.sum())} support pixels; lit part pixels unchanged: {changed == 0}"
    )
    # Each contact by kind: under the part (holding it), on it (a landing), or beside it only.
    above = np.zeros_like(part)
    above[:-1] = part[1:]
    below = np.zeros_like(part)
    below[1:] = part[:-1]
    islands_mm = [(i["layer"], i["anchor_mm"]) for i in rb.get("islands", [])]
    nrows = part.shape[1]
    kinds = {"holds": 0, "lands": 0, "beside": 0}
    astray = []
    for ci, sl in enumerate(ndimage.find_objects(lab) if contacts else []):
        mine = lab[sl] == ci + 1
        if (above[sl] & mine).any():
            kinds["holds"] += 1
            # Where it holds: the pixels right under the part, in the bare print's mm.
            ks, rr, cc = np.nonzero(above[sl] & mine)
            k = ks.max() + sl[0].start + 1
            x = (cc.mean() + sl[2].start + c0 + 0.5) * px
            y = (a_rows - (rr.mean() + sl[1].start + r0) - 0.5) * px
            kk = ks + sl[0].start + 1
            under = island_first[np.minimum(kk, n - 1), rr + sl[1].start, cc + sl[2].start]
            ok = bool(under.any()) or any(
                k - 3 <= layer <= k + 1 and math.dist(anchor, (x, y)) <= tip + 4 * px
                for layer, anchor in islands_mm
            )
            if not ok:
                astray.append(f"layer {k} ({x:.2f}, {y:.2f}) mm")
        elif (below[sl] & mine).any():
            kinds["lands"] += 1
        else:
            kinds["beside"] += 1
    print(f"  contacts holding the part {kinds['holds']} ({len(astray)} away from the bare "
          f"print's islands), landing on it {kinds['lands']}, beside it only {kinds['beside']}")
    if args.strict:
        if kinds["holds"] > tips or kinds["lands"] > landings:
            problems.append(f"{kinds['holds']} holding contacts for {tips} tips, "
                            f"{kinds['lands']} landings for {landings}")
        if kinds["beside"]:
            problems.append(f"{kinds['beside']} contact(s) beside the part, neither holding nor landing")
        # Not failed on: tips also hold slivers that are islands on a grid half a pixel over
        # (which the print's grid does not show), so a holding contact away from the bare
        # print's islands is listed, not refused.
        for where in astray[:5]:
            print(f"  holding contact away from the bare print's islands: {where}")
        big = int((sizes > 3 * footprint).sum())
        if big:
            problems.append(f"{big} contact(s) larger than a tip's footprint on three layers")
    for p in problems:
        print("FAIL", p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
