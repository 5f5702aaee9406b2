"""ISO 1101 flatness of panels, recomputed without lamina (numpy, scipy's linprog, ezdxf).

Flatness is the width of the thinnest zone between two parallel planes that holds every corner
of a face (the minimum zone). Here it is a Chebyshev plane fit: in a frame whose z is the
current normal, the linear program

    minimise t  subject to  -t <= z_i - (a x_i + b y_i + c) <= t

gives the thinnest zone measured along z, 2t, and the zone's normal (-a, -b, 1); its true
width is 2t / |(-a, -b, 1)|. The frame is turned to that normal and the program solved again
until the normal stops moving (the zone measured along its own normal is the minimum). The
start is the least-squares plane (numpy's SVD).

    check_flatness.py PANELS REPORT.json   every panel of an OBJ or DXF against lamina audit's
                                           report, to --rel (1e-6) of the panel's size
    check_flatness.py --random DIR LAMINA  random warped n-gons (4 to 9 corners) written to
                                           DIR/ngons.obj, audited by lamina, compared
    check_flatness.py --same A.json B.json ... reports of the same panels from different files:
                                           the same figures, panel by panel, to --rel (a DXF
                                           in inches rounds each coordinate once more)
    check_flatness.py --rules RULES.json PANELS REPORT.json [CSV]
                                           tolerance classes: each panel's class, tolerance
                                           and verdict recomputed from the rule file (first
                                           matching rule by layer, group and size, else the
                                           default; tolerance mm + relative x size, size the
                                           largest corner-to-corner distance), against the
                                           report and, row by row, its CSV
    check_flatness.py --quads OBJ [SUMMARY.json]
                                           a large OBJ of quads only (`v x y z`, `f a b c d`),
                                           vectorised: each quad's flatness is the least of its
                                           tetrahedron's four heights and three opposite-edge
                                           distances; the largest against lamina audit's
                                           `--json` summary (the benchmark's peer)

Panels are read here: OBJ `v`/`f` records (n-gons kept whole, `o`/`g` names as groups), DXF
3DFACE entities, polyface meshes and MESH entities through ezdxf (with their layers), a lamina
axes file (one quad per edge: p_a, p_b, p_b + h_b d_b, p_a + h_a d_a) and a lamina plates file
(each outline through its 4 x 4 placement matrix, the assembly group as group). Faces with fewer
than 4 distinct corners are skipped, as lamina skips them.
"""
import csv
import fnmatch
import argparse
import json
import os
import subprocess
import sys

import numpy as np
from scipy.optimize import linprog


def fail(msg):
    print(f"check_flatness: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


class Panel:
    def __init__(self, corners, layer=None, group=None):
        self.corners = np.array(corners, dtype=float)
        self.layer, self.group = layer, group


def read_obj(path):
    verts, faces, group = [], [], None
    for line in open(path, encoding="utf-8", errors="replace"):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            verts.append([float(x) for x in parts[1:4]])
        elif parts[0] in ("o", "g"):
            group = line.strip()[1:].strip() or None
        elif parts[0] == "f":
            idx = [int(tok.split("/")[0]) for tok in parts[1:]]
            faces.append(Panel([verts[i - 1] if i > 0 else verts[i] for i in idx], group=group))
    return faces


def read_lamina_json(path):
    data = json.load(open(path))
    if data.get("format") == "lamina-axes":
        nodes = data["nodes"]
        out = []
        for e in data["edges"]:
            a, b = nodes[e["a"]], nodes[e["b"]]
            pa, pb = np.array(a["p"]), np.array(b["p"])
            out.append(Panel([pa, pb, pb + b["height"] * np.array(b["axis"]),
                              pa + a["height"] * np.array(a["axis"])]))
        return out
    if data.get("format") == "lamina-plates":
        out = []
        for plate in data["plates"]:
            m = np.array(plate["matrix"], dtype=float)
            xy = np.array(plate["outline"], dtype=float)
            local = np.column_stack([xy, np.zeros(len(xy)), np.ones(len(xy))])
            out.append(Panel((local @ m.T)[:, :3], group=str(plate["group"])))
        return out
    fail(f"{path}: not a lamina axes or plates file")


def read_dxf(path):
    import ezdxf

    doc = ezdxf.readfile(path)
    # millimetres per drawing unit, by $INSUNITS (inches, feet, mm, cm, m; unset: mm)
    scale = {1: 25.4, 2: 304.8, 4: 1.0, 5: 10.0, 6: 1000.0}.get(doc.header.get("$INSUNITS", 0), 1.0)
    out = []
    for e in doc.modelspace():
        kind, layer = e.dxftype(), e.dxf.layer
        if kind == "3DFACE":
            c = [np.array(e.dxf.get(f"vtx{k}")) for k in range(4)]
            if np.array_equal(c[3], c[2]):
                c = c[:3]
            out.append(Panel(c, layer))
        elif kind == "POLYLINE" and e.is_poly_face_mesh:
            for face in e.faces():
                # ezdxf yields the face's vertices followed by the face record itself.
                out.append(Panel([list(v.dxf.location) for v in face[:-1]], layer))
        elif kind == "MESH":
            v = [list(p) for p in e.vertices]
            for f in e.faces:
                out.append(Panel([v[i] for i in f], layer))
    for p in out:
        p.corners *= scale
    return out


def distinct(p):
    size = max(np.linalg.norm(p - p[0], axis=1).max(), np.finfo(float).tiny)
    keep = []
    for q in p:
        if all(np.linalg.norm(q - k) > 1e-9 * size for k in keep):
            keep.append(q)
    return len(keep)


def frame(normal):
    n = normal / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(n, u), n])


