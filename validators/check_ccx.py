"""Checks `lamina size` against CalculiX, sharing no code with lamina (numpy + the `ccx` binary).

Runs the deck `lamina size --export-ccx` wrote (each member 32 B32 beams with a RECT section
oriented by its panel plane, the same supports, the sum of the loads) in CalculiX and compares
with sizing.json:
- the displacement of every network node, to `--tolerance` of the largest displacement;
- the reaction force at every support where two or more members meet, to `--tolerance` of the
  largest reaction (at a single member's end ccx's RF is only the beam node's share of the
  expanded section's reaction);
- with `--slender-frame`, the section forces at every member's mid-length: ccx's SECTION FORCES
  (the node between the member's middle two beams, which no other member shares) against
  lamina's end forces at a carried to mid-length with the member's load; the normal force to
  `--tolerance` of the largest normal force, the torque and both moments to `--tolerance` of the
  largest moment. Shear forces are not compared: ccx's are not usable (a cantilever under 10 N
  prints 10 to 60).
ccx can exit 0 after an *ERROR: its log is searched too.

CalculiX has no true beam for this: it expands every B32 into 20-node bricks, one across the
section, joined at angled joints by rigid knots as large as the section. Measured here:
- the expansion converges slowly, about as 1/n in the beams a member (the section is held whole
  at supports and knots, so the bricks next to them cannot contract sideways): a cantilever
  deflects 1.2 % too little at 8 beams, 0.55 % at 16, 0.3 % at 32; the portal frame below is
  3.6 %, 1.7 % and 0.9 % from lamina. Hence 32.
- one quadratic brick cannot warp as a rectangle does, so it is stiff in torsion. `--torsion`
  measures it on the deck's sections (a cantilever of 8 B32 twisted through a stiff lever,
  against Saint-Venant's series solution): 0.84 of the twist for a square (the polar moment),
  0.90 for 20 x 3, 0.94 for 100 x 2.
- its beam user element U1 would be a true Timoshenko beam, but in ccx 2.20 its stiffness
  couples the two transverse displacements of the weak plane with the wrong sign (s(3,9) =
  +s(3,3)): a cantilever 10 x 4 x 1000 mm under 100 N across its weak axis deflects 2.5 mm
  there instead of 1042 mm. Not used.

`--slender-frame DIR LAMINA` generates three frames with 20 to 30 mm deep panels and members 13
to 32 times their depth, sizes each with lamina, and checks them:
- a braced triangular tower (members in tension, compression and bending): `--tolerance`;
- a two-bay, two-storey portal frame bending in its plane (no bracing, no torsion):
  `--tolerance`;
- a two-storey frame with a cantilevered arm, which carries its load by twisting the top ring:
  `--torsion-tolerance` (default 2 %), with the bricks' torsion ratios printed.

Deep plates (Calyx: members 0.6 to 6 times as long as deep, median 0.8) are not beams, and ccx's
knots as large as the section cover most of each member. `--shells AXES` models the panels
themselves instead: each edge's quad from axes.json as S8R shells with its gauge as thickness,
panels welded along the node axes they share, self-weight as gravity on the shells, point loads
at mid-height of the axis; compared with the frame's displacements to `--shell-tolerance`.
When lamina itself analysed the panels as shells (`lamina size --shells N`: sizing.json's
"analysis" is {"shells": N}), its displacements are compared with these S8R shells alone (the
beam deck is used for its supports), to `--shell-tolerance` (default 5 %).

    check_ccx.py model.inp sizing.json [--tolerance 0.01] [--torsion] [--shells axes.json]
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


G_MM = 9806.65  # standard gravity, mm/s²


def num(x):
    """A number for a deck field: ccx reads 20 characters of it, no more."""
    return f"{float(x):.12g}"


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


def frd_section_forces(path):
    """{node: [c1..c6]} of the first STRESS block of a .frd written with *EL FILE, SECTION
    FORCES: for beams ccx puts the section forces there, in the beam's local axes (1 = the
    section's 1-direction, 2 = tangent x 1): 3 the normal force, 4 the torque, 5 and 6 the
    moments about 1 and 2, each the resultant on the face whose outward normal is the tangent.
    (Components 1 and 2 are meant as shear forces; they are not usable: a cantilever under
    10 N prints 10 to 60.)"""
    out, inside = {}, False
    for line in open(path):
        if line.startswith(" -4"):
            inside = line.split()[1] == "STRESS" and not out
        elif inside and line.startswith(" -1"):
            # fixed columns: " -1", I10, then 12-character numbers that may touch
            out[int(line[3:13])] = [float(line[13 + 12 * i:25 + 12 * i]) for i in range(6)]
        elif line.startswith(" -3"):
            inside = False
    return out


def deck_nodes(deck_text):
    """{node: xyz} of the deck's *NODE cards."""
    nodes, inside = {}, False
    for line in deck_text.splitlines():
        s = line.strip()
        if s.startswith("*"):
            inside = s.upper().startswith("*NODE") and "PRINT" not in s.upper() \
                and "FILE" not in s.upper()
        elif inside and s:
            v = s.split(",")
            nodes[int(v[0])] = np.array([float(x) for x in v[1:4]])
    return nodes


