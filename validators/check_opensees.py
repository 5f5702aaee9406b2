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
  spread uniformly along its member, down; where sizing.json gives `joints` (the plates
  weighed as cut), each member's `mass_kg` and `bolts_kg` instead, and each node's `core_kg`
  on its node (--plates checks those masses against plates.json);
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

With --checks, a second opinion on the design checks: the EN 1990 combinations rebuilt from the
loads (self-weight and `:G` loads permanent, the rest variable; ULS 6.10 with γ_G 1.35 and 1.0,
γ_Q 1.5, ψ0 0.6 for wind and 0.7 for point loads; SLS characteristic) must be the ones listed;
each ULS combination solved by OpenSees, and every member's stress, flexural buckling,
lateral-torsional buckling (EN 1993-1-1 6.3.2.2, curve d, M_cr of the rectangle with C1 from
the quarter-point moments) and interaction (6.3.3, Annex B) recomputed along it, and every
node's weld (EN 1993-1-8 4.5.3.3) — each must equal sizing.json's to 1e-6 and be at most 1;
throats below 3 mm named; the largest SLS displacement as reported.

With --plates (after --checks), every edge cut as analysed (a seam as its sized plies, one per
group), the grade the sizing's, the mass (each edge's plates from plates.json's areas, each
seam's bolt sets from nominal ISO 4017/4032/7089 sizes, the node cores as tubes: equal to
sizing.json's per edge and in total, the total within 0.1 %); and every seam's bolts by EN 1993-1-8 Table 3.4
recomputed here: the seam's section forces (each component's largest magnitude at either end
over the ULS combinations OpenSees solved, which must equal sizing.json's `seam_forces`), an
elastic bolt group on the holes (N and V shared, M_z ⊥ each arm; V_z shared, M_y and T as
couples about the plies' overlap's far edges), shear on one plane through the thread, bearing
on the thinner ply (k1 = min(2.8 e/d0 − 1.7, 2.5), α_d = min(e/3d0, p/3d0 − 1/4), e the least
hole-to-edge distance of the overlap by shapely, p the least pitch; stainless plies on
f_u,red = 0.5 f_y + 0.6 f_u), tension, punching (d_m the mean of the nut's flats and corners)
and shear with tension; class 8.8 (f_ub 800, α_v 0.6) with carbon steel, A4-70 (700, 0.5) with
stainless. Each must equal plates.json's to 1e-6 and be at most 1, and sizing.json's `bolts`
(size, count, class, utilisation) and `totals.max_bolt_utilisation` must name the same.

With --bom (after --plates), nest's bom.csv of those plates: every plate row's weld partners in
its own group, the sizing's grade, each seam's bolt row with plates.json's class and
utilisation, and all rows' masses (plates, bolt sets, tubes) adding up to the mass analysed
within 0.1 % (each row is written to 0.1 g).

    check_opensees.py axes.json sizing.json [--tolerance 0.01] [--checks] [--plates plates.json
                      [--bom bom.csv]]
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


def tau_modulus(d, t):
    """Roark, Table 10.7 case 4: the torque over the largest shear stress of a rectangle."""
    a, b = max(d, t) / 2.0, min(d, t) / 2.0
    r = b / a
    return 8.0 * a * b * b / (3.0 * (1 + 0.6095 * r + 0.8865 * r**2 - 1.8023 * r**3
                                     + 0.9100 * r**4))


def layers(e):
    """The plates across a member: a bolted seam's two plies (sizing.json `plies`, which must
    add up to its gauge), or the one plate."""
    plies = e.get("plies")
    if plies is None:
        return [e["gauge"]]
    if abs(sum(plies) - e["gauge"]) > 1e-9:
        fail(f"member {e['a']}-{e['b']}: plies {plies} do not add up to its gauge {e['gauge']}")
    return list(plies)


def section(e):
    """Area, I out of the plane, I in it, torsion constant, W out of the plane, torsion
    modulus: plies side by side with no shear connection bend out of their plane and twist each
    on its own, sharing a moment by their stiffness (the thickest most stressed)."""
    d, t = e["depth"], e["gauge"]
    ts = layers(e)
    i_weak = sum(d * ti**3 / 12.0 for ti in ts)
    j = sum(torsion_constant(d, ti) for ti in ts)
    w_weak = i_weak / (max(ts) / 2.0)
    w_tau = min(tau_modulus(d, ti) * j / torsion_constant(d, ti) for ti in ts)
    return d * t, i_weak, t * d**3 / 12.0, j, w_weak, w_tau


def read_loads(cases):
    """[(name, kind, value)] of the characteristic cases (every case but "all loads"): kind is
    self-weight (factor), wind ((kPa, unit direction)) or point ([(node, force)])."""
    out = []
    for case in cases:
        if case == "all loads":
            continue
        body = re.sub(r":[GQ]$", "", case)
        if body.startswith("self-weight"):
            out.append((case, "self-weight", float(body.split(":")[1]) if ":" in body else 1.0))
        elif body.startswith("wind:"):
            _, kpa, direction = body.split(":")
            v = np.array([float(c) for c in direction.split(",")])
            out.append((case, "wind", (float(kpa), v / np.linalg.norm(v))))
        elif body.startswith("point:"):
            sel, force = body[len("point:"):].rsplit(":", 1)
            out.append((case, "point", (selector(sel), [float(c) for c in force.split(",")])))
        else:
            fail(f"cannot read the load case {case!r}")
    return out


class Frame:
    """The frame of the axes and sizing.json, solvable by OpenSees for any set of loads."""

    def __init__(self, axes, s):
        self.s = s
        p = np.array([n["p"] for n in axes["nodes"]], dtype=float)
        d = np.array([n["axis"] for n in axes["nodes"]], dtype=float)
        h = np.array([n["height"] for n in axes["nodes"]], dtype=float)
        self.p, self.mid = p, p + d * (h[:, None] / 2.0)
        self.edges = s["edges"]
        if len(self.edges) != len(axes["edges"]):
            fail(f"{len(self.edges)} sized members for {len(axes['edges'])} axes edges")
        mat = s["material"]
        self.E, self.nu = mat["E"], mat["nu"]
        self.G = self.E / (2.0 * (1.0 + self.nu))
        rho = mat["density"] * 1e-6  # kg/mm³
        # Per member: local axes, length, its panel's weight per length at gauge and area.
        self.frames, self.weight, self.panel = [], [], []
        for e in self.edges:
            a, b = e["a"], e["b"]
            x = self.mid[b] - self.mid[a]
            length = np.linalg.norm(x)
            y, z = np.array(e["axes"]["y"], dtype=float), np.array(e["axes"]["z"], dtype=float)
            self.frames.append((x / length, y, z, length))
            quad = [p[a], p[b], p[b] + d[b] * h[b], p[a] + d[a] * h[a]]
            area = 0.5 * np.linalg.norm(np.cross(quad[2] - quad[0], quad[3] - quad[1]))
            self.panel.append(area)
            if s.get("joints") is not None:
                # Weighed as cut: the member's plates and bolt sets (--plates checks them
                # against plates.json).
                steel = e["mass_kg"] + (e.get("bolts_kg") or 0.0)
                self.weight.append(steel * G_ACC / length)
            else:
                self.weight.append(area * e["gauge"] * rho * G_ACC / length)
        # Node cores' weight at their nodes (weighed as cut).
        self.cores = [(i, n["core_kg"]) for i, n in enumerate(s["nodes"]) if n.get("core_kg")]
        self.held = []
        for text in s["supports"]:
            sel, kind = text.rsplit(":", 1)
            pick = selector(sel)
            fix = [1] * 6 if kind.strip() == "Fixed" else [1, 1, 1, 0, 0, 0]
            self.held += [(i, fix) for i in range(len(self.mid)) if pick(i, p[i])]
        if not self.held:
            fail("no support matches any node")

    def member_loads(self, loads):
        """Per member, the uniform load of `loads` ([(kind, value, factor)]), global, N/mm."""
        w = np.zeros((len(self.edges), 3))
        for kind, value, factor in loads:
            for k, (x, y, z, length) in enumerate(self.frames):
                if kind == "self-weight":
                    w[k, 2] -= self.weight[k] * value * factor
                elif kind == "wind":
                    kpa, direction = value
                    w[k] += direction * (kpa * 1e-3 * self.panel[k] * abs(z @ direction) / length
                                         * factor)
        return w

    def solve(self, loads):
        """Displacements (n × 6) and local end forces (members × 12) under `loads`."""
        import openseespy.opensees as ops
        ops.wipe()
        ops.model("basic", "-ndm", 3, "-ndf", 6)
        for i, x in enumerate(self.mid):
            ops.node(i + 1, *map(float, x))
        for i, fix in self.held:
            ops.fix(i + 1, *fix)
        ops.timeSeries("Constant", 1)
        ops.pattern("Plain", 1, 1)
        w = self.member_loads(loads)
        for k, e in enumerate(self.edges):
            x, y, z, _ = self.frames[k]
            ops.geomTransf("Linear", k + 1, *map(float, z))
            area, i_weak, i_strong, j, _, _ = section(e)
            ops.element("ElasticTimoshenkoBeam", k + 1, e["a"] + 1, e["b"] + 1, self.E, self.G,
                        area, j, i_weak, i_strong, 5.0 / 6.0 * area, 5.0 / 6.0 * area, k + 1)
            if np.any(w[k]):
                # OpenSees takes the uniform load in the element's axes: Wy, Wz, Wx.
                ops.eleLoad("-ele", k + 1, "-type", "-beamUniform",
                            float(w[k] @ y), float(w[k] @ z), float(w[k] @ x))
        for kind, value, factor in loads:
            if kind == "self-weight":
                for i, kg in self.cores:
                    ops.load(i + 1, 0.0, 0.0, -kg * G_ACC * value * factor, 0.0, 0.0, 0.0)
            if kind == "point":
                pick, f = value
                for i in range(len(self.mid)):
                    if pick(i, self.p[i]):
                        ops.load(i + 1, *(factor * np.array(f)), 0.0, 0.0, 0.0)
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("UmfPack")
        ops.test("NormDispIncr", 1e-12, 10)
        ops.algorithm("Linear")
        ops.integrator("LoadControl", 1.0)
        ops.analysis("Static")
        if ops.analyze(1) != 0:
            fail("OpenSees did not solve the frame")
        u = np.array([ops.nodeDisp(i + 1) for i in range(len(self.mid))])
        f = np.array([ops.eleResponse(k + 1, "localForce") for k in range(len(self.edges))])
        return u, f, w

STATIONS = (0.0, 0.25, 0.5, 0.75, 1.0)


def chi(lam, alpha, plateau):
    """EN 1993-1-1 (6.49)."""
    if lam <= plateau:
        return 1.0
    phi = 0.5 * (1.0 + alpha * (lam - plateau) + lam * lam)
    return min(1.0, 1.0 / (phi + math.sqrt(max(phi * phi - lam * lam, 0.0))))


def member_checks(e, mat, end, w, length):
    """[stress, buckling, lateral-torsional, interaction] of one member in one state: its end
    forces (local, what the joints apply) and its uniform load (local)."""
    d, t = e["depth"], e["gauge"]
    fy, E = mat["fy"], mat["E"]
    G = E / (2.0 * (1.0 + mat["nu"]))
    area, i_weak, i_strong, it, w_weak, w_tau = section(e)
    w_strong = t * d * d / 6.0
    f, m = np.array(end[:3]), np.array(end[3:6])
    stress, compression, strong, weak = 0.0, 0.0, [], 0.0
    for frac in STATIONS:
        x = frac * length
        # The part [0, x] in equilibrium: the section's forces are minus the end's and the load's.
        force = -(f + w * x)
        moment = -(m + np.array([0.0, x * f[2] + 0.5 * x * x * w[2],
                                 -x * f[1] - 0.5 * x * x * w[1]]))
        n, vy, vz = force
        tx, my, mz = moment
        sigma = abs(n) / area + abs(my) / w_weak + abs(mz) / w_strong
        tau = abs(tx) / w_tau + 1.5 * math.hypot(vy, vz) / area
        stress = max(stress, math.sqrt(sigma**2 + 3 * tau**2) / (fy / mat["gamma_M0"]))
        compression = max(compression, -n)
        strong.append(abs(mz))
        weak = max(weak, abs(my))
    lam1 = math.pi * math.sqrt(E / fy)
    lam_z = length / math.sqrt(i_weak / area) / lam1
    lam_y = length / math.sqrt(i_strong / area) / lam1
    n_rd = area * fy / mat["gamma_M1"]
    n_z = compression / (chi(lam_z, 0.49, 0.2) * n_rd)
    n_y = compression / (chi(lam_y, 0.49, 0.2) * n_rd)
    m_max = max(strong)
    if d > t:
        c1 = 1.0 if m_max <= 0 else min(2.5, max(1.0, 12.5 * m_max / (
            2.5 * m_max + 3 * strong[1] + 4 * strong[2] + 3 * strong[3])))
        mcr = c1 * math.pi / length * math.sqrt(E * i_weak * G * it)
        chi_lt = chi(min(math.sqrt(w_strong * fy / mcr), 1e6), 0.76, 0.2)
    else:
        chi_lt = 1.0
    ltb = m_max / (chi_lt * w_strong * fy / mat["gamma_M1"])
    bend_weak = weak / (w_weak * fy / mat["gamma_M1"])
    k_yy = 1 + 0.6 * min(lam_y, 1.0) * n_y
    k_zz = 1 + 0.6 * min(lam_z, 1.0) * n_z
    interaction = max(n_y + k_yy * ltb + k_zz * bend_weak, n_z + ltb + k_zz * bend_weak)
    return [stress, n_z, ltb, interaction]


def welded(e, end):
    """The plate welded at a member's end (0 at node a): a seam's ply there, else the plate."""
    return layers(e)[end] if e.get("plies") else e["gauge"]


def weld_per_length(e, end_forces, end):
    """Force per length on the two fillet welds at one member end (EN 1993-1-8 4.5.3.3)."""
    h, t = e["depth"], welded(e, end)
    nx, vy, vz, tx, my, mz = (abs(v) for v in end_forces)
    polar = 2.0 * (h**3 / 12.0 + h * t * t / 4.0)
    f_t = tx * math.sqrt(0.25 * (h * h + t * t)) / polar
    along = nx / (2 * h) + 3 * mz / (h * h) + my / (t * h)
    return math.sqrt(along**2 + (vy / (2 * h) + f_t)**2 + (vz / (2 * h) + f_t)**2)


def en1993(frame, s, loads, name):
    """The EN 1990 combinations from the loads, and every member's and weld's checks under the
    ultimate ones, recomputed from OpenSees' forces, against sizing.json."""
    names = [n for n, _, _ in loads]
    permanent = [k == "self-weight" or n.endswith(":G") for n, k, _ in loads]
    psi0 = [0.6 if k == "wind" else 0.7 for _, k, _ in loads]
    variable = [i for i in range(len(loads)) if not permanent[i]]
    leads = variable or [None]
    want = []
    for limit, gs, q in (("ULS", [1.35] + ([1.0] if any(permanent) and variable else []), 1.5),
                         ("SLS", [1.0], 1.0)):
        for g in gs:
            for lead in leads:
                want.append((limit, tuple(g if permanent[i] else (q if i == lead else q * psi0[i])
                                          for i in range(len(loads)))))
    got = [(c["limit"], tuple(c["factors"][n] for n in names)) for c in s["combinations"]]
    if len(got) != len(want) or any(a[0] != b[0] or not np.allclose(a[1], b[1], rtol=0, atol=1e-12)
                                     for a, b in zip(sorted(got), sorted(want))):
        fail(f"combinations {got} are not EN 1990's {want}")
    mat = s["material"]
    edges = frame.edges
    worst = np.zeros((len(edges), 4))
    welds = np.zeros(len(s["nodes"]))
    seam = {k: [] for k, e in enumerate(edges) if e.get("plies")}
    largest_sls = 0.0
    for c in s["combinations"]:
        factored = [(kind, value, c["factors"][n]) for n, kind, value in loads]
        u, f, w = frame.solve(factored)
        if c["limit"] == "SLS":
            largest_sls = max(largest_sls, np.linalg.norm(u[:, :3], axis=1).max())
            continue
        for k in seam:
            seam[k].append(f[k])
        for k, e in enumerate(edges):
            x, y, z, length = frame.frames[k]
            local_w = np.array([w[k] @ x, w[k] @ y, w[k] @ z])
            worst[k] = np.maximum(worst[k], member_checks(e, mat, f[k], local_w, length))
            for end, (forces, node) in enumerate(((f[k][:6], e["a"]), (f[k][6:], e["b"]))):
                welds[node] = max(welds[node], weld_per_length(e, forces, end))
    ours = np.array([[e["checks"][n]["utilisation"] for n in
                      ("stress", "buckling", "lateral-torsional", "interaction")] for e in edges])
    diff = np.abs(ours - worst).max()
    if not diff <= 1e-6 * max(1.0, worst.max()):
        k, j = np.unravel_index(np.argmax(np.abs(ours - worst)), ours.shape)
        fail(f"member {k}: check {j} is {ours[k, j]:.6g} in {name}, {worst[k, j]:.6g} here")
    util = np.array([e["utilisation"] for e in edges])
    if np.abs(util - worst.max(axis=1)).max() > 1e-6:
        fail("a member's utilisation is not its largest check")
    # Welds: the throat is one factor times the thinnest plate at every node.
    thinnest = np.full(len(s["nodes"]), np.inf)
    for e in edges:
        for end, v in enumerate((e["a"], e["b"])):
            thinnest[v] = min(thinnest[v], welded(e, end))
    throat = np.array([nd["throat"] for nd in s["nodes"]])
    factor = throat / thinnest
    if np.ptp(factor) > 1e-12:
        fail(f"throats are not one factor times the thinnest plate ({factor.min()}..{factor.max()})")
    fvw = mat["fu"] / (math.sqrt(3) * mat["beta_w"] * mat["gamma_M2"])
    weld_u = welds / (fvw * throat)
    lam_w = np.array([nd["weld_utilisation"] for nd in s["nodes"]], dtype=float)
    if np.abs(weld_u - lam_w).max() > 1e-6 * max(1.0, weld_u.max()):
        i = int(np.argmax(np.abs(weld_u - lam_w)))
        fail(f"node {i}: weld utilisation {lam_w[i]:.6g} in {name}, {weld_u[i]:.6g} here")
    thin = sorted(int(i) for i in np.nonzero(throat < 3.0)[0])
    if thin != s["totals"]["thin_sheet_welds"] or \
            any(nd["thin_sheet"] != (i in thin) for i, nd in enumerate(s["nodes"])):
        fail("the nodes with throats under 3 mm are not the ones named")
    if abs(largest_sls - s["totals"]["max_displacement"]) > 1e-6 * largest_sls:
        fail(f"largest SLS displacement {largest_sls:.6g} mm here, "
             f"{s['totals']['max_displacement']:.6g} in {name}")
    # What each seam's bolts carry: the ULS envelope of its section forces.
    envelope = {k: np.max(np.abs(np.array(seam[k])).reshape(-1, 2, 6), axis=(0, 1))
                for k in seam}
    for k, env in envelope.items():
        theirs = edges[k].get("seam_forces")
        if theirs is None or np.abs(np.array(theirs) - env).max() > 1e-6 * max(1.0, env.max()):
            fail(f"member {k}: seam forces {theirs} in {name}, {env.tolist()} here")
    for k, e in enumerate(edges):
        if e.get("plies") is None and e.get("seam_forces") is not None:
            fail(f"member {k}: seam forces on a member that is no seam")
    governing = {}
    for e in edges:
        governing[e["check"]] = governing.get(e["check"], 0) + 1
    over = [(k, util[k]) for k in range(len(edges)) if util[k] > 1.0]
    over_w = [(i, weld_u[i]) for i in range(len(weld_u)) if weld_u[i] > 1.0]
    if over or over_w:
        fail(f"over-utilised: members {over[:5]}, welds {over_w[:5]}")
    print(f"{name}: EN 1990/1993 ok ({len(s['combinations'])} combinations as EN 1990 gives "
          f"them; {len(edges)} members' four checks recomputed from OpenSees' forces to "
          f"{diff:.1e}, largest {worst.max():.3f}, governing {governing}; welds to "
          f"{np.abs(weld_u - lam_w).max():.1e}, largest {weld_u.max():.3f}, {len(thin)} below a "
          f"3 mm throat and named; largest SLS displacement {largest_sls:.3f} mm)")
    return envelope


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("axes")
    ap.add_argument("sizing")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--checks", action="store_true",
                    help="also recompute the EN 1990 combinations and EN 1993 checks")
    ap.add_argument("--bom", metavar="BOM_CSV",
                    help="with --plates: nest's bom.csv of those plates, checked against both")
    ap.add_argument("--plates", metavar="PLATES_JSON",
                    help="the plates cut from this sizing: built as analysed")
    args = ap.parse_args()
    axes = json.load(open(args.axes))
    s = json.load(open(args.sizing))
    if s.get("analysis") != "frame":
        fail(f"{args.sizing} is a {s.get('analysis')} analysis; this compares frames")
    frame = Frame(axes, s)
    loads = read_loads(s["cases"])
    os_all, os_f, _ = frame.solve([(kind, value, 1.0) for _, kind, value in loads])
    os_u, os_r = os_all[:, :3], os_all[:, 3:]
    edges = frame.edges
    lam_u = np.array([n["displacement"] for n in s["nodes"]])
    lam_r = np.array([n["rotation"] for n in s["nodes"]])
    lam_f = np.array([e["end_forces"] for e in edges])
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
    print(f"{args.sizing}: ok against OpenSees ({len(edges)} Timoshenko beams, {len(frame.mid)} "
          f"nodes, {len(frame.held)} held; largest differences: " + ", ".join(figures) + ")")
    envelope = en1993(frame, s, loads, args.sizing) if args.checks else None
    if args.plates:
        doc = json.load(open(args.plates))
        built_as_sized(s, doc, args.plates)
        if envelope is not None:
            bolts_hold(s, doc, envelope, args.plates)
        if args.bom:
            bom_as_built(s, doc, args.bom)


