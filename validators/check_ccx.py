"""Checks `lamina size` against CalculiX, sharing no code with lamina (numpy + the `ccx` binary).

Runs the deck `lamina size --export-ccx` wrote (B32 beams with RECT sections oriented by the
panel planes, the same supports, the sum of the loads) in CalculiX and compares with sizing.json:
the displacement of every network node (to `--tolerance` of the largest displacement) and the
reaction force at every support where two or more members meet (to `--tolerance` of the
largest reaction; at a single member's end ccx's RF is only the beam node's share of the
expanded section's reaction). ccx can exit 0 after
an *ERROR: its log is searched too.

CalculiX has no true beam for this: it expands every B32 into 20-node bricks, one across the
section, joined at angled joints by rigid knots as large as the section. The brick is exact
enough in tension and bending (0.5 % at 8 elements a member) but not in torsion: one quadratic
brick cannot warp as a rectangle does. `--torsion` measures it here on each distinct section
(a cantilever of 8 B32 twisted through a stiff lever, against Saint-Venant's series solution):
0.84 of the twist for a square (the polar moment), 0.90 for 20 x 3, 0.94 for 100 x 2. Its beam
user element U1 would be a true Timoshenko beam, but in ccx 2.20 its stiffness couples the two
transverse displacements of the weak plane with the wrong sign (s(3,9) = +s(3,3)): a cantilever
10 x 4 x 1000 mm under 100 N across its weak axis deflects 2.5 mm there instead of 1042 mm.

So `--slender-frame` generates two frames with 20 to 30 mm deep panels and members 13 to 32
times their depth, sizes each with lamina, and checks them in ccx:
- a braced triangular tower (rigid joints, members in tension, compression and bending, little
  torsion): held to 1 %;
- a two-storey frame with a cantilevered arm, which carries its load by twisting the top ring:
  held to `--torsion-tolerance` (default 5 %), the difference and the brick's torsion ratios
  printed.

    check_ccx.py model.inp sizing.json [--tolerance 0.01] [--torsion]
    check_ccx.py --slender-frame DIR LAMINA
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np


def fail(msg):
    print(f"check_ccx: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def torsion_constant(d, t):
    """Saint-Venant's torsion constant of a solid d x t rectangle, from the series solution."""
    a, b = max(d, t), min(d, t)
    s = sum(math.tanh(n * math.pi * a / (2 * b)) / n**5 for n in range(1, 200, 2))
    return a * b**3 * (1.0 / 3.0 - 64.0 / math.pi**5 * (b / a) * s)


def run_ccx(text, job, workdir):
    with open(os.path.join(workdir, job + ".inp"), "w") as f:
        f.write(text)
    p = subprocess.run(["ccx", "-i", job], cwd=workdir, capture_output=True, text=True)
    log = p.stdout + p.stderr
    if p.returncode != 0 or "*ERROR" in log:
        err = [l.strip() for l in log.splitlines() if "ERROR" in l] or log.splitlines()[-5:]
        fail(f"ccx ({job}) exit {p.returncode}: {' / '.join(err)[:400]}")
    return open(os.path.join(workdir, job + ".dat")).read()


def dat_blocks(text):
    """{title: {node: values}} for each block of a .dat file."""
    blocks, title = {}, None
    for line in text.splitlines():
        s = line.strip()
        if not s:
            continue
        if s[0].isalpha():
            title = s.split("(")[0].strip()
            blocks[title] = {}
        elif title:
            v = s.split()
            blocks[title][int(v[0])] = [float(x) for x in v[1:]]
    return blocks


def sections(deck_text):
    """The distinct (depth, thickness) of the deck's RECT sections."""
    found = set()
    lines = deck_text.splitlines()
    for i, line in enumerate(lines):
        if line.upper().startswith("*BEAM SECTION") and re.search(r"SECTION\s*=\s*RECT", line, re.I):
            d, t = (float(x) for x in lines[i + 1].split(",")[:2])
            found.add((d, t))
    return sorted(found)