def member_loads(deck_text, n_nodes, n_members, split):
    """The whole uniform load (N, global) on each member, from the consistent nodal loads the deck
    puts on its inner nodes: they carry all of it but a sixth of each end beam's share, which
    goes to the network nodes."""
    inner = 2 * split - 1
    w = np.zeros((n_members, 3))
    in_cload = False
    for line in deck_text.splitlines():
        s = line.strip()
        if s.startswith("*"):
            in_cload = s.upper().startswith("*CLOAD")
            continue
        if in_cload and s:
            node, dof, value = s.split(",")[:3]
            node, dof = int(node), int(dof)
            if node > n_nodes and dof <= 3:
                w[(node - n_nodes - 1) // inner, dof - 1] += float(value)
    return w


def end_beam_share(deck_text, sizing, split):
    """For each member, the fraction of its length its two end beams cover, from node positions."""
    nodes, n = deck_nodes(deck_text), len(sizing["nodes"])
    inner = 2 * split - 1
    out = []
    for k, e in enumerate(sizing["edges"]):
        a, b = nodes[e["a"] + 1], nodes[e["b"] + 1]
        first, last = nodes[n + 1 + k * inner + 1], nodes[n + 1 + k * inner + inner - 2]
        out.append((np.linalg.norm(first - a) + np.linalg.norm(b - last)) / np.linalg.norm(b - a))
    return np.array(out)


def mid_section_forces(edge, load):
    """lamina's section forces at mid-length of a member from its end forces at a (what the
    joint applies, local axes) and its whole uniform load: the left half's equilibrium, as ccx
    reports them (normal force, torque, moments about local y and z)."""
    ax = [np.array(edge["axes"][k]) for k in "xyz"]
    length = edge["length"]
    fa, ma = np.array(edge["end_forces"][:3]), np.array(edge["end_forces"][3:6])
    half = np.array([load @ a for a in ax]) / 2
    x = np.array([1.0, 0.0, 0.0])
    force = -fa - half
    moment = -ma + np.cross(length / 2 * x, fa) + np.cross(length / 4 * x, half)
    return np.array([force[0], moment[0], moment[1], moment[2]])


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
    lines += ["*MATERIAL, NAME=S", "*ELASTIC", f"{num(E)}, {num(nu)}",
              "*BEAM SECTION, ELSET=BAR, MATERIAL=S, SECTION=RECT", f"{num(d)}, {num(t)}", "0, 1, 0",
              "*BEAM SECTION, ELSET=LEVER, MATERIAL=S, SECTION=RECT", "60, 60", "1, 0, 0",
              "*BOUNDARY", "1, 1, 6", "*STEP", "*STATIC", "*CLOAD",
              f"{tip + 2}, 3, 10.0", f"{tip}, 3, -10.0",  # a couple of 1000 N mm about x
              "*NODE PRINT, NSET=NALL", "U", "*END STEP"]
    u = dat_blocks(run_ccx("\n".join(lines) + "\n", "twist", workdir))["displacements"]
    twist = (u[tip + 2][2] - u[tip][2]) / 100.0
    exact = 1000.0 * length / (E / (2 * (1 + nu)) * torsion_constant(d, t))
    return twist / exact


def beams_per_member(deck_text):
    """How many B32 the deck splits member 1 into."""
    m = re.search(r"\*ELEMENT,\s*TYPE=B32,\s*ELSET=M1\s*\n((?:[^*].*\n)+)", deck_text, re.I)
    if not m:
        fail("the deck has no ELSET=M1 of B32 beams")
    return len([l for l in m.group(1).splitlines() if l.strip()])


def compare_forces(text, frd, sizing, label):
    """Section forces at every member's mid-length: ccx's (SECTION FORCES at the node between
    the member's middle two beams, which no other member shares) against lamina's end forces
    carried to mid-length. Returns the worst difference over the largest of its kind."""
    n, members = len(sizing["nodes"]), sizing["edges"]
    split = beams_per_member(text)
    if split % 2:
        fail(f"{split} beams a member: no node at mid-length")
    w = member_loads(text, n, len(members), split)
    w /= (1.0 - end_beam_share(text, sizing, split) / 6.0)[:, None]
    ccx = frd_section_forces(frd)
    lam, got = [], []
    for k, edge in enumerate(members):
        mid = n + 1 + k * (2 * split - 1) + split - 1
        if mid not in ccx:
            fail(f"ccx wrote no section forces at member {k}'s mid-length node {mid}")
        c = ccx[mid]
        got.append([c[2], c[3], c[4], c[5]])
        lam.append(mid_section_forces(edge, w[k]))
    lam, got = np.array(lam), np.array(got)
    scale_n = np.abs(lam[:, 0]).max()
    scale_m = np.abs(lam[:, 1:]).max()
    rel_n = np.abs(got[:, 0] - lam[:, 0]) / scale_n
    rel_m = np.abs(got[:, 1:] - lam[:, 1:]).max(axis=1) / scale_m
    kn, km = int(rel_n.argmax()), int(rel_m.argmax())
    print(f"check_ccx: {label}section forces at mid-length of {len(members)} members: normal "
          f"force up to {scale_n:.4g} N, worst difference {100 * rel_n[kn]:.2f} % of it (member "
          f"{kn}); moments up to {scale_m:.4g} N mm, worst {100 * rel_m[km]:.2f} % (member {km}, "
          f"torque / My / Mz lamina {', '.join(f'{v:.4g}' for v in lam[km, 1:])}, ccx "
          f"{', '.join(f'{v:.4g}' for v in got[km, 1:])}); shear forces not compared (ccx's are "
          f"not usable)")
    return max(rel_n[kn], rel_m[km])


def compare(deck_path, sizing_path, tolerance, torsion, label="", forces=False):
    sizing = json.load(open(sizing_path))
    text = open(deck_path).read()
    if forces:
        at = text.upper().rfind("*END STEP")
        if at < 0:
            fail(f"{deck_path}: no *END STEP")
        text = text[:at] + "*EL FILE, SECTION FORCES, OUTPUT=2D\nS\n" + text[at:]
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
        rf = blocks.get("forces", {})
        lam_r = {r["node"]: np.array(r["force"]) for r in sizing["reactions"]}
        if set(i - 1 for i in rf) != set(lam_r):
            fail(f"ccx's supports {sorted(i - 1 for i in rf)} are not lamina's {sorted(lam_r)}")
        # ccx reports the whole reaction only where its knot gathers the section (two or more
        # members at the node); at a single member's end its RF is the beam node's own share.
        degree = np.bincount([e[k] for e in sizing["edges"] for k in "ab"], minlength=n)
        knots = [i for i in lam_r if degree[i] >= 2]
        rel_r = 0.0
        if knots:
            scale_r = max(np.linalg.norm(f) for f in lam_r.values())
            dr = {i: np.linalg.norm(np.array(rf[i + 1][:3]) - lam_r[i]) for i in knots}
            wr = max(dr, key=dr.get)
            rel_r = dr[wr] / scale_r
            print(f"check_ccx: {label}reactions at {len(knots)} of {len(lam_r)} supports (those "
                  f"with a knot): largest {scale_r:.4g} N, worst difference {dr[wr]:.3g} N at "
                  f"node {wr} ({100 * rel_r:.2f} % of the largest)")
        rel_f = compare_forces(text, os.path.join(work, "deck.frd"), sizing, label) if forces else 0.0
        if torsion:
            secs = sections(text)
            picks = secs if len(secs) <= 4 else [min(secs, key=lambda s: s[0] / s[1]),
                                                 max(secs, key=lambda s: s[0] / s[1])]
            ratios = [(d, t, twist_ratio(d, t, E, nu, work)) for d, t in picks]
            print(f"check_ccx: {label}ccx's expanded B32 twists " + ", ".join(
                f"{r:.3f}" for _, _, r in ratios) + " of Saint-Venant's twist on the sections "
                + ", ".join(f"{d:g} x {t:g}" for d, t, _ in ratios) + f" ({len(secs)} sections)")
    worst = max(rel_u, rel_r, rel_f)
    if worst > tolerance:
        fail(f"{label}{sizing_path}: {100 * worst:.2f} % from CalculiX, over the "
             f"{100 * tolerance:g} % allowed")
    print(f"check_ccx: {label}{sizing_path}: within {100 * tolerance:g} % of CalculiX")
    return worst


def deck_supports(deck_text):
    """{network node (0-based): 'fixed' | 'pinned'} from the deck's *BOUNDARY cards."""
    out, inside = {}, False
    for line in deck_text.splitlines():
        s = line.strip()
        if s.startswith("*"):
            inside = s.upper().startswith("*BOUNDARY")
        elif inside and s:
            node, first, last = (int(v) for v in s.split(",")[:3])
            out[node - 1] = "fixed" if (first, last) == (1, 6) else "pinned"
    return out


def shell_model(axes, sizing, deck_text, per_height):
    """The panels themselves as CalculiX shells (S8R, the gauge as thickness): each edge's quad
    from its two node axes (base p to p + height x axis) meshed `per_height` elements up and
    square-ish along; panels meeting at a node share the nodes of its axis line, so they are
    welded along it. A fixed support holds the whole axis line (all six freedoms of each of its
    nodes), a pinned one the axis' mid-point (translations). Self-weight as gravity on the
    shells' own volume; point loads at the axis' mid-point, where the frame model has its node.
    Returns the deck and, per network node, the shell node at mid-height of its axis."""
    mat = sizing["material"]
    nodes = axes["nodes"]
    p = np.array([n["p"] for n in nodes], dtype=float)
    d = np.array([n["axis"] for n in nodes], dtype=float)
    h = np.array([n["height"] for n in nodes], dtype=float)
    nv = 2 * per_height  # node rows up an axis
    ids, coords = {}, []

    def node(key, xyz):
        if key not in ids:
            ids[key] = len(coords) + 1
            coords.append(xyz)
        return ids[key]

    elements, thickness = [], []
    for k, e in enumerate(axes["edges"]):
        a, b = e["a"], e["b"]
        length = np.linalg.norm(p[b] - p[a])
        nu = 2 * max(1, math.ceil(length / (h[a] + h[b]) * 2 * per_height))
        grid = {}
        for i in range(nu + 1):
            for j in range(nv + 1):
                if i % 2 and j % 2:
                    continue  # serendipity: no centre node
                u, v = i / nu, j / nv
                xyz = (1 - u) * (p[a] + v * h[a] * d[a]) + u * (p[b] + v * h[b] * d[b])
                key = (("n", a, j) if i == 0 else ("n", b, j) if i == nu else ("e", k, i, j))
                grid[i, j] = node(key, xyz)
        for i in range(0, nu, 2):
            for j in range(0, nv, 2):
                elements.append([grid[i, j], grid[i + 2, j], grid[i + 2, j + 2], grid[i, j + 2],
                                 grid[i + 1, j], grid[i + 2, j + 1], grid[i + 1, j + 2],
                                 grid[i, j + 1]])
                thickness.append(sizing["edges"][k]["gauge"])
    centre = {i: ids[("n", i, per_height)] for i in range(len(nodes)) if ("n", i, per_height) in ids}
    lines = ["*HEADING", "check_ccx: the panels as S8R shells", "*NODE, NSET=NALL"]
    lines += [f"{i + 1}, {num(x)}, {num(y)}, {num(z)}" for i, (x, y, z) in enumerate(coords)]
    by_gauge = {}
    for el, t in enumerate(thickness):
        by_gauge.setdefault(t, []).append(el)
    by_gauge = sorted(by_gauge.items())
    for g, (t, els) in enumerate(by_gauge):
        lines.append(f"*ELEMENT, TYPE=S8R, ELSET=G{g}")
        lines += [f"{el + 1}, " + ", ".join(map(str, elements[el])) for el in els]
    # Every element in one set, for the gravity load.
    lines += ["*ELSET, ELSET=NALL_E"] + [f"G{g}" for g in range(len(by_gauge))]
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", f"{num(mat['E'])}, {num(mat['nu'])}",
              "*DENSITY", num(mat["density"] * 1e-9)]  # g/cm³ -> t/mm³
    for g, (t, _) in enumerate(by_gauge):
        lines += [f"*SHELL SECTION, ELSET=G{g}, MATERIAL=STEEL", num(t)]
    lines.append("*BOUNDARY")
    for i, kind in sorted(deck_supports(deck_text).items()):
        if kind == "fixed":
            lines += [f"{ids[('n', i, j)]}, 1, 6" for j in range(nv + 1)]
        else:
            lines.append(f"{centre[i]}, 1, 3")
    lines += ["*STEP", "*STATIC"]
    for case in sizing["cases"]:
        if case == "all loads":
            continue  # the sum of the others, which this one step applies together
        if case == "self-weight":
            lines += ["*DLOAD", f"NALL_E, GRAV, {num(G_MM)}, 0, 0, -1"]
        elif case.startswith("point:"):
            m = re.fullmatch(r"point:node=(\d+):([^,]+),([^,]+),([^,]+)", case)
            if not m:
                fail(f"cannot read the load case {case!r}")
            lines.append("*CLOAD")
            lines += [f"{centre[int(m.group(1))]}, {c + 1}, {num(m.group(c + 2))}"
                      for c in range(3) if float(m.group(c + 2)) != 0.0]
        else:
            fail(f"the shell model takes self-weight and point loads, not {case!r}")
    lines += ["*NODE PRINT, NSET=NALL", "U", "*END STEP"]
    return "\n".join(lines) + "\n", centre, len(elements)