# Bolt: d, d0, tensile stress area A_s (ISO 898-1), nut across flats s (ISO 4032).
BOLTS = {"M6": (6, 6.6, 20.1, 10), "M8": (8, 9, 36.6, 13), "M10": (10, 11, 58, 16),
         "M12": (12, 13, 84.3, 18), "M16": (16, 18, 157, 24), "M20": (20, 22, 245, 30),
         "M22": (22, 24, 303, 34), "M24": (24, 26, 353, 36), "M27": (27, 30, 459, 41),
         "M30": (30, 33, 561, 46)}


def bolt_checks(bolt, stainless, mat, holes, overlap, t, forces):
    """EN 1993-1-8 Table 3.4 on the most loaded bolt: shear, bearing, tension, punching, and
    shear with tension, as utilisations."""
    from shapely.geometry import Point
    d, d0, area, flats = BOLTS[bolt]
    fub, alpha_v = (700.0, 0.5) if stainless else (800.0, 0.6)
    fu = min(0.5 * mat["fy"] + 0.6 * mat["fu"], mat["fu"]) if stainless else mat["fu"]
    g = mat["gamma_M2"]
    n = len(holes)
    fx, fy, fz, mx, my, mz = (abs(v) for v in forces)
    h = np.array(holes, dtype=float)
    r = np.abs(h - h.mean(axis=0))
    polar = float((r ** 2).sum())
    twist = mz / polar if polar > 0 else 0.0
    shear = float(np.hypot(fx / n + twist * r[:, 1], fy / n + twist * r[:, 0]).max())
    xs, ys = np.array(overlap.exterior.coords).T

    def couple(moment, along, coords):
        if moment == 0:
            return 0.0
        out = 0.0
        for edge in (coords.min(), coords.max()):
            arm = np.abs(h[:, along] - edge)
            out = max(out, moment * arm.max() / (arm ** 2).sum())
        return out

    tension = fz / n + couple(my, 0, xs) + couple(mx, 1, ys)
    f_v = alpha_v * fub * area / g
    f_t = 0.9 * fub * area / g
    e = min(overlap.exterior.distance(Point(p)) for p in holes)
    p = min(math.dist(a, b) for a, b in zip(holes, holes[1:]))
    alpha_b = min(e / (3 * d0), p / (3 * d0) - 0.25, fub / fu, 1.0)
    k1 = min(2.8 * e / d0 - 1.7, 2.5)
    f_b = max(k1 * alpha_b * fu * d * t / g, 0.0)
    b_p = 0.6 * math.pi * 0.5 * flats * (1 + 2 / math.sqrt(3)) * t * fu / g
    return {"shear": shear / f_v, "bearing": shear / f_b, "tension": tension / f_t,
            "punching": tension / b_p, "shear and tension": shear / f_v + tension / (1.4 * f_t)}


