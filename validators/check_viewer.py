"""A lamina viewer page opened in headless Chromium (Debian's `chromium`, over the DevTools
protocol) or Firefox ESR (Debian's `firefox-esr`, over WebDriver BiDi), both through
websocket-client, with the figures it shows checked against the source files read here without
lamina (json, numpy, shapely, ezdxf, Pillow, scipy).

    check_viewer.py PAGE.html [--select ID]... [--layer K]... [--axes AXES.json]
        [--plates PLATES.json] [--welds WELDS.json] [--sizing SIZING.json] [--nest NEST.json]
        [--sl1 JOB.sl1] [--network NET.json] [--max-mb MB] [--screenshot OUT.png]
        [--browser chromium|firefox] [--no-webgl] [--same-legend OTHER.html]

Every page: it opens from file:// with no network, sets `document.body.dataset.ready`, logs no
console error and throws no exception; a page with nothing to draw in 3D (sheets, print layers)
carries no three.js. Where it has a WebGL canvas, a screenshot of the canvas is not blank (its
pixels are not one colour: standard deviation and the share of pixels away from the
background), and a click where the page draws each selected object (its own `screenOf`: a point,
a line's middle, a face's centroid where nothing hides it) must pick that object and no other;
the cost of a hover pick is printed. Where the browser has no WebGL (Firefox headless, or
--no-webgl: Chromium with --disable-3d-apis), a 3D page must show its fallback: a notice naming
WebGL, a projection drawing the objects, the legends, and a search box that finds the first
selected id. --same-legend: every class the legends of both pages list has the same colour, in
the same order. --screenshot saves the window after the selections. `#select=ID` in the URL must
show ID in `#lamina-info` (or, for an id no object has, such as edge E5 on a page of panels, the
object one of whose figures names it) with figures that agree with the sources:

- a panel `Pk` (with --axes, or --panels for an audit of OBJ faces): the corner deviation, the
  distance of the fourth corner from the plane of the other three, recomputed with numpy; with
  --axes its tolerance and pass.
- a plate tag (with --plates): its gauge, group and area (outline less 64-gon holes, shapely);
  with --sizing its utilisation.
- a weld `Wn-k` (with --welds): node n's k-th pair's plates, root gap and dihedral angle.
- a sheet part (with --nest): the sheet nest.json puts it on, its rotation, and its box, the
  bounding box of the CUT_OUTER contour that starts at its placement's bbox_min (ezdxf).
- a node `Nk` (with --network): its position; a member `Ek` (with --network): its nodes and length.
- a member `Ek` (with --sizing, on the sizing report): its utilisation, governing check and gauge.

`#layer=K` (with --sl1; --first-island: the first layer where the images start an island, and
the page's island count against the images' total) must show layer K and the count of islands that start there, counted here
from the archive's images (grey >= 128, 8-connected regions with no lit pixel in the layer below).
The time from navigation to ready is printed (not held to a limit here: machines are noisy).
"""
import argparse
import base64
import configparser
import io
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
import zipfile

import numpy as np
from PIL import Image, ImageStat

import websocket


