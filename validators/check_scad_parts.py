"""Rebuilds a sample of parts of an assembly.scad in OpenSCAD, each alone (imported from its cut
DXF, or cut out of its sheet's DXF by its clip polygon, extruded and placed by its matrix), and
compares each with the same part in lamina's assembly.obj (one object per plate): volume within
1e-4 (relative) and bounding box within 0.01 mm. Shares no code with lamina.

The whole assemblies (every part unioned by CGAL, minutes on one core) are rebuilt by
`scripts/bench scad`; a part alone renders in well under a second, and the sample covers the
thinnest and thickest plates, plates with bolt holes, a part from every DXF (every sheet of a cut plan), and
parts spread evenly over the file.

    check_scad_parts.py ASSEMBLY.scad ASSEMBLY.obj [--parts N]
"""
import os
import re
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import trimesh

TOLERANCE = 1e-4
BOX = 0.01


def read_obj_objects(path):
    """Each `o NAME` object of an OBJ as (vertices, faces)."""
    objects, name, verts, faces = {}, None, [], []
    offset = 0
    current = []
    for line in open(path, encoding="utf-8"):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "o":
            if name is not None:
                objects[name] = current
            name, current = parts[1], []
        elif parts[0] == "v":
            verts.append([float(x) for x in parts[1:4]])
        elif parts[0] == "f":
            current.append([int(t.split("/")[0]) - 1 for t in parts[1:4]])
    if name is not None:
        objects[name] = current
    verts = np.array(verts)
    out = {}
    for k, f in objects.items():
        f = np.array(f)
        used = np.unique(f)
        remap = {int(v): i for i, v in enumerate(used)}
        out[k] = (verts[used], np.vectorize(remap.get)(f))
    return out


def signed_volume(v, f):
    a, b, c = (v[f[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def main():
    args = sys.argv[1:]
    want_parts = 12
    if "--parts" in args:
        i = args.index("--parts")
        want_parts = int(args[i + 1])
        del args[i:i + 2]
    scad_path, obj_path = args
    folder = os.path.dirname(os.path.abspath(scad_path))
    lines = open(scad_path, encoding="utf-8").read().splitlines()
    header = [ln for ln in lines if not re.match(r"\s*(part|bolt|core)\(", ln)]
    parts = [(m.group(2), ln) for ln in lines
             if (m := re.match(r"\s*part\((.*)\);\s*//\s*(\S+)\s*$", ln))]
    if not parts:
        print(f"{scad_path}: no part lines")
        return 1
    objects = read_obj_objects(obj_path)
    # The sample: thinnest and thickest, a bolted ply if any, and the rest evenly spread.
    thickness = {pid: float(re.match(r'\s*part\("[^"]*",\s*([0-9.e+-]+)', ln).group(1))
                 for pid, ln in parts}
    order = sorted(thickness, key=lambda p: (thickness[p], p))
    picks = [order[0], order[-1]]
    bolted = [pid for pid, _ in parts if pid in objects and "-" in pid and
              len(objects[pid][1]) > 200]
    picks += bolted[:2]
    # One part from every file several parts are cut from (each sheet of a cut plan).
    of_file = {}
    for pid, ln in parts:
        of_file.setdefault(re.match(r'\s*part\("([^"]*)"', ln).group(1), []).append(pid)
    picks += [ids[0] for ids in of_file.values() if len(ids) > 1]
    sample = list(dict.fromkeys(picks))
    # The rest evenly over the file, up to the number asked for.
    rest = [pid for pid, _ in parts if pid not in set(sample)]
    room = max(0, want_parts - len(sample))
    if room and rest:
        step = max(1, len(rest) // room)
        sample += rest[::step][:room]
    line_of = dict(parts)
    problems = []

    identity = "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]"

    def run(pid, line, tag):
        with tempfile.TemporaryDirectory() as tmp:
            scad = os.path.join(folder, f".part-{pid}-{tag}.scad")
            with open(scad, "w", encoding="utf-8") as f:
                f.write("\n".join(header + [line]) + "\n")
            out = os.path.join(tmp, "part.stl")
            try:
                p = subprocess.run(["openscad", "-q", "-o", out, scad], cwd=folder,
                                   capture_output=True, text=True, timeout=120)
            finally:
                os.remove(scad)
            if p.returncode != 0 or not os.path.exists(out):
                raise RuntimeError(p.stderr.strip()[-400:])
            return trimesh.load(out, force="mesh", process=True)

    def render(pid):
        """The part placed (for its box) and in its own frame, the matrix left out (for its
        volume: STL's six digits at 800 mm from the origin would blur a 1.5 mm plate)."""
        line = line_of[pid]
        own = re.sub(r"\[\[[^\]]*\](?:, \[[^\]]*\]){3}\]", identity, line, count=1)
        try:
            return pid, (run(pid, line, "placed"), run(pid, own, "own")), None
        except RuntimeError as e:
            return pid, None, str(e)

    with ThreadPoolExecutor(max_workers=2) as pool:
        rendered = list(pool.map(render, sample))
    for pid, meshes, err in rendered:
        if meshes is None:
            problems.append(f"{pid}: OpenSCAD did not render it: {err}")
            continue
        mesh, own = meshes
        if pid not in objects:
            problems.append(f"{pid}: not an object of {obj_path}")
            continue
        v, f = objects[pid]
        ours = abs(signed_volume(v, f))
        theirs = abs(signed_volume(np.asarray(own.vertices), np.asarray(own.faces)))
        rel = abs(theirs - ours) / ours
        box = np.abs(np.vstack([mesh.bounds[0] - v.min(axis=0),
                                mesh.bounds[1] - v.max(axis=0)])).max()
        if rel > TOLERANCE:
            problems.append(f"{pid}: volume {theirs:.4f} mm³ against {ours:.4f} ({rel:.2e})")
        if box > BOX:
            problems.append(f"{pid}: bounding box {box:.4f} mm off")
        print(f"{pid}: {theirs:.3f} mm³ (lamina {ours:.3f}, {rel:.1e}), box within {box:.4f} mm")
    for p in problems:
        print(f"PROBLEM: {p}")
    print(f"{scad_path}: {len(sample)} of {len(parts)} parts rebuilt alone, "
          f"{len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