def bolts_hold(s, doc, envelope, name):
    """Every seam's bolts recomputed by Table 3.4 under OpenSees' ULS envelope."""
    from shapely.geometry import Polygon
    stainless = re.match(r"1\.4[0-6]", s["material"]["name"].strip()) is not None
    by_edge = {}
    for p in doc["plates"]:
        by_edge.setdefault(p["edge"], []).append(p)
    worst, diff, count = 0.0, 0.0, 0
    for k, env in envelope.items():
        a, b = by_edge[k]
        bolt = a["bolt"]
        want_class = "A4-70" if stainless else "8.8"
        if bolt.get("class") != want_class or not bolt.get("preload"):
            fail(f"edge {k}: bolts of class {bolt.get('class')} ({bolt.get('preload')!r}), "
                 f"{want_class} with its installation stated expected")
        overlap = Polygon(a["outline"]).intersection(Polygon(b["outline"]))
        ours = bolt_checks(bolt["size"], stainless, s["material"], a["holes"], overlap,
                           min(a["thickness"], b["thickness"]), env)
        theirs = bolt.get("checks") or {}
        for check, u in ours.items():
            got = theirs.get(check)
            if got is None or abs(got - u) > 1e-6 * max(1.0, u):
                fail(f"edge {k}: bolt {check} {got} in {name}, {u:.6g} here")
            diff = max(diff, abs((got or 0.0) - u))
        top = max(ours.values())
        if abs(bolt.get("utilisation", -1) - top) > 1e-6 * max(1.0, top):
            fail(f"edge {k}: bolt utilisation {bolt.get('utilisation')}, its largest check {top:.6g}")
        if top > 1.0:
            fail(f"edge {k}: {bolt['size']} bolts at utilisation {top:.3f}")
        # The sizing names the same row and the same utilisation.
        sized = s["edges"][k].get("bolts") or {}
        if (sized.get("size"), sized.get("count"), sized.get("class")) != \
                (bolt["size"], len(a["holes"]), bolt["class"]) or \
                abs((sized.get("utilisation") or -1.0) - top) > 1e-6 * max(1.0, top):
            fail(f"edge {k}: the sizing's bolts {sized}, {len(a['holes'])} × {bolt['size']} "
                 f"{bolt['class']} at {top:.6g} here")
        worst = max(worst, top)
        count += 1
    sized_worst = s["totals"].get("max_bolt_utilisation")
    if count and (sized_worst is None or abs(sized_worst - worst) > 1e-6):
        fail(f"the sizing's largest bolt utilisation {sized_worst}, {worst:.6g} here")
    print(f"{name}: bolts ok ({count} seams' rows recomputed by EN 1993-1-8 Table 3.4 under "
          f"OpenSees' ULS forces to {diff:.1e}, each as sizing.json and plates.json give it; "
          f"largest utilisation {worst:.3f})")


