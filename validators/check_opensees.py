"""A second opinion on `lamina size`'s frame from OpenSees (openseespy), sharing no code with
lamina: the same frame built from the axes file and sizing.json's members, solved by OpenSees
with 3D elastic Timoshenko beams (ElasticTimoshenkoBeam, torsion St Venant), and compared with
lamina's node displacements and rotations and member end forces under the sum of the loads.

The frame, as sizing.json's `definitions.model` describes it: a node at mid-height of each node
axis (p + axis · height / 2, from the axes file), a member per edge with a solid rectangle, depth
the edge's `depth` along its local y, thickness its `gauge` along local z (the panel normal),
rigid joints. Torsion constant of the rectangle (a long side, b short side):
a b³ (1/3 − 0.21 (b/a)(1 − b⁴/(12 a⁴))); shear areas 5/6 A.

Loads, read from sizing.json's case names and applied together (the sum of the loads):
- `self-weight[:F]`: each panel's area (the quad of its node axes) × gauge × density × g × F,
  spread uniformly along its member, down;
- `wind:KPA:DX,DY,DZ`: pressure × panel area × |local z · direction|, uniform along the member,
  along the direction;
- `point:SEL:FX,FY,FZ`: on the mid-height node of every axis whose base point the selector
  picks (`all`, `node=N`, `x|y|z` `<` `<=` `>` `>=` value).
A trailing `:G` or `:Q` (the action) does not change the load.
Supports (sizing.json `supports`, `SEL: Fixed|Pinned`): all six freedoms or the three
displacements of the mid-height node.

Pass: the largest difference in translation within --tolerance (default 1 %) of the largest
translation, rotations of the largest rotation, end forces of the largest end force, end moments
of the largest end moment. The figures are printed.

    check_opensees.py axes.json sizing.json [--tolerance 0.01]
"""
import argparse
import json
import math
import re
import sys

import numpy as np

G_ACC = 9.80665