def lone_panel(length, height, gauge, E, nu, per_height, workdir):
    """Shell over beam deflection of one panel, clamped along one axis and pulled along the
    other (a unit load spread over its nodes): out of its plane, then in it. The beam is
    Timoshenko's (PL³/3EI + PL/(5/6 G A)) with I about the weak, then the strong axis."""
    axes = {"nodes": [{"p": [0.0, 0.0, 0.0], "axis": [0.0, 0.0, 1.0], "height": height},
                      {"p": [length, 0.0, 0.0], "axis": [0.0, 0.0, 1.0], "height": height}],
            "edges": [{"a": 0, "b": 1}]}
    sizing = {"material": {"E": E, "nu": nu, "density": 1.0}, "edges": [{"gauge": gauge}],
              "cases": []}
    G, area = E / (2 * (1 + nu)), height * gauge
    ratios = []
    for dof, inertia in ((2, height * gauge**3 / 12), (3, gauge * height**3 / 12)):
        text, _, _ = shell_model(axes, sizing, "*BOUNDARY\n1, 1, 6\n", per_height)
        nodes = deck_nodes(text)
        edge = sorted((k for k, x in nodes.items() if abs(x[0] - length) < 1e-9),
                      key=lambda k: nodes[k][2])
        share = np.zeros(len(edge))
        for e in range(0, len(edge) - 1, 2):  # consistent loads of quadratic edges
            share[e:e + 3] += [1 / 6, 4 / 6, 1 / 6]
        share /= share.sum()
        load = "*CLOAD\n" + "".join(f"{k}, {dof}, {num(f)}\n" for k, f in zip(edge, share))
        text = text.replace("*NODE PRINT", load + "*NODE PRINT")
        disp = dat_blocks(run_ccx(text, "panel", workdir))["displacements"]
        shell = np.mean([disp[k][dof - 1] for k in edge])
        beam = length**3 / (3 * E * inertia) + length / (5 / 6 * G * area)
        ratios.append(shell / beam)
    return ratios