def twist_ratio(d, t, E, nu, workdir):
    """ccx's twist of an expanded B32 cantilever (1000 mm, 8 elements) over Saint-Venant's."""
    n, length = 8, 1000.0
    tip = 2 * n + 1
    lines = ["*NODE, NSET=NALL"]
    lines += [f"{i + 1}, {length * i / (2 * n)}, 0, 0" for i in range(tip)]
    lines += [f"{tip + 1}, {length}, 50, 0", f"{tip + 2}, {length}, 100, 0"]
    lines.append("*ELEMENT, TYPE=B32, ELSET=BAR")
    lines += [f"{e + 1}, {2 * e + 1}, {2 * e + 2}, {2 * e + 3}" for e in range(n)]
    lines += ["*ELEMENT, TYPE=B32, ELSET=LEVER", f"{n + 1}, {tip}, {tip + 1}, {tip + 2}"]
    lines += ["*MATERIAL, NAME=S", "*ELASTIC", f"{E!r}, {nu!r}",
              "*BEAM SECTION, ELSET=BAR, MATERIAL=S, SECTION=RECT", f"{d!r}, {t!r}", "0, 1, 0",
              "*BEAM SECTION, ELSET=LEVER, MATERIAL=S, SECTION=RECT", "60, 60", "1, 0, 0",
              "*BOUNDARY", "1, 1, 6", "*STEP", "*STATIC", "*CLOAD",
              f"{tip + 2}, 3, 10.0", f"{tip}, 3, -10.0",  # a couple of 1000 N mm about x
              "*NODE PRINT, NSET=NALL", "U", "*END STEP"]
    u = dat_blocks(run_ccx("\n".join(lines) + "\n", "twist", workdir))["displacements"]
    twist = (u[tip + 2][2] - u[tip][2]) / 100.0
    exact = 1000.0 * length / (E / (2 * (1 + nu)) * torsion_constant(d, t))
    return twist / exact


def compare(deck_path, sizing_path, tolerance, torsion, label=""):
    sizing = json.load(open(sizing_path))
    text = open(deck_path).read()
    m = re.search(r"\*ELASTIC\s*\n\s*([^,\s]+)\s*,\s*([^,\s]+)", text, re.I)
    if not m:
        fail(f"{deck_path}: no *ELASTIC card")
    E, nu = float(m.group(1)), float(m.group(2))
    n = len(sizing["nodes"])
    lam_u = np.array([nd["displacement"] for nd in sizing["nodes"]])
    scale_u = np.abs(lam_u).max()
    if not scale_u > 0:
        fail(f"{sizing_path} has no displacement to compare")
    with tempfile.TemporaryDirectory() as work:
        blocks = dat_blocks(run_ccx(text, "deck", work))
        disp = blocks.get("displacements", {})
        if any(i + 1 not in disp for i in range(n)):
            fail(f"ccx printed no displacement for some of the {n} network nodes")
        ccx_u = np.array([disp[i + 1][:3] for i in range(n)])
        du = np.linalg.norm(ccx_u - lam_u, axis=1)
        w = int(du.argmax())
        rel_u = du[w] / scale_u
        print(f"check_ccx: {label}displacements at {n} nodes: largest {scale_u:.4g} mm (ccx "
              f"{np.abs(ccx_u).max():.4g}), worst difference {du[w]:.3g} mm at node {w} "
              f"({100 * rel_u:.2f} % of the largest)")
        forces = blocks.get("forces", {})
        lam_r = {r["node"]: np.array(r["force"]) for r in sizing["reactions"]}
        if set(i - 1 for i in forces) != set(lam_r):
            fail(f"ccx's supports {sorted(i - 1 for i in forces)} are not lamina's {sorted(lam_r)}")
        # ccx reports the whole reaction only where its knot gathers the section (two or more
        # members at the node); at a single member's end its RF is the beam node's own share.
        degree = np.bincount([e[k] for e in sizing["edges"] for k in "ab"], minlength=n)
        knots = [i for i in lam_r if degree[i] >= 2]
        rel_r = 0.0
        if knots:
            scale_r = max(np.linalg.norm(f) for f in lam_r.values())
            dr = {i: np.linalg.norm(np.array(forces[i + 1][:3]) - lam_r[i]) for i in knots}
            wr = max(dr, key=dr.get)
            rel_r = dr[wr] / scale_r
            print(f"check_ccx: {label}reactions at {len(knots)} of {len(lam_r)} supports (those "
                  f"with a knot): largest {scale_r:.4g} N, worst difference {dr[wr]:.3g} N at "
                  f"node {wr} ({100 * rel_r:.2f} % of the largest)")
        if torsion:
            secs = sections(text)
            picks = secs if len(secs) <= 4 else [min(secs, key=lambda s: s[0] / s[1]),
                                                 max(secs, key=lambda s: s[0] / s[1])]
            ratios = [(d, t, twist_ratio(d, t, E, nu, work)) for d, t in picks]
            print(f"check_ccx: {label}ccx's expanded B32 twists " + ", ".join(
                f"{r:.3f}" for _, _, r in ratios) + " of Saint-Venant's twist on the sections "
                + ", ".join(f"{d:g} x {t:g}" for d, t, _ in ratios) + f" ({len(secs)} sections)")
    if max(rel_u, rel_r) > tolerance:
        fail(f"{label}{sizing_path}: {100 * max(rel_u, rel_r):.2f} % from CalculiX, over the "
             f"{100 * tolerance:g} % allowed")
    print(f"check_ccx: {label}{sizing_path}: within {100 * tolerance:g} % of CalculiX")
    return max(rel_u, rel_r)