def flatness(p):
    """The minimum-zone width of the points p (n x 3) and its normal."""
    c = p.mean(axis=0)
    q = p - c
    normal = np.linalg.svd(q)[2][-1]
    width = None
    for _ in range(50):
        r = frame(normal)
        local = q @ r.T
        x, y, z = local[:, 0], local[:, 1], local[:, 2]
        ones = np.ones_like(x)
        # variables a, b, c, t; rows: z - (ax + by + c) <= t and (ax + by + c) - z <= t
        a_ub = np.vstack([np.column_stack([-x, -y, -ones, -ones]),
                          np.column_stack([x, y, ones, -ones])])
        b_ub = np.concatenate([-z, z])
        res = linprog([0, 0, 0, 1], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * 4,
                      method="highs")
        if res.status != 0:
            fail(f"linprog: {res.message}")
        a, b, _, t = res.x
        local_normal = np.array([-a, -b, 1.0])
        width = 2 * t / np.linalg.norm(local_normal)
        new = r.T @ (local_normal / np.linalg.norm(local_normal))
        moved = np.linalg.norm(np.cross(new, normal))
        normal = new
        if moved < 1e-15:
            break
    extent = q @ normal
    return extent.max() - extent.min(), normal


def read_panels(path):
    """The panels of 4 or more distinct corners."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        read = read_obj(path)
    elif ext == ".dxf":
        read = read_dxf(path)
    elif ext == ".json":
        read = read_lamina_json(path)
    else:
        fail(f"{path}: give .obj, .dxf or lamina .json panels")
    return [p for p in read if distinct(p.corners) >= 4]


def compare(panels_path, report_path, rel):
    panels = [p.corners for p in read_panels(panels_path)]
    report = json.load(open(report_path))
    rows = report["panels"]
    if len(rows) != len(panels):
        fail(f"{report_path} has {len(rows)} panels, {panels_path} {len(panels)} of 4+ corners")
    if report["summary"].get("metric") is None:
        fail(f"{report_path} names no metric")
    worst, worst_k, largest, worst_own = 0.0, -1, 0.0, 0.0
    for k, (p, row) in enumerate(zip(panels, rows)):
        w, n = flatness(p)
        size = np.linalg.norm(p.max(axis=0) - p.min(axis=0))
        d = abs(w - row["flatness"]) / size
        if d > worst:
            worst, worst_k = d, k
        if w > 1e-6 * size:
            worst_own = max(worst_own, abs(w - row["flatness"]) / w)
        largest = max(largest, w)
        # The normal: the zone's, up to sign where the zone is not unique (a flat panel has
        # one normal; a warped quad's zone is unique).
        ln = np.array(row["normal"])
        if w > 1e-9 * size and abs(abs(ln @ n) - 1.0) > 1e-6:
            fail(f"panel {k}: lamina's normal {ln} is not the zone's {n}")
    print(f"check_flatness: {panels_path}: {len(panels)} panels, largest flatness {largest:.9g} mm, "
          f"worst difference from lamina {worst:.2e} of the panel's size (panel {worst_k}), "
          f"{worst_own:.2e} of the flatness itself (panels flatter than 1e-6 of their size aside)")
    if worst > rel or worst_own > rel:
        fail(f"{panels_path}: flatness differs from lamina's by {worst:.2e} of a panel's size")


def random_ngons(out, lamina, rel):
    rng = np.random.default_rng(2026)
    lines, count = [], 0
    faces = []
    for k in range(300):
        n = int(rng.integers(4, 10))
        t = np.sort(rng.uniform(0, 2 * np.pi, n))
        r = rng.uniform(50, 400)
        pts = np.column_stack([r * np.cos(t) * rng.uniform(0.5, 1.5), r * np.sin(t),
                               rng.normal(0, rng.choice([1e-4, 0.01, 1.0, 5.0]), n)])
        # a random pose, far from the origin as real coordinates are
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        pts = pts @ q.T + rng.uniform(-5e4, 5e4, 3)
        idx = []
        for p in pts:
            lines.append("v " + " ".join(repr(float(x)) for x in p))
            count += 1
            idx.append(count)
        faces.append("f " + " ".join(map(str, idx)))
    path = os.path.join(out, "ngons.obj")
    with open(path, "w") as f:
        f.write("\n".join(lines + faces) + "\n")
    report = os.path.join(out, "ngons.report.json")
    p = subprocess.run([lamina, "audit", path, "--tolerance", "1", "--report", report],
                       capture_output=True, text=True)
    if p.returncode not in (0, 1):
        fail(f"lamina audit exit {p.returncode}: {(p.stdout + p.stderr).strip()[:300]}")
    compare(path, report, rel)


def rules_check(rules_path, panels_path, report_path, csv_path):
    rules = json.load(open(rules_path))
    default = rules.get("default")
    panels = read_panels(panels_path)
    report = json.load(open(report_path))
    rows = report["panels"]
    metric = {"flatness": "flatness", "best-fit": "best_fit", "corner": "deviation"}[
        report["summary"]["metric"]]
    if len(rows) != len(panels):
        fail(f"{report_path}: {len(rows)} panels, {panels_path} {len(panels)}")

    def matches(rule, p, size):
        for key, name in (("layer", p.layer), ("group", p.group)):
            if key in rule and (name is None or not fnmatch.fnmatchcase(name.lower(), rule[key].lower())):
                return False
        return rule.get("min_size", 0) <= size <= rule.get("max_size", float("inf"))

    counts = {}
    fails = 0
    for k, (p, row) in enumerate(zip(panels, rows)):
        c = p.corners
        size = max(np.linalg.norm(c[i] - c[j]) for i in range(len(c)) for j in range(i + 1, len(c)))
        name, allow = None, default
        for n, rule in enumerate(rules.get("rules", [])):
            if matches(rule, p, size):
                name, allow = rule.get("name") or f"rule {n + 1}", rule
                break
        if allow is None:
            fail(f"panel {k} matches no rule and there is no default")
        name = name or "default"
        tol = allow.get("mm", 0.0) + allow.get("relative", 0.0) * size
        ok = row[metric] <= tol
        if row.get("class") != name or abs(row["tolerance"] - tol) > 1e-9 * max(tol, 1.0) or row["pass"] != ok:
            fail(f"panel {k}: lamina says class {row.get('class')}, tolerance {row['tolerance']}, "
                 f"pass {row['pass']}; the rules give {name}, {tol}, {ok}")
        counts[name] = counts.get(name, 0) + 1
        fails += not ok
    s = report["summary"]
    if s["above_tolerance"] != fails or s["within_tolerance"] != (fails == 0):
        fail(f"summary: {s['above_tolerance']} above, the rules give {fails}")
    for c in s["classes"]:
        if c["panels"] != counts.get(c["name"], 0):
            fail(f"class {c['name']}: {c['panels']} panels, the rules give {counts.get(c['name'], 0)}")
    if csv_path:
        with open(csv_path, newline="") as f:
            table = list(csv.DictReader(f))
        if len(table) != len(rows):
            fail(f"{csv_path}: {len(table)} rows, the report {len(rows)} panels")
        for r, row in zip(table, rows):
            if (int(r["panel"]) != row["index"] or r["class"] != row.get("class", "")
                    or (r["pass"] == "pass") != row["pass"]
                    or abs(float(r["tolerance_mm"]) - row["tolerance"]) > 1e-12 * row["tolerance"]
                    or abs(float(r["flatness_mm"]) - row["flatness"]) > 1e-12 * max(row["flatness"], 1e-300)):
                fail(f"{csv_path}: row {r['panel']} disagrees with the report")
    print(f"check_flatness: {panels_path}: {len(rows)} panels in classes "
          f"{', '.join(f'{k} {v}' for k, v in sorted(counts.items()))}, {fails} above their "
          f"tolerance: lamina's classes, tolerances and verdicts agree")


def quads(path, summary_path, rel):
    lines = open(path).read().splitlines()
    v = np.array(" ".join(l[2:] for l in lines if l.startswith("v ")).split(), dtype=float)
    f = np.array(" ".join(l[2:] for l in lines if l.startswith("f ")).split(), dtype=np.int64)
    p = v.reshape(-1, 3)[f.reshape(-1, 4) - 1]
    normals = [np.cross(p[:, j] - p[:, i], p[:, k] - p[:, i])
               for i, j, k in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3))]
    normals += [np.cross(p[:, j] - p[:, i], p[:, l] - p[:, k])
                for i, j, k, l in ((0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2))]
    n = np.stack(normals, axis=1)
    length = np.linalg.norm(n, axis=2)
    size = np.linalg.norm(p.max(axis=1) - p.min(axis=1), axis=1)
    ok = length > 1e-12 * size[:, None] ** 2
    n = n / np.where(ok, length, 1.0)[:, :, None]
    t = np.einsum("nkj,nij->nki", n, p)
    width = np.where(ok, t.max(axis=2) - t.min(axis=2), np.inf).min(axis=1)
    largest = float(width.max())
    print(f"check_flatness: {path}: {len(width)} quads, largest flatness {largest:.9g} mm")
    if summary_path:
        theirs = json.load(open(summary_path))["max_flatness"]
        if abs(theirs - largest) > rel * max(largest, 1e-9):
            fail(f"lamina's largest flatness {theirs} differs from {largest}")
        print(f"check_flatness: lamina's largest flatness {theirs:.9g} mm agrees")


def same(reports, rel):
    first = json.load(open(reports[0]))["panels"]
    for other in reports[1:]:
        rows = json.load(open(other))["panels"]
        if len(rows) != len(first):
            fail(f"{other}: {len(rows)} panels, {reports[0]} {len(first)}")
        worst = 0.0
        for a, b in zip(first, rows):
            for key in ("flatness", "best_fit", "deviation"):
                worst = max(worst, abs(a[key] - b[key]) / max(abs(a[key]), 1e-9))
        print(f"check_flatness: {other}: {len(rows)} panels, figures within {worst:.1e} "
              f"(relative) of {reports[0]}")
        if worst > rel:
            fail(f"{other}: figures differ from {reports[0]} by {worst:.2e}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("panels", nargs="?")
    ap.add_argument("report", nargs="?")
    ap.add_argument("--rel", type=float, default=1e-6)
    ap.add_argument("--random", nargs=2, metavar=("DIR", "LAMINA"))
    ap.add_argument("--same", nargs="+")
    ap.add_argument("--rules", nargs="+", metavar="RULES PANELS REPORT [CSV]")
    ap.add_argument("--quads", nargs="+", metavar="OBJ [SUMMARY]")
    args = ap.parse_args()
    if args.random:
        os.makedirs(args.random[0], exist_ok=True)
        random_ngons(*args.random, args.rel)
    elif args.same:
        same(args.same, args.rel)
    elif args.quads:
        quads(args.quads[0], args.quads[1] if len(args.quads) > 1 else None, args.rel)
    elif args.rules:
        if len(args.rules) not in (3, 4):
            ap.error("--rules RULES PANELS REPORT [CSV]")
        rules_check(*args.rules[:3], args.rules[3] if len(args.rules) == 4 else None)
    elif args.panels and args.report:
        compare(args.panels, args.report, args.rel)
    else:
        ap.error("give PANELS REPORT, --random DIR LAMINA or --same REPORTS")


if __name__ == "__main__":
    main()