def compare_shells(axes_path, sizing_path, deck_path, per_height):
    """The frame's node displacements against the shell model's."""
    axes, sizing = json.load(open(axes_path)), json.load(open(sizing_path))
    text, centre, count = shell_model(axes, sizing, open(deck_path).read(), per_height)
    n = len(sizing["nodes"])
    lam_u = np.array([nd["displacement"] for nd in sizing["nodes"]])
    scale = np.abs(lam_u).max()
    with tempfile.TemporaryDirectory() as work:
        disp = dat_blocks(run_ccx(text, "shells", work)).get("displacements", {})
        p = np.array([nd["p"] for nd in axes["nodes"]], dtype=float)
        lengths = [np.linalg.norm(p[e["b"]] - p[e["a"]]) for e in axes["edges"]]
        depth = np.median([e["depth"] for e in sizing["edges"]])
        gauge = np.median([e["gauge"] for e in sizing["edges"]])
        mat = sizing["material"]
        weak, strong = lone_panel(float(np.median(lengths)), float(depth), float(gauge),
                                  mat["E"], mat["nu"], 8, work)
    used = [i for i in range(n) if i in centre]
    shell_u = np.array([disp[centre[i]][:3] for i in used])
    du = np.linalg.norm(shell_u - lam_u[used], axis=1)
    w = int(du.argmax())
    rel = du[w] / scale
    print(f"check_ccx: shells ({count} S8R, {per_height} up each panel): largest displacement "
          f"{np.abs(shell_u).max():.4g} mm (lamina {scale:.4g}); worst difference {du[w]:.3g} mm "
          f"at node {used[w]} ({100 * rel:.2f} % of lamina's largest)")
    print(f"check_ccx: a lone panel as long as the median member ({np.median(lengths):.0f} mm, "
          f"{depth:.0f} x {gauge:g} mm), clamped along one axis and loaded along the other, "
          f"deflects {weak:.3f} of the beam out of its plane (a plate wider than long bends "
          f"without the anticlastic curvature of a beam: 1 - nu² = {1 - mat['nu'] ** 2:.3f}) "
          f"and {strong:.3f} in its plane")
    return rel