def write_axes(path, nodes, edges, axis_of, height):
    recs = []
    for p in nodes:
        a = axis_of(np.array(p, dtype=float))
        a = a / np.linalg.norm(a)
        recs.append({"p": list(map(float, p)), "axis": a.tolist(), "height": height,
                     "reference": a.tolist()})
    doc = {"format": "lamina-axes", "version": 1, "summary": {"generator": "check_ccx"},
           "nodes": recs, "edges": [{"a": a, "b": b} for a, b in edges]}
    json.dump(doc, open(path, "w"))


def size(lamina, out, name, loads, gauges):
    axes = os.path.join(out, f"{name}-axes.json")
    sizing, deck = os.path.join(out, f"{name}-sizing.json"), os.path.join(out, f"{name}.inp")
    cmd = [lamina, "size", axes, "-o", sizing, "--support", "z<1", "--gauges", gauges,
           "--material", "s355", "--export-ccx", deck]
    for load in loads:
        cmd += ["--load", load]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"lamina size ({name}): exit {p.returncode}: {(p.stdout + p.stderr).strip()[:400]}")
    return deck, sizing


def tower(out, lamina):
    """A braced triangular tower: three legs, four levels 450 mm apart, each face braced by
    diagonals; node axes horizontal and radial; 20 mm panels (members 22 to 32 x their depth)."""
    r = 260.0
    corners = [(r * math.cos(2 * math.pi * i / 3), r * math.sin(2 * math.pi * i / 3)) for i in range(3)]
    nodes = [(x, y, 450.0 * level) for level in range(4) for x, y in corners]
    edges = []
    for level in range(1, 4):
        b = 3 * level
        edges += [(b + i, b + (i + 1) % 3) for i in range(3)]  # ring
        edges += [(b - 3 + i, b + i) for i in range(3)]  # legs
        edges += [(b - 3 + i, b + (i + 1) % 3) for i in range(3)]  # diagonals
    write_axes(os.path.join(out, "tower-axes.json"), nodes, edges,
               lambda p: np.array([p[0], p[1], 0.0]), 20.0)
    loads = ["self-weight", "point:node=9:300,100,-400", "point:node=10:0,250,-400",
             "point:node=11:-150,0,-400"]
    return size(lamina, out, "tower", loads, "3,4,5,6,8,10")


def arm_frame(out, lamina):
    """Two storeys on four columns, braces on two faces, an arm cantilevered off the top ring;
    30 mm panels (members 13 to 21 x their depth); node axes radial, tilted up."""
    corners = [(0, 0), (600, 0), (600, 400), (0, 400)]
    nodes = [(x, y, z) for z in (0.0, 450.0, 900.0) for x, y in corners]
    edges = []
    for level in (1, 2):
        b = 4 * level
        edges += [(b + i, b + (i + 1) % 4) for i in range(4)]
        edges += [(b - 4 + i, b + i) for i in range(4)]
    edges += [(0, 5), (6, 11)]
    nodes.append((1100.0, 0.0, 950.0))
    edges.append((9, len(nodes) - 1))
    write_axes(os.path.join(out, "arm-axes.json"), nodes, edges,
               lambda p: np.array([p[0] - 300.0, p[1] - 200.0, 0.0]) / np.hypot(p[0] - 300.0, p[1] - 200.0)
               + np.array([0.0, 0.0, 0.3]), 30.0)
    loads = ["self-weight", f"point:node={len(nodes) - 1}:15,-10,-40", "point:node=10:0,80,-50",
             "point:node=8:-60,0,0"]
    return size(lamina, out, "arm", loads, "4,5,6,8,10")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("deck", nargs="?")
    ap.add_argument("sizing", nargs="?")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--torsion-tolerance", type=float, default=0.05)
    ap.add_argument("--torsion", action="store_true", help="measure ccx's torsion of the sections")
    ap.add_argument("--slender-frame", nargs=2, metavar=("DIR", "LAMINA"))
    args = ap.parse_args()
    if shutil.which("ccx") is None:
        fail("ccx is not installed (scripts/setup installs calculix-ccx)")
    if args.slender_frame:
        out, lamina = args.slender_frame
        os.makedirs(out, exist_ok=True)
        compare(*tower(out, lamina), args.tolerance, False, "braced tower: ")
        compare(*arm_frame(out, lamina), args.torsion_tolerance, True, "frame with an arm: ")
    elif args.deck and args.sizing:
        compare(args.deck, args.sizing, args.tolerance, args.torsion)
    else:
        ap.error("give model.inp and sizing.json, or --slender-frame DIR LAMINA")


if __name__ == "__main__":
    main()
