"""Checks the NC programs `lamina nest --nc gcode|essi` writes beside each sheet DXF, against the
DXF (read with ezdxf) and nest.json, sharing no code with lamina.

Each program is run through a parser of this file's own: G-code words by gcodeparser (PyPI,
0.3.0; parenthesised RS-274 comments are stripped first, as gcodeparser would read the words
inside them), modal G0/G1/G2/G3 in absolute millimetres with I/J arc centres from the arc's
start; ESSI (ISO 6582) as incremental moves in the given unit, `+dx+dy` lines and
`+dx+dy+i+j±` arcs (a sign alone is zero), 5/6 rapid, 7/8 torch, 9/10 marker, 3…4 a comment.
Then:

- every move with the torch or marker on is a feed move (G1/G2/G3, or an ESSI move between 7/8
  or 9/10) and every rapid (G0, or between 5/6) has both off; no rapid or feed is left out;
- the marker runs come first and are the DXF's ETCH polylines, one for one in file order (either
  direction, within 0.002 mm, or the ESSI unit);
- the torch runs are the DXF's cut contours one for one in file order (CUT_INNER, CUT_OUTER and
  micro-joint pieces): after leaving out a lead-in (its first straight move) and lead-out (its
  last) that lie in the scrap (outside the part grown by half the kerf less the tolerance, or
  inside the hole shrunk so) and are no longer than the DXF's lead lines allow, every point of
  the run (sampled every 0.05 mm and at every vertex, arcs every 0.01 mm) lies half the kerf
  from the contour within 0.01 mm on its scrap side, and every point of the contour (sampled so) lies half the kerf from the run within 0.01 mm: the run is the contour offset by
  half the kerf, corners included;
- common lines (nest.json's `common_lines`): exactly two closed outer contours lie half the
  kerf off the whole line (sampled every 0.05 mm); the earlier one's run passes along the line
  (within 0.01 mm), the later one's run starts and ends on it, and that run with the line
  follows its whole contour as above;
- inner contours are cut before the outer contour that holds them;
- the rapid travel (from the origin, move by move) equals nest.json's `rapid_mm`, within the
  rounding of the coordinates written;
- with `cut_order` travel, it is at most a nearest-neighbour tour's over the same runs: markings
  by nearest neighbour from the origin (each polyline from whichever end is nearer), then parts
  by nearest neighbour (each entered at its first run's start, its runs as programmed; a common
  line's second part, cut straight after the first, with the first).
- Leads may be longer than the DXF's by what rounding to the ESSI unit adds (√2 units).
"""

import argparse
import json
import math
import re
import sys
from pathlib import Path

import ezdxf
import numpy as np
import shapely
from gcodeparser import parse_gcode_lines
from shapely.geometry import LineString, Polygon

TOL = 0.01


def fail(msg):
    print(f"check_nc: FAIL: {msg}")
    sys.exit(1)


def arc_points(start, end, centre, ccw, step=0.01):
    """Points along an arc from start to end about centre (start excluded)."""
    a0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a1 = math.atan2(end[1] - centre[1], end[0] - centre[0])
    r0 = math.dist(start, centre)
    r1 = math.dist(end, centre)
    if abs(r0 - r1) > 0.02:
        fail(f"an arc's start and end are {r0:.4f} and {r1:.4f} mm from its centre")
    sweep = a1 - a0
    if ccw and sweep <= 0:
        sweep += 2 * math.pi
    if not ccw and sweep >= 0:
        sweep -= 2 * math.pi
    n = max(2, int(abs(sweep) * r0 / step) + 1)
    pts = []
    for k in range(1, n + 1):
        t = k / n
        a = a0 + sweep * t
        r = r0 + (r1 - r0) * t
        pts.append((centre[0] + r * math.cos(a), centre[1] + r * math.sin(a)))
    pts[-1] = end
    return pts