def lamina_shell_deck(deck_path, sizing_path, tolerance):
    """lamina's own S8R deck (`size --shells N --export-ccx`), run as it is: the mid-height
    node of network node i is deck node i + 1. Its displacements against sizing.json's, and
    its loads (the sum of the CLOADs) against sizing.json's reactions: the deck holds what was
    analysed."""
    text = open(deck_path).read()
    sizing = json.load(open(sizing_path))
    if "TYPE=S8R" not in text:
        fail(f"{deck_path} has no S8R elements: not a shell deck")
    loads, inside = np.zeros(3), False
    for line in text.splitlines():
        if line.startswith("*"):
            inside = line.upper().startswith("*CLOAD")
        elif inside and line.strip():
            node, dof, value = [v.strip() for v in line.split(",")]
            if int(dof) <= 3:
                loads[int(dof) - 1] += float(value)
    reactions = np.sum([r["force"] for r in sizing["reactions"]], axis=0)
    balance = np.linalg.norm(loads + reactions) / np.linalg.norm(loads)
    if not balance <= 1e-9:
        fail(f"{deck_path}: its loads {loads} do not balance sizing.json's reactions {reactions}")
    lam_u = np.array([nd["displacement"] for nd in sizing["nodes"]])
    with tempfile.TemporaryDirectory() as work:
        disp = dat_blocks(run_ccx(text, "lamina-shells", work)).get("displacements", {})
    ccx_u = np.array([disp[i + 1][:3] for i in range(len(lam_u))])
    du = np.linalg.norm(ccx_u - lam_u, axis=1)
    w, scale = int(du.argmax()), np.abs(ccx_u).max()
    rel = du[w] / scale
    print(f"check_ccx: lamina's shell deck ({deck_path}) in CalculiX: largest displacement "
          f"{scale:.4g} mm (lamina {np.abs(lam_u).max():.4g}); worst difference {du[w]:.3g} mm "
          f"at node {w} ({100 * rel:.2f} % of the largest); its loads balance lamina's "
          f"reactions to {balance:.1e}")
    if rel > tolerance:
        fail(f"{sizing_path}: {100 * rel:.2f} % from CalculiX on the same mesh, over the "
             f"{100 * tolerance:g} % allowed")


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