def fail(msg):
    print(f"check_opensees: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def selector(text):
    """A predicate on (node index, base point) from lamina's selector syntax."""
    t = text.strip()
    if t == "all":
        return lambda i, p: True
    m = re.fullmatch(r"node=(\d+)", t)
    if m:
        n = int(m.group(1))
        return lambda i, p: i == n
    m = re.fullmatch(r"([xyz])\s*(<=|>=|<|>)\s*(\S+)", t)
    if not m:
        fail(f"cannot read the selector {text!r}")
    axis, op, value = "xyz".index(m.group(1)), m.group(2), float(m.group(3))
    ops_ = {"<": lambda c: c < value, "<=": lambda c: c <= value,
            ">": lambda c: c > value, ">=": lambda c: c >= value}[op]
    return lambda i, p: ops_(p[axis])


def torsion_constant(d, t):
    a, b = max(d, t), min(d, t)
    return a * b**3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b**4 / (12.0 * a**4)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("axes")
    ap.add_argument("sizing")
    ap.add_argument("--tolerance", type=float, default=0.01)
    args = ap.parse_args()
    import openseespy.opensees as ops

    axes = json.load(open(args.axes))
    s = json.load(open(args.sizing))
    if s.get("analysis") != "frame":
        fail(f"{args.sizing} is a {s.get('analysis')} analysis; this compares frames")
    p = np.array([n["p"] for n in axes["nodes"]], dtype=float)
    d = np.array([n["axis"] for n in axes["nodes"]], dtype=float)
    h = np.array([n["height"] for n in axes["nodes"]], dtype=float)
    mid = p + d * (h[:, None] / 2.0)
    edges = s["edges"]
    if len(edges) != len(axes["edges"]):
        fail(f"{len(edges)} sized members for {len(axes['edges'])} axes edges")
    mat = s["material"]
    E, nu, rho = mat["E"], mat["nu"], mat["density"] * 1e-6  # kg/mm³
    G = E / (2.0 * (1.0 + nu))

    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for i, x in enumerate(mid):
        ops.node(i + 1, *map(float, x))
    held = 0
    for text in s["supports"]:
        sel, kind = text.rsplit(":", 1)
        pick = selector(sel)
        fix = [1] * 6 if kind.strip() == "Fixed" else [1, 1, 1, 0, 0, 0]
        for i in range(len(mid)):
            if pick(i, p[i]):
                ops.fix(i + 1, *fix)
                held += 1
    if held == 0:
        fail("no support matches any node")

    # Loads from the case names (the sum: every case but "all loads").
    self_weight, wind, points = 0.0, [], []
    for case in s["cases"]:
        if case == "all loads":
            continue
        body = re.sub(r":[GQ]$", "", case)
        if body.startswith("self-weight"):
            self_weight += float(body.split(":")[1]) if ":" in body else 1.0
        elif body.startswith("wind:"):
            _, kpa, direction = body.split(":")
            v = np.array([float(c) for c in direction.split(",")])
            wind.append((float(kpa), v / np.linalg.norm(v)))
        elif body.startswith("point:"):
            sel, force = body[len("point:"):].rsplit(":", 1)
            pick = selector(sel)
            f = [float(c) for c in force.split(",")]
            points += [(i, f) for i in range(len(mid)) if pick(i, p[i])]
        else:
            fail(f"cannot read the load case {case!r}")

    ops.timeSeries("Constant", 1)
    ops.pattern("Plain", 1, 1)
    for k, e in enumerate(edges):
        a, b = e["a"], e["b"]
        x = mid[b] - mid[a]
        length = np.linalg.norm(x)
        x /= length
        z = np.array(e["axes"]["z"], dtype=float)
        y = np.array(e["axes"]["y"], dtype=float)
        ops.geomTransf("Linear", k + 1, *map(float, z))
        depth, t = e["depth"], e["gauge"]
        area = depth * t
        iy, iz = depth * t**3 / 12.0, t * depth**3 / 12.0
        ops.element("ElasticTimoshenkoBeam", k + 1, a + 1, b + 1, E, G, area,
                    torsion_constant(depth, t), iy, iz, 5.0 / 6.0 * area, 5.0 / 6.0 * area, k + 1)
        quad = [p[a], p[b], p[b] + d[b] * h[b], p[a] + d[a] * h[a]]
        cross = np.cross(quad[2] - quad[0], quad[3] - quad[1])
        panel = 0.5 * np.linalg.norm(cross)
        w = np.zeros(3)
        if self_weight:
            w += np.array([0.0, 0.0, -panel * t * rho * G_ACC * self_weight / length])
        for kpa, direction in wind:
            w += direction * (kpa * 1e-3 * panel * abs(z @ direction) / length)
        if np.any(w):
            # OpenSees takes the uniform load in the element's axes: Wy, Wz, Wx.
            ops.eleLoad("-ele", k + 1, "-type", "-beamUniform",
                        float(w @ y), float(w @ z), float(w @ x))
    for i, f in points:
        ops.load(i + 1, *f, 0.0, 0.0, 0.0)

    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-12, 10)
    ops.algorithm("Linear")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")
    if ops.analyze(1) != 0:
        fail("OpenSees did not solve the frame")

    lam_u = np.array([n["displacement"] for n in s["nodes"]])
    lam_r = np.array([n["rotation"] for n in s["nodes"]])
    os_u = np.array([ops.nodeDisp(i + 1)[:3] for i in range(len(mid))])
    os_r = np.array([ops.nodeDisp(i + 1)[3:] for i in range(len(mid))])
    lam_f = np.array([e["end_forces"] for e in edges])
    os_f = np.array([ops.eleResponse(k + 1, "localForce") for k in range(len(edges))])
    forces = [0, 1, 2, 6, 7, 8]
    moments = [3, 4, 5, 9, 10, 11]
    figures = []
    for label, ours, theirs in (("translations", lam_u, os_u), ("rotations", lam_r, os_r),
                                ("end forces", lam_f[:, forces], os_f[:, forces]),
                                ("end moments", lam_f[:, moments], os_f[:, moments])):
        scale = np.abs(theirs).max()
        worst = np.abs(ours - theirs).max() / scale if scale > 0 else 0.0
        figures.append(f"{label} {worst:.2e} of {scale:.4g}")
        if not worst <= args.tolerance:
            at = np.unravel_index(np.argmax(np.abs(ours - theirs)), ours.shape)
            fail(f"{label} differ by {worst:.3%} of the largest ({scale:.4g}) at row {at[0]}: "
                 f"lamina {ours[at]:.6g}, OpenSees {theirs[at]:.6g}")
    print(f"{args.sizing}: ok against OpenSees ({len(edges)} Timoshenko beams, {len(mid)} nodes, "
          f"{held} held; largest differences: " + ", ".join(figures) + ")")


main()