class Program:
    """Runs (tool, points, first-move-is-line, last-move-is-line) and rapids in order."""

    def __init__(self):
        self.runs = []     # (tool, [points], moves) with moves a list of ("line"|"arc", pts)
        self.rapid = 0.0
        self.rapids = 0
        self.at = (0.0, 0.0)
        self.tool = None   # None, "torch" or "marker"
        self.current = None

    def on(self, tool, where):
        if self.tool is not None:
            fail(f"{where}: the {tool} comes on while the {self.tool} is on")
        self.tool = tool
        self.current = (tool, [self.at], [])

    def off(self, tool, where):
        if self.tool is None:
            return  # a redundant off (a program's safe ending) does nothing
        if self.tool != tool:
            fail(f"{where}: the {tool} goes off but it was not on")
        if not self.current[2]:
            fail(f"{where}: the {tool} came on and off without a move")
        self.runs.append(self.current)
        self.tool = None
        self.current = None

    def rapid_to(self, p, where):
        if self.tool is not None:
            fail(f"{where}: a rapid with the {self.tool} on")
        self.rapid += math.dist(self.at, p)
        self.rapids += 1
        self.at = p

    def feed_to(self, p, where, centre=None, ccw=None):
        if self.tool is None:
            fail(f"{where}: a feed move with the torch and marker off")
        if centre is None:
            pts = [p]
            kind = "line"
        else:
            pts = arc_points(self.at, p, centre, ccw)
            kind = "arc"
        self.current[1].extend(pts)
        self.current[2].append((kind, [self.at] + pts))
        self.at = p


def read_gcode(path, on, off, mark_on, mark_off):
    text = Path(path).read_text()
    prog = Program()
    def norm(c):
        return " ".join(c.split())
    on_codes = {norm(on): "torch", norm(mark_on): "marker"}
    if len(on_codes) < 2:
        fail("the torch and the marker need different on codes")
    off_codes = {}
    for code, tool in ((off, "torch"), (mark_off, "marker")):
        off_codes.setdefault(norm(code), set()).add(tool)
    mode = None
    for n, raw in enumerate(text.splitlines(), 1):
        where = f"{path}:{n}"
        line = re.sub(r"\([^)]*\)", "", raw).strip()
        if not line:
            continue
        if norm(line) in on_codes:
            prog.on(on_codes[norm(line)], where)
            continue
        if norm(line) in off_codes:
            tools = off_codes[norm(line)]
            prog.off(prog.tool if prog.tool in tools else sorted(tools)[0], where)
            continue
        for g in parse_gcode_lines(line, include_comments=False):
            letter, number = g.command
            p = g.params
            if letter == "G" and number in (0, 1, 2, 3):
                mode = number
            elif letter == "G" and number in (20, 91):
                fail(f"{where}: G{number} (inches or incremental) is not what lamina writes")
            elif letter == "G" and number in (4, 17, 21, 40, 64, 90):
                continue
            elif letter == "M" and number in (2, 30, 52):
                continue
            elif letter in ("X", "Y"):
                pass
            else:
                fail(f"{where}: unexpected {letter}{number} (is the post's on/off code given?)")
            if "X" not in p and "Y" not in p:
                continue
            target = (float(p.get("X", prog.at[0])), float(p.get("Y", prog.at[1])))
            if mode == 0:
                prog.rapid_to(target, where)
            elif mode == 1:
                prog.feed_to(target, where)
            elif mode in (2, 3):
                centre = (prog.at[0] + float(p.get("I", 0)), prog.at[1] + float(p.get("J", 0)))
                prog.feed_to(target, where, centre, mode == 3)
            else:
                fail(f"{where}: a move before any G0/G1/G2/G3")
    if prog.tool is not None:
        fail(f"{path}: the program ends with the {prog.tool} on")
    return prog