def built_as_sized(s, doc, name):
    """Every edge cut as it was analysed: a single plate of its gauge, or a seam's two plies
    (the sizing's, one in each group) adding up to it; the steel the sizing's; and the mass."""
    by_edge = {}
    for p in doc["plates"]:
        by_edge.setdefault(p["edge"], []).append(p)
    seams = 0
    for k, e in enumerate(s["edges"]):
        cut = by_edge.get(k, [])
        got = sorted(p["thickness"] for p in cut)
        want = sorted(e["plies"]) if e.get("plies") else [e["gauge"]]
        if len(got) != len(want) or any(abs(a - b) > 1e-9 for a, b in zip(got, want)):
            fail(f"edge {k}: cut as {got} mm, analysed as {want} mm")
        if e.get("plies"):
            seams += 1
            if len({p["group"] for p in cut}) != 2:
                fail(f"edge {k}: a seam's plies are not one in each group")
    if doc["material"]["grade"] != s["material"]["name"] or \
            abs(doc["material"]["density"] - s["material"]["density"]) > 1e-12:
        fail(f"{name}: {doc['material']} is not the sizing's {s['material']['name']}")
    rho = s["material"]["density"] * 1e-6
    if s.get("joints") is None:
        fail(f"{name}: the sizing weighed the uncut panels ({s['totals']['self_weight']})")
    plates_kg = bolts_kg = 0.0
    for k, e in enumerate(s["edges"]):
        cut = by_edge.get(k, [])
        steel = sum(p["area_mm2"] * p["thickness"] for p in cut) * rho
        bolts = bolt_sets_kg(cut[0], rho) if len(cut) == 2 else 0.0
        if abs(steel - e["mass_kg"]) > 1e-9 * max(steel, 1e-3):
            fail(f"edge {k}: its plates weigh {steel} kg, the analysis {e['mass_kg']} kg")
        if abs(bolts - (e.get("bolts_kg") or 0.0)) > 1e-9 * max(bolts, 1e-3):
            fail(f"edge {k}: its bolt sets weigh {bolts} kg, the analysis {e.get('bolts_kg')} kg")
        plates_kg += steel
        bolts_kg += bolts
    cores_kg = sum(math.pi / 4 * (c["outer_diameter"] ** 2 - (c["outer_diameter"] - 2 * c["wall"]) ** 2)
                   * c["length"] for c in doc.get("cores", [])) * rho
    sized_cores = sum(n.get("core_kg") or 0.0 for n in s["nodes"])
    if abs(cores_kg - sized_cores) > 1e-9 * max(cores_kg, 1e-3):
        fail(f"{name}: node cores {cores_kg} kg, the analysis {sized_cores} kg")
    built = plates_kg + bolts_kg + cores_kg
    analysed = s["totals"]["mass_kg"]
    if abs(built / analysed - 1.0) > 1e-3:
        fail(f"{name}: built {built:.3f} kg, analysed {analysed:.3f} kg: more than 0.1 % apart")
    print(f"{name}: built as analysed ({len(s['edges'])} edges, {seams} seams as their sized "
          f"plies; {doc['material']['grade']}; built {built:.3f} kg (plates {plates_kg:.3f}, bolt "
          f"sets {bolts_kg:.3f}, node cores {cores_kg:.3f}) against {analysed:.3f} kg analysed: "
          f"{100 * (built / analysed - 1):+.1e} %)")