def portal(out, lamina):
    """A two-bay, two-storey portal frame in the x-z plane, every node axis along (1, 0, 1) so
    each panel lies in the frame's plane and in-plane loads bend the members about their strong
    axis: rigid corners carry sway and floor loads by bending alone (no bracing, no torsion).
    30 mm panels, 21 mm deep across the members (members 21 to 28 x their depth)."""
    nodes = [(x, 0.0, z) for z in (0.0, 450.0, 900.0) for x in (0.0, 500.0, 1100.0)]
    edges = []
    for level in (1, 2):
        b = 3 * level
        edges += [(b, b + 1), (b + 1, b + 2)] + [(b - 3 + i, b + i) for i in range(3)]
    write_axes(os.path.join(out, "portal-axes.json"), nodes, edges,
               lambda p: np.array([1.0, 0.0, 1.0]), 30.0)
    loads = ["self-weight", "point:node=6:40,0,-30", "point:node=7:0,0,-60",
             "point:node=4:20,0,0"]
    return size(lamina, out, "portal", loads, "3,4,5,6,8,10")


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
    ap.add_argument("--torsion-tolerance", type=float, default=0.02)
    ap.add_argument("--torsion", action="store_true", help="measure ccx's torsion of the sections")
    ap.add_argument("--slender-frame", nargs=2, metavar=("DIR", "LAMINA"))
    ap.add_argument("--shells", metavar="AXES", help="also model the panels as shells (axes.json)")
    ap.add_argument("--shell-tolerance", type=float, default=0.05)
    ap.add_argument("--per-height", type=int, default=4, help="shell elements up each panel")
    ap.add_argument("--lamina-shells", action="store_true",
                    help="the deck is lamina's own S8R deck (size --shells --export-ccx)")
    ap.add_argument("--write-shell-deck", metavar="INP",
                    help="with --shells: also write the S8R deck (for the benchmark)")
    args = ap.parse_args()
    if shutil.which("ccx") is None:
        fail("ccx is not installed (scripts/setup installs calculix-ccx)")
    if args.slender_frame:
        out, lamina = args.slender_frame
        os.makedirs(out, exist_ok=True)
        compare(*tower(out, lamina), args.tolerance, False, "braced tower: ", forces=True)
        compare(*portal(out, lamina), args.tolerance, False, "portal frame: ", forces=True)
        compare(*arm_frame(out, lamina), args.torsion_tolerance, True, "frame with an arm: ",
                forces=True)
    elif args.lamina_shells and args.deck and args.sizing:
        lamina_shell_deck(args.deck, args.sizing, args.shell_tolerance)
    elif args.deck and args.sizing:
        analysis = json.load(open(args.sizing)).get("analysis")
        lamina_shells = isinstance(analysis, dict) and "shells" in analysis
        if lamina_shells and not args.shells:
            fail(f"{args.sizing} is a shell analysis: give --shells axes.json to compare it")
        if not lamina_shells:
            compare(args.deck, args.sizing, args.tolerance, args.torsion)
        if args.shells and args.write_shell_deck:
            text, _, _ = shell_model(json.load(open(args.shells)), json.load(open(args.sizing)),
                                     open(args.deck).read(), args.per_height)
            with open(args.write_shell_deck, "w") as f:
                f.write(text)
        if args.shells:
            rel = compare_shells(args.shells, args.sizing, args.deck, args.per_height)
            if rel > args.shell_tolerance:
                fail(f"{args.sizing}: {100 * rel:.2f} % from the shell model, over the "
                     f"{100 * args.shell_tolerance:g} % allowed")
            if lamina_shells:
                print(f"check_ccx: lamina's shells ({analysis['shells']} up each panel) within "
                      f"{100 * rel:.2f} % of CalculiX's S8R shells on {args.sizing}")
    else:
        ap.error("give model.inp and sizing.json, or --slender-frame DIR LAMINA")


if __name__ == "__main__":
    main()