def read_essi(path, unit):
    lines = Path(path).read_text().splitlines()
    if not lines or lines[0].strip() != "%":
        fail(f"{path}: an ESSI program starts with %")
    prog = Program()
    rapid = False
    comment = False
    ended = False
    at = (0, 0)  # integer units
    for n, raw in enumerate(lines[1:], 2):
        where = f"{path}:{n}"
        line = raw.strip()
        if ended and line:
            fail(f"{where}: text after the end (0)")
        if comment:
            if line == "4":
                comment = False
            continue
        if line == "3":
            comment = True
            continue
        if re.fullmatch(r"\d+", line):
            code = int(line)
            if code == 5:
                rapid = True
            elif code == 6:
                rapid = False
            elif code in (7, 9):
                prog.on("torch" if code == 7 else "marker", where)
            elif code in (8, 10):
                prog.off("torch" if code == 8 else "marker", where)
            elif code == 0:
                ended = True
            else:
                fail(f"{where}: unexpected ESSI code {code}")
            continue
        tokens = re.findall(r"[+-]\d*", line)
        if "".join(tokens) != line:
            fail(f"{where}: not an ESSI move: {line!r}")
        vals = [int(t) if len(t) > 1 else 0 for t in tokens]
        if len(tokens) == 2:
            at = (at[0] + vals[0], at[1] + vals[1])
            p = (at[0] * unit, at[1] * unit)
            if rapid:
                prog.rapid_to(p, where)
            else:
                prog.feed_to(p, where)
        elif len(tokens) == 5 and len(tokens[4]) == 1:
            if rapid:
                fail(f"{where}: an arc as a rapid")
            centre = ((at[0] + vals[2]) * unit, (at[1] + vals[3]) * unit)
            at = (at[0] + vals[0], at[1] + vals[1])
            prog.feed_to((at[0] * unit, at[1] * unit), where, centre, tokens[4] == "+")
        else:
            fail(f"{where}: {len(tokens)} values: neither a line (2) nor an arc (5)")
    if not ended:
        fail(f"{path}: no end code 0")
    if prog.tool is not None:
        fail(f"{path}: the program ends with the {prog.tool} on")
    return prog


def dxf_paths(path):
    doc = ezdxf.readfile(path)
    etch, cuts, leads = [], [], []
    for e in doc.modelspace():
        layer = e.dxf.layer
        if e.dxftype() != "LWPOLYLINE":
            continue
        pts = [(x, y) for x, y, *_ in e.get_points()]
        if layer == "ETCH":
            etch.append(pts)
        elif layer in ("CUT_INNER", "CUT_OUTER"):
            cuts.append((layer, pts, bool(e.closed)))
        elif layer == "LEAD":
            leads.append(pts)
    return etch, cuts, leads


def samples(points, step=0.25):
    """Every vertex and points at most `step` apart along the polyline."""
    p = np.asarray(points, dtype=float)
    if len(p) < 2:
        return p
    seg = p[1:] - p[:-1]
    n = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / step).astype(int))
    idx = np.repeat(np.arange(len(seg)), n)
    k = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + 1
    t = k / np.repeat(n, n)
    return np.vstack([p[:1], p[idx] + seg[idx] * t[:, None]])