def bom_as_built(s, doc, path):
    """The BOM a fabricator orders and weighs from: every plate row's weld partners in its own
    group (a seam's ply is welded only within its group), the sizing's grade, each seam's bolts
    with plates.json's utilisation, and the rows' masses adding up to the mass analysed."""
    import csv
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    plates = {p["id"]: p for p in doc["plates"]}
    total = 0.0
    kinds = {}
    for r in rows:
        total += float(r["mass_kg"] or 0.0)
        kinds[r["kind"]] = kinds.get(r["kind"], 0) + 1
        if r["kind"] == "plate":
            if r["grade"] != s["material"]["name"]:
                fail(f"{path}: {r['id']} in {r['grade']}, the sizing's steel is {s['material']['name']}")
            group = r["id"].split("-")[0]
            for end in ("welded_at_a", "welded_at_b"):
                _, partners = r[end].split(":", 1)
                for q in partners.split():
                    if q in ("not", "welded", "core") or "-C" in q:
                        continue
                    if q.split("-")[0] != group:
                        fail(f"{path}: {r['id']} is welded to {q} of another group ({r[end]})")
        elif r["kind"] == "bolts":
            a = plates[r["id"].split("+")[0]]["bolt"]
            want = f"utilisation {a['utilisation']:.3f}"
            if want not in r["bolts"] or r["grade"] != a["class"]:
                fail(f"{path}: {r['id']}: {r['grade']} {r['bolts']!r}, plates.json {a['class']} {want}")
    analysed = s["totals"]["mass_kg"]
    # Each row's mass is written to 0.1 g.
    if abs(total - analysed) > 1e-3 * analysed:
        fail(f"{path}: the rows weigh {total:.4f} kg, the analysis {analysed:.4f} kg")
    print(f"{path}: ok ({kinds.get('plate', 0)} plates welded within their groups, "
          f"{kinds.get('bolts', 0)} bolt rows with plates.json's utilisation, {kinds.get('tube', 0)} "
          f"tubes; {total:.3f} kg in all against {analysed:.3f} kg analysed: "
          f"{100 * (total / analysed - 1):+.4f} %)")