def fail(msg):
    print(f"check_viewer: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


class Browser:
    """Chromium headless with one page, spoken to over the DevTools protocol (with
    `no_webgl`, started with --disable-3d-apis: a machine without WebGL)."""

    def __init__(self, width=1280, height=800, no_webgl=False):
        exe = shutil.which("chromium") or shutil.which("chromium-browser")
        if not exe:
            fail("no chromium on PATH (scripts/setup installs Debian's chromium)")
        self.profile = tempfile.mkdtemp(prefix="lamina-chromium-")
        gl = ["--disable-3d-apis"] if no_webgl else ["--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
        self.proc = subprocess.Popen(
            [exe, "--headless=new", "--no-sandbox", "--disable-gpu-sandbox", "--disable-dev-shm-usage",
             *gl, "--remote-debugging-port=0", "--remote-allow-origins=*",
             f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
             "--no-first-run", "--no-default-browser-check", "--disable-extensions",
             "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        m = self.announced(r"DevTools listening on ws://127\.0\.0\.1:(\d+)/", 30)
        if m is None:
            self.close()
            fail("chromium did not start its DevTools endpoint")
        port = int(m.group(1))
        # Keep reading chromium's log so a full pipe never stalls it.
        threading.Thread(target=lambda: [None for _ in self.proc.stderr], daemon=True).start()
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
        page = next(t for t in targets if t["type"] == "page")
        self.ws = websocket.create_connection(page["webSocketDebuggerUrl"], timeout=60,
                                              suppress_origin=True)
        self.next_id = 0
        self.errors = []
        for domain in ("Page", "Runtime", "Log"):
            self.call(f"{domain}.enable")

    def call(self, method, **params):
        self.next_id += 1
        mine = self.next_id
        self.ws.send(json.dumps({"id": mine, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("id") == mine:
                if self.error_of(msg):
                    fail(f"{method}: {self.error_of(msg)}")
                return msg.get("result", {})
            self.event(msg)

    @staticmethod
    def error_of(msg):
        return msg.get("error")

    def event(self, msg):
        m, p = msg.get("method"), msg.get("params", {})
        if m == "Runtime.exceptionThrown":
            d = p["exceptionDetails"]
            self.errors.append(d.get("exception", {}).get("description") or d.get("text"))
        elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            self.errors.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p["args"]))
        elif m == "Log.entryAdded" and p["entry"].get("level") == "error":
            self.errors.append(f"{p['entry'].get('source')}: {p['entry'].get('text')}")

    def announced(self, pattern, seconds):
        """The browser's stderr read until a line matches `pattern` (its match), or None when
        it exits or `seconds` pass."""
        deadline = time.time() + seconds
        while time.time() < deadline:
            line = self.proc.stderr.readline()
            if not line:
                if self.proc.poll() is not None:
                    return None
                continue
            m = re.search(pattern, line)
            if m:
                return m
        return None

    def navigate(self, url):
        self.call("Page.navigate", url=url)

    def screenshot(self):
        return base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])

    def click(self, x, y):
        for kind in ("mousePressed", "mouseReleased"):
            self.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", clickCount=1)

    def eval(self, expr):
        r = self.call("Runtime.evaluate", expression=expr, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            fail(f"evaluating {expr!r}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait(self, expr, what, timeout=30):
        deadline = time.time() + timeout
        while time.time() < deadline:
            v = self.eval(expr)
            if v:
                return v
            time.sleep(0.05)
        fail(f"{what} did not happen within {timeout} s (errors: {self.errors})")

    def close(self):
        try:
            self.proc.kill()
            self.proc.wait(10)
        except Exception:
            pass
        shutil.rmtree(self.profile, ignore_errors=True)


class Firefox(Browser):
    """Firefox headless (Debian's firefox-esr) with one page, spoken to over WebDriver BiDi.
    Headless Firefox has no WebGL here: its pages show the viewer's fallback."""

    def __init__(self, width=1280, height=800):
        exe = shutil.which("firefox-esr") or shutil.which("firefox")
        if not exe:
            fail("no firefox-esr on PATH (scripts/setup installs Debian's firefox-esr)")
        self.profile = tempfile.mkdtemp(prefix="lamina-firefox-")
        self.proc = subprocess.Popen(
            [exe, "--headless", "--no-remote", "--profile", self.profile, "--remote-debugging-port", "0",
             "--width", str(width), "--height", str(height)],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        m = self.announced(r"WebDriver BiDi listening on (ws://\S+)", 60)
        if m is None:
            self.close()
            fail("firefox did not start WebDriver BiDi")
        url = m.group(1)
        threading.Thread(target=lambda: [None for _ in self.proc.stderr], daemon=True).start()
        self.ws = websocket.create_connection(url.rstrip("/") + "/session", timeout=60, suppress_origin=True)
        self.next_id = 0
        self.errors = []
        self.call("session.new", capabilities={})
        self.call("session.subscribe", events=["log.entryAdded"])
        self.context = self.call("browsingContext.getTree")["contexts"][0]["context"]
        self.call("browsingContext.setViewport", context=self.context,
                  viewport={"width": width, "height": height})

    @staticmethod
    def error_of(msg):
        return msg.get("type") == "error" and f"{msg.get('error')}: {msg.get('message')}"

    def event(self, msg):
        if msg.get("method") == "log.entryAdded" and msg["params"].get("level") == "error":
            self.errors.append(msg["params"].get("text"))

    def navigate(self, url):
        self.call("browsingContext.navigate", context=self.context, url=url, wait="complete")

    def screenshot(self):
        return base64.b64decode(self.call("browsingContext.captureScreenshot", context=self.context)["data"])

    def click(self, x, y):
        self.call("input.performActions", context=self.context, actions=[{
            "type": "pointer", "id": "mouse", "actions": [
                {"type": "pointerMove", "x": int(round(x)), "y": int(round(y))},
                {"type": "pointerDown", "button": 0}, {"type": "pointerUp", "button": 0}]}])

    def eval(self, expr):
        r = self.call("script.evaluate", expression=expr, target={"context": self.context},
                      awaitPromise=True, resultOwnership="none")
        if r.get("type") == "exception":
            fail(f"evaluating {expr!r}: {r.get('exceptionDetails', {}).get('text')}")
        return bidi_value(r["result"])


def bidi_value(v):
    """A WebDriver BiDi remote value as Python."""
    t = v.get("type")
    if t in ("undefined", "null"):
        return None
    if t == "number":
        return {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf, "-0": -0.0}.get(v["value"], v["value"])
    if t in ("string", "boolean"):
        return v["value"]
    if t == "array":
        return [bidi_value(x) for x in v.get("value", [])]
    if t == "object":
        return {k if isinstance(k, str) else bidi_value(k): bidi_value(x) for k, x in v.get("value", [])}
    return v.get("value")


def number(text):
    m = re.search(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", text)
    if not m:
        fail(f"no number in {text!r}")
    return float(m.group(0))


def info(b):
    return b.eval("""(() => {
        const i = document.getElementById('lamina-info');
        const rows = {};
        for (const tr of i.querySelectorAll('tr')) rows[tr.cells[0].textContent] = tr.cells[1].textContent;
        return {id: (i.querySelector('h3') || {}).textContent, sub: (i.querySelector('.lv-sub') || {}).textContent,
                selected: i.dataset.selected, rows, text: i.innerText};
    })()""")


def close_to(name, shown, want, tol):
    if not abs(shown - want) <= tol:
        fail(f"{name}: the page shows {shown}, the source gives {want} (tolerance {tol})")


def obj_quads(path):
    verts, faces = [], []
    for line in open(path):
        t = line.split()
        if t and t[0] == "v":
            verts.append([float(x) for x in t[1:4]])
        elif t and t[0] == "f":
            faces.append([int(x.split("/")[0]) - 1 for x in t[1:]])
    return [[np.array(verts[i]) for i in f] for f in faces]


def check_panel(ident, rows, axes, quads=None):
    k = int(ident[1:])
    if quads is not None:
        q = quads[k]
        tol = None
    else:
        nodes, edges = axes["nodes"], axes["edges"]
        e = edges[k]
        p = [np.array(nodes[i]["p"]) for i in (e["a"], e["b"])]
        d = [np.array(nodes[i]["axis"]) * nodes[i]["height"] for i in (e["a"], e["b"])]
        q = [p[0], p[1], p[1] + d[1], p[0] + d[0]]
        tol = axes["summary"]["tolerance"]
    n = np.cross(q[1] - q[0], q[3] - q[0])
    dev = abs(np.dot(q[2] - q[0], n / np.linalg.norm(n)))
    held = next((v for key, v in rows.items() if key.startswith("corner")), None)
    if held is None:
        fail(f"{ident}: no corner deviation among {list(rows)}")
    close_to(f"{ident} corner deviation", number(held), dev, 6e-7)
    if tol is None:
        return f"{ident} corner deviation {dev:.6f} mm"
    close_to(f"{ident} tolerance", number(rows["tolerance"]), tol, 1e-9)
    want = "yes" if dev <= tol else "no"
    if rows.get("within tolerance") != want and abs(dev - tol) > 1e-9:
        fail(f"{ident}: shown as within tolerance = {rows.get('within tolerance')}, {dev} against {tol}")
    return f"{ident} deviation {dev:.6f} mm"


def check_plate(ident, rows, plates, sizing):
    from shapely.geometry import Polygon
    doc = plates
    p = next(p for p in doc["plates"] if p["id"] == ident)
    close_to(f"{ident} gauge", number(rows["gauge"]), p["thickness"], 5e-4)
    if int(number(rows["group"])) != p["group"]:
        fail(f"{ident}: group {rows['group']}, plates.json says {p['group']}")
    area = Polygon(p["outline"]).area
    if p.get("holes"):
        r = p["bolt"]["hole_diameter"] / 2
        n = doc.get("hole_segments", 64)
        area -= len(p["holes"]) * 0.5 * n * r * r * math.sin(2 * math.pi / n)
    close_to(f"{ident} area", number(rows["area"]), area, 0.51)
    said = f"{ident} gauge {p['thickness']} mm, area {area:.0f} mm²"
    if sizing is not None:
        u = sizing["edges"][p["edge"]]["utilisation"]
        close_to(f"{ident} utilisation", number(rows["utilisation"]), u, 5e-4)
        said += f", utilisation {u:.3f}"
    return said


def check_weld(ident, rows, welds):
    node, k = (int(v) for v in ident[1:].split("-"))
    n = next(n for n in welds["nodes"] if n["node"] == node)
    pair = n["pairs"][k - 1]
    shown = rows["plates"].replace(" ", "").split("/")
    if shown != pair["plates"]:
        fail(f"{ident}: plates {shown}, welds.json says {pair['plates']}")
    close_to(f"{ident} root gap", number(rows["root gap"]), pair["root_gap_mm"], 5e-4)
    close_to(f"{ident} dihedral", number(rows["dihedral"]), pair["dihedral_deg"], 5e-3)
    return f"{ident} gap {pair['root_gap_mm']:.3f} mm, {pair['dihedral_deg']:.2f}°"


def check_part(ident, got, nest_path):
    import ezdxf
    nest = json.load(open(nest_path))
    place = next(p for p in nest["placements"] if p["id"] == ident)
    if place["sheet"] not in got["sub"]:
        fail(f"{ident}: shown on {got['sub']!r}, nest.json puts it on {place['sheet']}")
    close_to(f"{ident} rotation", number(got["rows"]["rotation"]), place["rotation_deg"], 1e-9)
    doc = ezdxf.readfile(os.path.join(os.path.dirname(nest_path), place["sheet"]))
    w, h = (number(v) for v in got["rows"]["box"].split("×"))
    lo = np.array(place["bbox_min"])
    hi = lo + [w, h]
    # The outer contour: one closed polyline, or (micro-joints) the open pieces inside the box
    # the page claims; either way they must start at bbox_min and span exactly that box.
    pieces = []
    for e in doc.modelspace().query("LWPOLYLINE[layer=='CUT_OUTER']"):
        pts = np.array([(x, y) for x, y, *_ in e.get_points()])
        if (pts.min(axis=0) >= lo - 0.06).all() and (pts.max(axis=0) <= hi + 0.06).all():
            pieces.append(pts)
    if not pieces:
        fail(f"{ident}: no CUT_OUTER contour inside the box the page shows")
    pts = np.vstack(pieces)
    got_lo, got_hi = pts.min(axis=0), pts.max(axis=0)
    close_to(f"{ident} box corner", float(np.abs(got_lo - lo).max()), 0.0, 0.05)
    close_to(f"{ident} box width", w, got_hi[0] - got_lo[0], 0.051)
    close_to(f"{ident} box height", h, got_hi[1] - got_lo[1], 0.051)
    # N bridges cut the contour into N pieces, or N + 1 when the pierce point is not at one.
    if place["micro_joints"] and not place["micro_joints"] <= len(pieces) <= place["micro_joints"] + 1:
        fail(f"{ident}: {len(pieces)} outer pieces in its box, nest.json says {place['micro_joints']} micro-joints")
    return f"{ident} on {place['sheet']}, box {w:.1f} × {h:.1f} mm in {len(pieces)} piece(s)"


def check_member(ident, rows, sizing):
    e = sizing["edges"][int(ident[1:])]
    close_to(f"{ident} utilisation", number(rows["utilisation"]), e["utilisation"], 5e-4)
    close_to(f"{ident} gauge", number(rows["gauge"]), e["gauge"], 1e-9)
    if e["check"] not in rows["utilisation"]:
        fail(f"{ident}: governed by {rows['utilisation']!r}, sizing.json says {e['check']}")
    return f"{ident} utilisation {e['utilisation']:.3f} ({e['check']})"


def check_node(ident, rows, net):
    k = int(ident[1:])
    p = np.array(net["nodes"][k]["p"] if "p" in net["nodes"][k] else net["nodes"][k]["position"])
    shown = np.array([float(v) for v in rows["position"].split(",")])
    close_to(f"{ident} position", float(np.abs(shown - p).max()), 0.0, 5e-4)
    return f"{ident} at {rows['position']}"


def check_edge(ident, rows, net):
    e = net["edges"][int(ident[1:])]
    ends = [np.array(net["nodes"][e[k]]["p"]) for k in ("a", "b")]
    if rows.get("nodes") != f"N{e['a']} – N{e['b']}":
        fail(f"{ident}: the page says nodes {rows.get('nodes')!r}, the network N{e['a']} – N{e['b']}")
    length = float(np.linalg.norm(ends[1] - ends[0]))
    close_to(f"{ident} length", number(rows["length"]), length, 5e-4 * max(1.0, length))
    return f"{ident} N{e['a']} – N{e['b']}, {length:.3f} mm"


def sl1_islands(path, layers=None):
    """Per layer (all, or those asked), the islands starting there, counted from the images."""
    from scipy import ndimage
    with zipfile.ZipFile(path) as z:
        cfg = configparser.ConfigParser()
        cfg.read_string("[c]\n" + z.read("config.ini").decode())
        c = cfg["c"]
        job, count = c["jobDir"], int(float(c["numFast"])) + int(float(c["numSlow"]))

        def lit(k):
            return np.array(Image.open(io.BytesIO(z.read(f"{job}{k:05d}.png"))).convert("L")) >= 128
        out = {}
        for k in (range(count) if layers is None else layers):
            if k == 0:
                out[k] = 0
                continue
            now, below = lit(k), lit(k - 1)
            labels, n = ndimage.label(now, structure=np.ones((3, 3)))
            held = set(np.unique(labels[below & now]))
            out[k] = sum(1 for i in range(1, n + 1) if i not in held)
    return out


LEGENDS = """[...document.querySelectorAll('.lv-legend-item')].map(b => [b.querySelector('h4').textContent,
    [...b.querySelectorAll('.lv-swatch')].map(w => [w.textContent.replace(/ \\(\\d+\\)$/, ''),
        getComputedStyle(w.firstChild).backgroundColor])])"""


def same_legend(b, url, other):
    """The class legends of two pages: every label both list has the same colour, in the same
    order. Returns what was compared; fails otherwise."""
    mine = {h: items for h, items in b.eval(LEGENDS) if items}
    b.navigate(other)
    b.wait("document.body && document.body.dataset.ready === '1'", "the other page getting ready")
    theirs = {h: items for h, items in b.eval(LEGENDS) if items}
    compared = 0
    for heading in sorted(set(mine) & set(theirs)):
        a_items, b_items = dict(mine[heading]), dict(theirs[heading])
        common = [label for label, _ in mine[heading] if label in b_items]
        if common != [label for label, _ in theirs[heading] if label in a_items]:
            fail(f"{heading}: the classes are listed in another order on the two pages")
        for label in common:
            if a_items[label] != b_items[label]:
                fail(f"{heading}: '{label}' is {a_items[label]} on one page and {b_items[label]} on the other")
            compared += 1
    if compared == 0:
        fail("the two pages have no legend class in common to compare")
    b.navigate(url)
    b.wait("document.body && document.body.dataset.ready === '1'", "the page getting ready again")
    return f"{compared} classes coloured as on {os.path.basename(other)}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("page")
    ap.add_argument("--select", action="append", default=[])
    ap.add_argument("--layer", action="append", type=int, default=[])
    ap.add_argument("--axes")
    ap.add_argument("--panels", help="the audited panels as OBJ faces (panel k is face k)")
    ap.add_argument("--plates")
    ap.add_argument("--welds")
    ap.add_argument("--sizing")
    ap.add_argument("--nest")
    ap.add_argument("--sl1")
    ap.add_argument("--first-island", action="store_true",
                    help="find the first layer where an island starts (counted here) and check the page there")
    ap.add_argument("--network")
    ap.add_argument("--max-mb", type=float)
    ap.add_argument("--screenshot")
    ap.add_argument("--browser", choices=["chromium", "firefox"], default="chromium")
    ap.add_argument("--no-webgl", action="store_true", help="chromium with --disable-3d-apis")
    ap.add_argument("--same-legend", metavar="OTHER.html",
                    help="another model's page: every class both pages list has the same colour and order")
    a = ap.parse_args()
    load = lambda p: json.load(open(p)) if p else None
    axes, plates, welds, sizing, net = map(load, (a.axes, a.plates, a.welds, a.sizing, a.network))

    size = os.path.getsize(a.page)
    if a.max_mb is not None and size > a.max_mb * 1e6:
        fail(f"{a.page} is {size / 1e6:.2f} MB, more than {a.max_mb} MB")
    html = open(a.page, encoding="utf-8").read()
    if re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", html):
        fail("the page loads something from the network")

    m = re.search(r'<script type="application/json" id="lamina-data">(.*?)</script>', html, re.S)
    if not m:
        fail("the page has no lamina-data scene")
    scene = json.loads(m.group(1))
    three_d = bool(scene["layers"])
    if not three_d and 'id="three-core"' in html:
        fail("the page draws nothing in 3D but carries three.js")

    url = "file://" + os.path.abspath(a.page)
    b = Firefox() if a.browser == "firefox" else Browser(no_webgl=a.no_webgl)
    said = [] if a.browser == "chromium" else [a.browser]
    try:
        b.navigate(url)
        b.wait("document.body && document.body.dataset.ready === '1'", "the viewer getting ready")
        ready_ms = float(b.eval("document.body.dataset.readyMs"))
        webgl = b.eval("""(() => { const c = document.createElement('canvas');
            return !!(c.getContext('webgl2') || c.getContext('webgl')); })()""")
        if three_d and not webgl:
            # The fallback: the notice, a projection with the objects, legends, views.
            flat = b.eval("""(() => { const f = document.querySelector('.lv-flat');
                if (!f || f.offsetParent === null) return null;
                return {notice: (f.querySelector('.lv-notice') || {}).textContent || '',
                        shapes: f.querySelectorAll('svg [data-id]').length,
                        legends: document.querySelectorAll('.lv-legend-item').length,
                        views: [...document.querySelectorAll('.lv-views button')].map(x => x.dataset.view)}; })()""")
            if not flat:
                fail("without WebGL the page shows no fallback projection")
            if "WebGL" not in flat["notice"]:
                fail(f"without WebGL the page does not say what is missing: {flat['notice']!r}")
            if flat["shapes"] == 0:
                fail("without WebGL the projection draws nothing")
            if any(L["colorings"] for L in scene["layers"] if L["visible"]) and flat["legends"] == 0:
                fail("without WebGL the page shows no legend")
            said.append(f"no WebGL: projection of {flat['shapes']} objects, {flat['legends']} legend(s), "
                        f"views {'/'.join(v for v in flat['views'] if v)}")
            if a.select:
                # The search box, typed into and submitted, finds the first selected id.
                ident = a.select[0]
                b.eval(f"""(() => {{ const i = document.querySelector('.lv-search input');
                    document.getElementById('lamina-info').dataset.selected = '';
                    i.value = {json.dumps(ident)}; i.form.requestSubmit(); }})()""")
                b.wait(f"document.getElementById('lamina-info').dataset.selected === {json.dumps(ident)}",
                       f"the search box finding {ident}")
                said.append(f"search found {ident}")
        elif three_d and a.no_webgl:
            fail("--no-webgl, yet the browser offers WebGL")
        if a.same_legend:
            said.append(same_legend(b, url, "file://" + os.path.abspath(a.same_legend)))
        canvas = b.eval("""(() => { const c = document.querySelector('#lamina-viewer canvas');
            if (!c || c.offsetParent === null) return null;
            c.scrollIntoView({block: 'center'});
            const r = c.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })()""")
        if canvas:
            shot = b.screenshot()
            img = Image.open(io.BytesIO(shot)).convert("RGB")
            x, y, w, h = (int(round(v)) for v in canvas)
            crop = img.crop((x, y, x + w, y + h))
            px = np.asarray(crop).reshape(-1, 3).astype(int)
            bg = np.array([0xf3, 0xf4, 0xf6])
            away = float((np.abs(px - bg).sum(axis=1) > 30).mean())
            std = max(ImageStat.Stat(crop).stddev)
            if away < 0.01 or std < 3:
                fail(f"the 3D canvas looks blank: {100 * away:.2f} % of pixels away from the background, stddev {std:.1f}")
            said.append(f"canvas {w}×{h}: {100 * away:.1f} % drawn, stddev {std:.1f}")
            # Hover picking's cost, reported (not held to a limit: machines are noisy).
            first, mean = b.eval("window.lamina.pickTime(50)")
            elements = sum(len(base64.b64decode(L["indices"])) // 8 if L["kind"] == "lines"
                           else len(base64.b64decode(L["positions"])) // 12 if L["kind"] == "points" else 0
                           for L in scene["layers"])
            said.append(f"hover pick {mean:.1f} ms ({first:.1f} ms after a frame) over {elements} lines and points")
        if canvas and a.select:
            # A click where each selected object is drawn (as the page says, where nothing
            # hides it) picks that object and no other.
            b.eval("location.hash = ''")
            clicked = []
            for ident in a.select:
                at = b.eval(f"window.lamina.screenOf({json.dumps(ident)})")
                if not at:
                    continue
                b.eval("document.getElementById('lamina-info').dataset.selected = ''")
                b.click(at[0], at[1])
                picked = b.wait("document.getElementById('lamina-info').dataset.selected", "a click picking a part")
                if picked != ident:
                    fail(f"a click on {ident}, where the page draws it ({at[0]:.1f}, {at[1]:.1f}), picked {picked}")
                clicked.append(ident)
            if not clicked:
                fail(f"none of {a.select} is drawn unhidden in the opening view to be clicked")
            said.append(f"clicks picked {', '.join(clicked)}")
        for asked in a.select:
            b.eval("document.getElementById('lamina-info').dataset.selected = ''")
            b.eval(f"location.hash = {json.dumps('select=' + asked)}")
            b.wait("document.getElementById('lamina-info').dataset.selected", f"selecting {asked}")
            got = info(b)
            ident = got["id"]
            if ident != asked:
                # An id no object has (edge E5 on a page of panels) selects the object one of
                # whose figures names it.
                if ident != got["selected"] or not any(re.match(rf"{re.escape(asked)}\b", v)
                                                       for v in got["rows"].values()):
                    fail(f"#select={asked} shows {ident!r}, whose figures do not name {asked}")
                said.append(f"{asked} found as {ident}")
            rows = got["rows"]
            if re.fullmatch(r"P\d+", ident) and (axes or a.panels):
                said.append(check_panel(ident, rows, axes, obj_quads(a.panels) if a.panels else None))
            elif re.fullmatch(r"W\d+-\d+", ident) and welds:
                said.append(check_weld(ident, rows, welds))
            elif re.fullmatch(r"E\d+", ident) and sizing:
                said.append(check_member(ident, rows, sizing))
            elif re.fullmatch(r"E\d+", ident) and net:
                said.append(check_edge(ident, rows, net))
            elif re.fullmatch(r"N\d+", ident) and net:
                said.append(check_node(ident, rows, net))
            elif plates and any(p["id"] == ident for p in plates["plates"]) and "gauge" in rows:
                said.append(check_plate(ident, rows, plates, sizing))
            elif a.nest:
                said.append(check_part(ident, got, a.nest))
            else:
                fail(f"{ident}: no source given to check its figures against")
        layers = list(a.layer)
        if a.first_island:
            counts = sl1_islands(a.sl1)
            first = next((k for k in sorted(counts) if counts[k]), None)
            if first is None:
                fail(f"{a.sl1} has no island to look for")
            shown = int(number(b.eval("""(() => { const f = window.lamina.data.print.figures;
                return f.find(r => r[0] === 'islands')[1]; })()""")))
            if shown != sum(counts.values()):
                fail(f"the page counts {shown} islands, the images have {sum(counts.values())}")
            layers.append(first)
        for k in layers:
            if not a.sl1:
                fail("--layer needs --sl1")
            b.eval(f"location.hash = 'view=print&layer={k}'")
            b.wait(f"document.getElementById('lamina-info').dataset.selected === 'layer {k}'", f"layer {k}")
            rows = info(b)["rows"]
            want = sl1_islands(a.sl1, [k])[k]
            shown = int(number(rows["islands starting here"]))
            if shown != want:
                fail(f"layer {k}: the page shows {shown} islands starting, the images have {want}")
            said.append(f"layer {k}: {want} islands start")
        time.sleep(0.7)  # a selection's flight lasts 0.5 s
        b.eval("0")  # collect late events
        if a.screenshot:
            Image.open(io.BytesIO(b.screenshot())).save(a.screenshot)
        if b.errors:
            fail(f"console errors: {b.errors}")
    finally:
        b.close()
    print(f"check_viewer: OK: {os.path.basename(a.page)} ({size / 1e6:.2f} MB) ready in {ready_ms:.0f} ms; "
          + "; ".join(said))


if __name__ == "__main__":
    main()