def check_run(where, run, layer, pts, closed, r, lead_max, part_poly, shared=None):
    """The run reproduces the contour offset by r on its scrap side (leads aside); with
    `shared` (a common line another run cuts), the run starts and ends on that line and the two
    together follow the contour. Returns the run's path as a LineString."""
    tool, points, moves = run
    contour = LineString(pts + [pts[0]] if closed else pts)
    # The scrap side: outside the part (outer), inside the hole (inner).
    if layer == "CUT_OUTER":
        body = part_poly
    else:
        body = Polygon(pts)
    mids = list(moves)
    lead_in = lead_out = None

    def off_contour(p):
        d = contour.distance(shapely.Point(p))
        return abs(d - r) > TOL

    if mids and mids[0][0] == "line" and off_contour(mids[0][1][0]):
        lead_in = mids.pop(0)
    if mids and mids[-1][0] == "line" and off_contour(mids[-1][1][-1]):
        lead_out = mids.pop()
    for name, lead in (("lead-in", lead_in), ("lead-out", lead_out)):
        if lead is None:
            continue
        a, b = lead[1][0], lead[1][-1]
        if math.dist(a, b) > lead_max + TOL:
            fail(f"{where}: a {name} of {math.dist(a, b):.3f} mm, longer than the DXF's leads "
                 f"({lead_max:.3f} mm)")
        line = LineString([a, b])
        if layer == "CUT_OUTER":
            if line.distance(body) < r - TOL:
                fail(f"{where}: the {name} comes {line.distance(body):.4f} mm from the part "
                     f"(half the kerf is {r})")
        else:
            shrunk = body.buffer(-(r - TOL), join_style="mitre") if r > TOL else body
            if not shrunk.buffer(1e-9).contains(line):
                fail(f"{where}: the {name} leaves the hole shrunk by half the kerf")
    if not mids:
        fail(f"{where}: nothing but leads")
    path_pts = [mids[0][1][0]] + [q for _, seg in mids for q in seg[1:]]
    run_line = LineString(path_pts)
    s = samples(path_pts)
    d = shapely.distance(contour, shapely.points(s))
    k = int(np.argmax(np.abs(d - r)))
    if abs(d[k] - r) > TOL:
        fail(f"{where}: the path at ({s[k][0]:.3f}, {s[k][1]:.3f}) is {d[k]:.4f} mm from the "
             f"contour, not half the kerf {r} ± {TOL}")
    if r > TOL:
        inside = shapely.contains(body, shapely.points(s))
        wrong = inside if layer == "CUT_OUTER" else ~inside
        if wrong.any():
            k = int(np.argmax(wrong))
            fail(f"{where}: the path at ({s[k][0]:.3f}, {s[k][1]:.3f}) runs on the part's side")
    c = samples(pts + [pts[0]] if closed else pts)
    cut = run_line
    if shared is not None:
        for end in (path_pts[0], path_pts[-1]):
            if shared.distance(shapely.Point(end)) > TOL:
                fail(f"{where}: the cut after a common line starts or ends at ({end[0]:.3f}, "
                     f"{end[1]:.3f}), {shared.distance(shapely.Point(end)):.4f} mm off the line")
        cut = shapely.union(run_line, shared)
    d = shapely.distance(cut, shapely.points(c))
    k = int(np.argmax(np.abs(d - r)))
    if abs(d[k] - r) > TOL:
        fail(f"{where}: the contour at ({c[k][0]:.3f}, {c[k][1]:.3f}) is {d[k]:.4f} mm from the "
             f"path, not half the kerf {r} ± {TOL}: the path does not follow the whole contour")
    return run_line