# Nominal bolt sets: head k (ISO 4017), nut m (ISO 4032), washer h and outside diameter
# (ISO 7089), across flats s; with BOLTS' d and d0.
SET_SIZES = {"M6": (4, 5.2, 1.6, 12, 10), "M8": (5.3, 6.8, 1.6, 16, 13),
             "M10": (6.4, 8.4, 2, 20, 16), "M12": (7.5, 10.8, 2.5, 24, 18),
             "M16": (10, 14.8, 3, 30, 24), "M20": (12.5, 18, 3, 37, 30),
             "M22": (14, 19.4, 3, 39, 34), "M24": (15, 21.5, 4, 44, 36),
             "M27": (17, 23.8, 4, 50, 41), "M30": (18.7, 25.6, 4, 56, 46)}


def bolt_sets_kg(ply, rho):
    """The bolt sets through a seam ply's holes, kg: shank (d × ordered length), head and nut
    as hexagon prisms (the nut less the shank), two washers as rings from d0."""
    bolt = ply["bolt"]
    d, d0 = BOLTS[bolt["size"]][:2]
    k, m, h, od, flats = SET_SIZES[bolt["size"]]
    hexagon = math.sqrt(3) / 2 * flats ** 2
    shank = math.pi / 4 * d ** 2
    ring = math.pi / 4 * (od ** 2 - d0 ** 2)
    each = shank * bolt["length"] + hexagon * k + (hexagon - shank) * m + 2 * ring * h
    return each * len(ply["holes"]) * rho


main()