def nn_travel(start, items):
    """Nearest-neighbour travel over items (entry, exit, reversible): from wherever the last
    one ended to the nearest entry (or exit, for a reversible item) left; ties to the first."""
    if not items:
        return 0.0, start
    entry = np.array([e for e, _, _ in items], dtype=float)
    exit_ = np.array([x for _, x, _ in items], dtype=float)
    rev = np.array([r for _, _, r in items])
    left = np.ones(len(items), dtype=bool)
    at = np.array(start, dtype=float)
    total = 0.0
    for _ in range(len(items)):
        de = np.where(left, np.hypot(*(entry - at).T), np.inf)
        dx = np.where(left & rev, np.hypot(*(exit_ - at).T), np.inf)
        i, j = int(np.argmin(de)), int(np.argmin(dx))
        if dx[j] < de[i]:
            total += dx[j]
            at = entry[j]
            left[j] = False
        else:
            total += de[i]
            at = exit_[i]
            left[i] = False
    return total, tuple(at)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("folder")
    ap.add_argument("--format", choices=["gcode", "essi"], default="gcode")
    ap.add_argument("--on", default="M3 S1")
    ap.add_argument("--off", default="M5")
    ap.add_argument("--mark-on", default="M7")
    ap.add_argument("--mark-off", default="M9")
    ap.add_argument("--unit", type=float, default=0.01, help="ESSI unit, mm")
    ap.add_argument("--table", action="store_true",
                    help="print each sheet's rapid travel against the nearest-neighbour tour")
    args = ap.parse_args()
    folder = Path(args.folder)
    nest = json.load(open(folder / "nest.json"))
    r = 0.5 * nest["kerf_mm"]
    ext = "ngc" if args.format == "gcode" else "esi"
    total_runs = 0
    worst_ratio = 0.0
    for s in nest["sheets"]:
        dxf = folder / s["file"]
        prog_path = dxf.with_suffix("." + ext)
        if not prog_path.exists():
            fail(f"{prog_path}: missing")
        if args.format == "gcode":
            prog = read_gcode(prog_path, args.on, args.off, args.mark_on, args.mark_off)
            rounding = 0.001
        else:
            prog = read_essi(prog_path, args.unit)
            rounding = 2 * args.unit
        etch, cuts, leads = dxf_paths(dxf)
        # The DXF's longest lead, and what rounding the program's coordinates can add to it:
        # each end moves at most half a unit each way.
        lead_max = max((math.dist(p[0], p[-1]) for p in leads), default=0.0)
        lead_max += math.sqrt(2) * args.unit if args.format == "essi" else 0.0
        marks = [run for run in prog.runs if run[0] == "marker"]
        torch = [run for run in prog.runs if run[0] == "torch"]
        first_cut = next((k for k, run in enumerate(prog.runs) if run[0] == "torch"), len(prog.runs))
        if any(run[0] == "marker" for run in prog.runs[first_cut:]):
            fail(f"{prog_path}: marking after cutting began")
        if len(marks) != len(etch):
            fail(f"{prog_path}: {len(marks)} marker runs, the DXF etches {len(etch)} polylines")
        for k, (run, line) in enumerate(zip(marks, etch)):
            a = np.array(run[1])
            b = np.array(line)
            tol = max(0.002, args.unit) if args.format == "essi" else 0.002
            if a.shape != b.shape or (np.abs(a - b).max() > tol and np.abs(a - b[::-1]).max() > tol):
                fail(f"{prog_path}: marker run {k} is not the DXF's etched polyline {k}")
        if len(torch) != len(cuts):
            fail(f"{prog_path}: {len(torch)} torch runs, the DXF has {len(cuts)} cut contours")
        # Parts: an outer contour (closed, or pieces until they close) holds the holes before it.
        outer_of = []
        part_poly = None
        k = 0
        while k < len(cuts):
            layer, pts, closed = cuts[k]
            if layer == "CUT_OUTER" and not closed:
                j = k
                ring = []
                while j < len(cuts) and cuts[j][0] == "CUT_OUTER" and not cuts[j][2]:
                    ring.extend(cuts[j][1])
                    j += 1
                    if math.dist(cuts[j - 1][1][-1], cuts[k][1][0]) < 1e-6:
                        break
                outer_of.extend([(k, j, Polygon(ring))] * (j - k))
                k = j
            else:
                outer_of.append((k, k + 1, Polygon(pts) if layer == "CUT_OUTER" else None))
                k += 1
        # Common lines (nest.json): the two closed outer contours half the kerf off the whole
        # line; the earlier one's run cuts the line, the later one's runs from it round to it.
        shared = {}
        for c in s.get("common_lines", []):
            line = LineString([c["from"], c["to"]])
            on_line = shapely.points(samples([c["from"], c["to"]], 0.05))
            near = [k for k, (layer, pts, closed) in enumerate(cuts)
                    if layer == "CUT_OUTER" and closed
                    and np.abs(shapely.distance(LineString(pts + [pts[0]]), on_line) - r).max() <= TOL]
            if len(near) != 2:
                fail(f"{prog_path}: common line {c['parts']} lies half the kerf off "
                     f"{len(near)} outer contours, not 2")
            shared[near[1]] = (line, on_line, near[0])
        paths = {}
        for k, (run, (layer, pts, closed)) in enumerate(zip(torch, cuts)):
            poly = outer_of[k][2]
            paths[k] = check_run(f"{prog_path} torch run {k} ({layer})", run, layer, pts, closed,
                                 r, lead_max, poly, shared[k][0] if k in shared else None)
        for k, (line, on_line, first) in shared.items():
            d = shapely.distance(paths[first], on_line)
            if d.max() > TOL:
                fail(f"{prog_path}: torch run {first} passes {d.max():.4f} mm off the common line "
                     f"that run {k} starts from")
        # Inner before outer: every hole inside an outer contour is cut before it.
        holes = [(k, Polygon(pts)) for k, (layer, pts, _) in enumerate(cuts) if layer == "CUT_INNER"]
        for k, (layer, _, _) in enumerate(cuts):
            if layer != "CUT_OUTER" or outer_of[k][0] != k:
                continue
            poly = outer_of[k][2]
            for h, hp in holes:
                if poly.contains(hp) and h > k:
                    fail(f"{prog_path}: a hole (run {h}) is cut after the outer contour (run {k}) that holds it")
        # Rapid travel as nest.json gives it.
        if abs(prog.rapid - s["rapid_mm"]) > rounding * max(prog.rapids, 1):
            fail(f"{prog_path}: rapid travel {prog.rapid:.3f} mm, nest.json says {s['rapid_mm']:.3f}")
        # No longer than a nearest-neighbour tour over the same runs.
        if nest["cut_order"] == "travel":
            items = [(run[1][0], run[1][-1], True) for run in marks]
            nn_marks, at = nn_travel((0.0, 0.0), items)
            # Parts: each hole's run grouped with the outer contour (or its pieces) that
            # follows; the travel between a group's own runs is the same in any tour. A common
            # line's second part, cut straight after its first, joins the first's group.
            groups, inside, pending, prev = [], 0.0, None, None
            for k, run in enumerate(torch):
                if pending is None:
                    pending = [run[1][0], None, k]
                else:
                    inside += math.dist(prev, run[1][0])
                pending[1] = run[1][-1]
                prev = run[1][-1]
                if cuts[k][0] == "CUT_OUTER" and outer_of[k][1] == k + 1:
                    if k in shared and groups and groups[-1][2] == shared[k][2]:
                        entry, exit_, _ = groups.pop()
                        inside += math.dist(exit_, pending[0])
                        pending[0] = entry
                    groups.append((pending[0], pending[1], k))
                    pending = None
            nn_parts, _ = nn_travel(at, [(e, x, False) for e, x, _ in groups])
            nn_total = nn_marks + nn_parts + inside
            worst_ratio = max(worst_ratio, prog.rapid / max(nn_total, 1e-9))
            if args.table:
                print(f"{s['file']}: {len(s['parts'])} parts, {len(marks)} etched polylines, "
                      f"rapid {prog.rapid / 1000:.1f} m, nearest neighbour {nn_total / 1000:.1f} m "
                      f"({100 * prog.rapid / nn_total:.0f} %)")
            if prog.rapid > nn_total + rounding * max(prog.rapids, 1):
                fail(f"{prog_path}: rapid travel {prog.rapid:.1f} mm, longer than a "
                     f"nearest-neighbour tour's {nn_total:.1f} mm")
        total_runs += len(prog.runs)
    print(f"{folder}: ok ({len(nest['sheets'])} {args.format} programs, {total_runs} runs, "
          f"kerf {nest['kerf_mm']} mm, rapid travel {sum(s['rapid_mm'] for s in nest['sheets']) / 1000:.1f} m"
          + (f", at most {100 * worst_ratio:.1f} % of nearest neighbour's" if worst_ratio else "")
          + ")")


if __name__ == "__main__":
    main()
