// lamina's viewer: the scene in #lamina-data drawn with three.js (embedded beside this script as
// text and imported from Blob URLs, so the page needs no network). Written for lamina; see
// src/view/mod.rs for what the page promises (data-ready, #select=ID, #lamina-info).
const root = document.getElementById("lamina-viewer");
const text = (id) => document.getElementById(id).textContent;
const scriptUrl = (t) => URL.createObjectURL(new Blob([t], { type: "text/javascript" }));

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

const SVG = "http://www.w3.org/2000/svg";
function svgEl(tag, attrs = {}) {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  return e;
}

function bytes(b64) {
  const s = atob(b64);
  const out = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
  return out.buffer;
}

// Colours. A scale with a limit runs green → amber → red from 0 to the limit and stays dark
// red beyond; without one it runs over the values' range (viridis stops).
// Viridis, its last stop darkened from (253, 231, 37) so the top of a scale stays visible on
// the light background.
const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 190, 80], [205, 180, 0]];
const TRAFFIC = [[26, 150, 65], [166, 217, 106], [253, 174, 97], [215, 25, 28]];
const BEYOND = [120, 0, 10];
const PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
  "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#ad494a", "#637939", "#e7ba52", "#7b4173"];
const GREY = [170, 170, 170];

function ramp(stops, t) {
  t = Math.min(1, Math.max(0, t));
  const x = t * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(x));
  const f = x - i;
  return stops[i].map((a, k) => a + (stops[i + 1][k] - a) * f);
}

function hexRgb(h) {
  return [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
}

function scaleOf(c) {
  if (c.labels.length) return { kind: "cat" };
  // A loop, not Math.min(...values): spreading a million values overflows the call stack.
  let lo = 0, hi = -Infinity;
  for (const v of c.values) {
    if (v === null || !Number.isFinite(v)) continue;
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  if (c.limit !== null) [lo, hi] = [0, c.limit];
  if (!(hi > lo)) hi = lo + 1;
  return { kind: "scale", lo, hi };
}

// A category's colour: fixed for classes (weld access, pass or fail), else the palette.
const swatch = (c, i) => (c.colors.length ? c.colors[i] : PALETTE[i % PALETTE.length]);

function colourOf(c, s, v) {
  if (v === null || v === undefined || !Number.isFinite(v)) return GREY;
  if (s.kind === "cat") return hexRgb(swatch(c, v));
  if (c.limit !== null) return v > c.limit ? BEYOND : ramp(TRAFFIC, v / c.limit);
  return ramp(VIRIDIS, (v - s.lo) / (s.hi - s.lo));
}

const fmt = (v) => (Math.abs(v) >= 1000 || v === 0 ? v.toFixed(0) : Math.abs(v) >= 1 ? v.toFixed(3) : v.toPrecision(3));

function start(data) {
  // The page: a bar (tabs, search, title), the stage, and a side panel.
  const tabs = el("div", { class: "lv-tabs" });
  const search = el("input", { type: "search", placeholder: "find a tag or id (e.g. 2-041)", "aria-label": "find" });
  const found = el("span", { class: "lv-found" });
  const bar = el("div", { class: "lv-bar" }, el("strong", {}, data.title), tabs,
    el("form", { class: "lv-search", onsubmit: (e) => { e.preventDefault(); find(search.value); } }, search, found));
  const stage = el("div", { class: "lv-stage" });
  const side = el("div", { class: "lv-side" });
  const info = el("div", { id: "lamina-info", class: "lv-info" }, el("p", { class: "lv-hint" }, "Hover or click a part for its id and figures."));
  const layersBox = el("div", { class: "lv-layers" });
  const legend = el("div", { class: "lv-legend" });
  const notes = el("div", { class: "lv-notes" });
  for (const n of data.notes) notes.append(el("p", {}, n));
  side.append(info, layersBox, legend, notes);
  root.append(bar, el("div", { class: "lv-main" }, stage, side));
  const tip = el("div", { class: "lv-tip" });
  stage.append(tip);

  const views = {};
  if (data.layers.length) {
    views["3d"] = hasWebGL() ? build3d(data, stage, layersBox, legend, info, tip) : buildFlat(data, stage, layersBox, legend, info);
  }
  if (data.sheets.length) views.sheets = buildSheets(data, stage, info);
  if (data.print) views.print = buildPrint(data.print, stage, info);
  let current = null;
  function show(name) {
    if (!views[name]) return;
    current = name;
    for (const [k, v] of Object.entries(views)) {
      v.node.style.display = k === name ? "" : "none";
      v.tab.classList.toggle("on", k === name);
    }
    layersBox.style.display = legend.style.display = name === "3d" ? "" : "none";
    views[name].shown?.();
  }
  const titles = { "3d": "3D", sheets: "Sheets", print: "Print layers" };
  for (const k of Object.keys(views)) {
    views[k].tab = el("button", { type: "button", onclick: () => show(k) }, titles[k]);
    tabs.append(views[k].tab);
  }

  function find(q) {
    q = q.trim();
    if (!q) return false;
    const lower = q.toLowerCase();
    for (const exact of [true, false]) {
      for (const k of Object.keys(views)) {
        const hit = views[k].find(lower, exact);
        if (hit) {
          show(k);
          hit();
          found.textContent = "";
          return true;
        }
      }
    }
    found.textContent = "not found";
    return false;
  }

  function applyHash() {
    const h = new URLSearchParams(location.hash.slice(1));
    if (h.get("view") && views[h.get("view")]) show(h.get("view"));
    if (h.get("layer") !== null && views.print) {
      show("print");
      views.print.go(Number(h.get("layer")));
    }
    if (h.get("select")) {
      search.value = h.get("select");
      find(h.get("select"));
    }
  }
  show(Object.keys(views)[0]);
  applyHash();
  window.addEventListener("hashchange", applyHash);
  window.lamina = {
    find, show, data,
    screenOf: (id) => views["3d"]?.screenOf?.(id) ?? null,
    pickTime: (n) => views["3d"]?.pickTime?.(n) ?? null,
  };
  requestAnimationFrame(() => requestAnimationFrame(() => {
    document.body.dataset.readyMs = performance.now().toFixed(0);
    document.body.dataset.ready = "1";
  }));
}

// An object's figures as (name, value) pairs: its layer's columns with its values, the empty
// ones left out.
const figuresOf = (L, o) => L.columns.map((c, i) => [c, o.values[i]]).filter(([, v]) => v !== "");

function figuresTable(title, sub, figures) {
  const t = el("table");
  for (const [k, v] of figures) t.append(el("tr", {}, el("th", {}, k), el("td", {}, v)));
  return [el("h3", { class: "lv-id" }, title), el("p", { class: "lv-sub" }, sub), t];
}

// One legend: categories with their counts in class order, or a scale with its range.
function legendItem(name, c) {
  const s = scaleOf(c);
  const box = el("div", { class: "lv-legend-item" }, el("h4", {}, `${name}: ${c.name}${c.unit ? ` (${c.unit})` : ""}`));
  if (s.kind === "cat") {
    const counts = new Map();
    c.values.forEach((v) => counts.set(v, (counts.get(v) || 0) + 1));
    c.labels.forEach((label, i) => {
      box.append(el("div", { class: "lv-swatch" }, el("span", { style: `background:${swatch(c, i)}` }), `${label} (${counts.get(i) || 0})`));
    });
  } else {
    const stops = (c.limit !== null ? TRAFFIC : VIRIDIS).map((rgb, i, a) => `rgb(${rgb.join(",")}) ${(100 * i) / (a.length - 1)}%`);
    const gradient = el("div", { class: "lv-gradient", style: `background:linear-gradient(to right,${stops.join(",")})` });
    const u = c.unit ? ` ${c.unit}` : "";
    box.append(gradient, el("div", { class: "lv-ticks" }, el("span", {}, `${fmt(s.lo)}${u}`), el("span", {}, `${fmt(s.hi)}${u}`)));
    if (c.limit !== null) box.append(el("p", { class: "lv-sub" }, `red at the limit (${fmt(c.limit)}${u}); dark red beyond it`));
    if (c.values.some((v) => v === null)) box.append(el("p", { class: "lv-sub" }, "grey: no value"));
  }
  box.append(el("p", { class: "lv-def" }, c.definition));
  return box;
}

// The layer list (a checkbox each, and a menu of colourings) and the legends of the visible
// coloured layers. Each layer has L, coloring and visible; `changed(layer, what)` redraws.
function layerControls(layers, layersBox, legend, changed) {
  function drawLegend() {
    legend.replaceChildren();
    for (const layer of layers) {
      const c = layer.L.colorings[layer.coloring];
      if (layer.visible && c) legend.append(legendItem(layer.L.name, c));
    }
  }
  layers.forEach((layer) => {
    const check = el("input", { type: "checkbox" });
    check.checked = layer.visible;
    check.addEventListener("change", () => { layer.visible = check.checked; drawLegend(); changed(layer, "visible"); });
    const row = el("div", { class: "lv-layer" }, el("label", {}, check, ` ${layer.L.name} (${layer.L.objects.length})`));
    if (layer.L.colorings.length > 1) {
      const sel = el("select", { "aria-label": `${layer.L.name} colour` });
      layer.L.colorings.forEach((c, i) => sel.append(el("option", { value: i }, `by ${c.name}`)));
      sel.addEventListener("change", () => { layer.coloring = Number(sel.value); drawLegend(); changed(layer, "coloring"); });
      row.append(sel);
    } else if (layer.L.colorings.length === 1) {
      row.append(el("span", { class: "lv-sub" }, ` by ${layer.L.colorings[0].name}`));
    }
    layersBox.append(row);
  });
  drawLegend();
}

// The views a 3D page offers: the direction the camera looks from (z is up on screen but in plan,
// where y is).
const VIEWS = {
  plan: [0, -1e-4, 1],
  front: [0, -1, 0],
  side: [1, 0, 0],
  iso: [1, -1.3, 0.9],
};

// A model is flat when its height is under 1 % of its width: it opens in plan.
const isFlat = (size) => size[2] <= 0.01 * Math.max(size[0], size[1]);

// A round length (1, 2 or 5 × 10^k) near `about`, for a scale bar.
function roundLength(about) {
  const k = Math.pow(10, Math.floor(Math.log10(about)));
  return [1, 2, 5, 10].map((m) => m * k).reduce((a, b) => (Math.abs(b - about) < Math.abs(a - about) ? b : a));
}

const dims = (size) => size.map((v) => (v >= 100 ? v.toFixed(0) : v.toPrecision(3))).join(" × ") + " mm";

// Search over the layers' objects: by id, then by a figure that names another id (a panel's
// "edge E5", a plate's edge) when no object has that id, then (not exact) by part of an id.
function finder(layers, select) {
  const index = new Map();
  layers.forEach((layer, li) => layer.L.objects.forEach((o, k) => {
    const key = o.id.toLowerCase();
    if (!index.has(key)) index.set(key, [li, k]);
  }));
  const also = new Map();
  layers.forEach((layer, li) => layer.L.objects.forEach((o, k) => {
    for (const v of o.values) {
      const m = /^([ENP]\d+)\b/.exec(v);
      if (m && !index.has(m[1].toLowerCase()) && !also.has(m[1].toLowerCase())) also.set(m[1].toLowerCase(), [li, k]);
    }
  }));
  return {
    index,
    find(q, exact) {
      let hit = index.get(q) || also.get(q);
      if (!hit && !exact) {
        for (const [key, v] of index) if (key.includes(q)) { hit = v; break; }
      }
      return hit ? () => select(hit[0], hit[1]) : null;
    },
  };
}

// Members on screen at least this wide, pixels (WebGL draws lines one pixel wide).
const LINE_PX = 2.5;

// Segments (pairs of `idx` into `pos`) as screen-space quads LINE_PX wide: each end's two
// corners are pushed apart across the segment's direction on screen by the vertex shader.
// `recolour` copies the source vertices' colours; `viewport` follows the canvas size.
function fatLines(pos, idx) {
  const n = idx.length / 2;
  const here = new Float32Array(12 * n), there = new Float32Array(12 * n), side = new Float32Array(4 * n);
  const source = new Uint32Array(4 * n), tris = new Uint32Array(6 * n);
  const SIDES = [-1, 1, 1, -1]; // a's left and right, then b's in a's frame
  for (let s = 0; s < n; s++) {
    const a = idx[2 * s], b = idx[2 * s + 1];
    for (let c = 0; c < 4; c++) {
      const [p, q] = c < 2 ? [a, b] : [b, a];
      const v = 4 * s + c;
      here.set(pos.subarray(3 * p, 3 * p + 3), 3 * v);
      there.set(pos.subarray(3 * q, 3 * q + 3), 3 * v);
      side[v] = SIDES[c];
      source[v] = p;
    }
    tris.set([4 * s, 4 * s + 1, 4 * s + 2, 4 * s + 2, 4 * s + 1, 4 * s + 3], 6 * s);
  }
  const geo = new THREE.BufferGeometry();
  geo.setAttribute("position", new THREE.BufferAttribute(here, 3));
  geo.setAttribute("other", new THREE.BufferAttribute(there, 3));
  geo.setAttribute("side", new THREE.BufferAttribute(side, 1));
  const tint = new Float32Array(12 * n);
  geo.setAttribute("tint", new THREE.BufferAttribute(tint, 3));
  geo.setIndex(new THREE.BufferAttribute(tris, 1));
  const material = new THREE.ShaderMaterial({
    side: THREE.DoubleSide, // a quad's winding depends on the segment's direction on screen
    uniforms: { halfSize: { value: new THREE.Vector2(1, 1) }, width: { value: LINE_PX } },
    vertexShader: `
      attribute vec3 other; attribute float side; attribute vec3 tint;
      uniform vec2 halfSize; uniform float width;
      varying vec3 vTint;
      void main() {
        vTint = tint;
        vec4 a = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
        vec4 b = projectionMatrix * modelViewMatrix * vec4(other, 1.0);
        vec2 d = b.xy / b.w * halfSize - a.xy / a.w * halfSize;
        d = length(d) > 1e-6 ? normalize(d) : vec2(1.0, 0.0);
        a.xy += vec2(-d.y, d.x) * side * 0.5 * width / halfSize * a.w;
        gl_Position = a;
      }`,
    fragmentShader: `
      varying vec3 vTint;
      void main() { gl_FragColor = vec4(vTint, 1.0); }`,
  });
  const mesh = new THREE.Mesh(geo, material);
  mesh.frustumCulled = false;
  return {
    mesh,
    recolour(colours) {
      for (let v = 0; v < source.length; v++) tint.set(colours.subarray(3 * source[v], 3 * source[v] + 3), 3 * v);
      geo.getAttribute("tint").needsUpdate = true;
    },
    viewport(w, h) { material.uniforms.halfSize.value.set(w / 2, h / 2); },
  };
}

// ---------------------------------------------------------------- 3D
function build3d(data, stage, layersBox, legend, info, tip) {
  const node = el("div", { class: "lv-3d" });
  stage.append(node);
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  node.append(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf3f4f6);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1e7);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x667080, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(0.4, 0.6, 1);
  camera.add(sun);
  scene.add(camera);
  camera.up.set(0, 0, 1); // before the controls: they orbit about it
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.screenSpacePanning = true;
  // Point and line layers' vertices on screen, per layer, for picking: kept until the next frame.
  const projected = new Map();
  // A scale bar for the centre of the view (lengths there, in the model's millimetres).
  const bar = el("div", { class: "lv-scale" }, el("div", { class: "lv-scale-bar" }), el("span", {}));
  node.append(bar);
  function drawScale() {
    const h = node.clientHeight;
    if (!h) return;
    const perPixel = (2 * camera.position.distanceTo(controls.target) * Math.tan((camera.fov * Math.PI) / 360)) / h;
    if (!(perPixel > 0)) return;
    const len = roundLength(perPixel * 110);
    bar.firstChild.style.width = `${(len / perPixel).toFixed(1)}px`;
    bar.lastChild.textContent = `${len >= 1 ? len : len.toPrecision(1)} mm at the centre of view`;
  }
  const render = () => { projected.clear(); drawScale(); renderer.render(scene, camera); };
  controls.addEventListener("change", render);

  const dot = document.createElement("canvas");
  dot.width = dot.height = 64;
  const g = dot.getContext("2d");
  g.beginPath();
  g.arc(32, 32, 28, 0, 2 * Math.PI);
  g.fillStyle = "#fff";
  g.fill();
  const dotTexture = new THREE.CanvasTexture(dot);

  const layers = [];
  const box = new THREE.Box3();
  for (const L of data.layers) {
    const pos = new Float32Array(bytes(L.positions));
    const idx = new Uint32Array(bytes(L.indices));
    const geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.BufferAttribute(pos, 3));
    const colours = new Float32Array(pos.length);
    geo.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    let obj, fat = null;
    const per = L.kind === "faces" ? 3 : L.kind === "lines" ? 2 : 1;
    if (L.kind !== "points") geo.setIndex(new THREE.BufferAttribute(idx, 1));
    if (L.kind === "faces") {
      geo.computeVertexNormals();
      obj = new THREE.Mesh(geo, new THREE.MeshLambertMaterial({
        vertexColors: true, side: THREE.DoubleSide, polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
      }));
      const out = new Uint32Array(bytes(L.outline));
      if (out.length) {
        const og = new THREE.BufferGeometry();
        og.setAttribute("position", geo.getAttribute("position"));
        og.setIndex(new THREE.BufferAttribute(out, 1));
        obj.add(new THREE.LineSegments(og, new THREE.LineBasicMaterial({ color: 0x30343a, transparent: true, opacity: 0.55 })));
      }
    } else if (L.kind === "lines") {
      fat = fatLines(pos, idx);
      obj = fat.mesh;
    } else {
      obj = new THREE.Points(geo, new THREE.PointsMaterial({
        vertexColors: true, size: 7, sizeAttenuation: false, map: dotTexture, alphaTest: 0.5,
      }));
    }
    // Which object each element belongs to, and each element's vertices.
    const owner = new Uint32Array(L.kind === "points" ? pos.length / 3 : idx.length / per);
    L.objects.forEach((o, k) => owner.fill(k, o.first, o.first + o.count));
    const vertsOf = (k) => {
      const o = L.objects[k];
      if (L.kind === "points") return [o.first];
      const v = [];
      for (let i = o.first * per; i < (o.first + o.count) * per; i++) v.push(idx[i]);
      return v;
    };
    // An object's bounding sphere (scene coordinates, less the origin) from its vertices.
    const sphereOf = (k) => {
      const b = new THREE.Box3();
      const v3 = new THREE.Vector3();
      for (const v of vertsOf(k)) b.expandByPoint(v3.fromArray(pos, 3 * v));
      return { c: b.getCenter(new THREE.Vector3()), r: b.getSize(new THREE.Vector3()).length() / 2 };
    };
    obj.visible = L.visible;
    scene.add(obj);
    if (pos.length) {
      geo.computeBoundingBox();
      if (L.visible) box.union(geo.boundingBox);
    }
    const layer = { L, obj, geo, fat, colours, owner, vertsOf, sphereOf, per, coloring: L.colorings.length ? 0 : -1 };
    layers.push(layer);
    paint(layer);
  }
  if (box.isEmpty()) box.set(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  camera.near = radius / 1000;
  camera.far = radius * 100;
  const size = box.getSize(new THREE.Vector3()).toArray();
  let view = isFlat(size) ? "plan" : "iso";

  function paint(layer) {
    const { L, colours } = layer;
    const c = L.colorings[layer.coloring];
    const s = c ? scaleOf(c) : null;
    const base = L.kind === "lines" ? [40, 60, 90] : L.kind === "points" ? [200, 80, 30] : [160, 170, 185];
    L.objects.forEach((o, k) => {
      const rgb = c ? colourOf(c, s, c.values[k]) : base;
      for (const v of layer.vertsOf(k)) colours.set(rgb.map((x) => x / 255), 3 * v);
    });
    layer.geo.getAttribute("color").needsUpdate = true;
    if (layer.fat) layer.fat.recolour(colours);
  }

  function fit(centreAt = centre, r = radius, keep = false) {
    const dir = keep
      ? camera.position.clone().sub(controls.target).normalize()
      : new THREE.Vector3(...VIEWS[view]).normalize();
    const dist = r / Math.sin((camera.fov * Math.PI) / 360) * 1.05;
    controls.target.copy(centreAt);
    camera.position.copy(centreAt).addScaledVector(dir, dist);
    camera.updateProjectionMatrix();
    controls.update();
    render();
  }

  let flight = null;
  function flyTo(c, r) {
    const from = { t: controls.target.clone(), p: camera.position.clone() };
    const dir = camera.position.clone().sub(controls.target).normalize();
    const dist = Math.max(r, radius * 0.2) / Math.sin((camera.fov * Math.PI) / 360) * 1.6;
    const to = { t: c.clone(), p: c.clone().addScaledVector(dir, dist) };
    const t0 = performance.now();
    cancelAnimationFrame(flight);
    const step = (now) => {
      const f = Math.min(1, (now - t0) / 500);
      const e = f * f * (3 - 2 * f);
      controls.target.lerpVectors(from.t, to.t, e);
      camera.position.lerpVectors(from.p, to.p, e);
      controls.update();
      render();
      if (f < 1) flight = requestAnimationFrame(step);
    };
    flight = requestAnimationFrame(step);
  }

  // Selection: the object drawn again in a bright colour over the rest.
  const marks = new THREE.Group();
  scene.add(marks);
  let selected = null;
  function select(li, k, fly) {
    const layer = layers[li];
    const o = layer.L.objects[k];
    marks.clear();
    const pos = layer.geo.getAttribute("position");
    const vs = layer.vertsOf(k);
    const pts = new Float32Array(vs.length * 3);
    vs.forEach((v, i) => pts.set([pos.getX(v), pos.getY(v), pos.getZ(v)], 3 * i));
    const g2 = new THREE.BufferGeometry();
    g2.setAttribute("position", new THREE.BufferAttribute(pts, 3));
    const hl = 0xffb000;
    if (layer.L.kind === "faces") {
      marks.add(new THREE.Mesh(g2, new THREE.MeshBasicMaterial({ color: hl, side: THREE.DoubleSide, transparent: true, opacity: 0.6, depthTest: false })));
    } else if (layer.L.kind === "lines") {
      marks.add(new THREE.LineSegments(g2, new THREE.LineBasicMaterial({ color: hl, depthTest: false })));
    }
    const { c, r: orad } = layer.sphereOf(k);
    const ring = new THREE.Mesh(new THREE.SphereGeometry(Math.max(orad * 0.08, radius * 0.008), 16, 12),
      new THREE.MeshBasicMaterial({ color: hl, depthTest: false, transparent: true, opacity: 0.9 }));
    ring.position.copy(c);
    marks.add(ring);
    marks.renderOrder = 10;
    selected = { li, k };
    info.replaceChildren(...figuresTable(o.id, layer.L.name, figuresOf(layer.L, o)));
    info.dataset.selected = o.id;
    if (fly) flyTo(c, orad);
    render();
  }

  // Picking: what is drawn under the pointer, nearest in screen space. A point within its dot
  // comes first, then a line within a few pixels (fewer over a face), then the nearest face the
  // ray meets; a point
  // or line behind that face is hidden (drawn with the depth test) and not picked. The
  // vertices of point and line layers are projected once per view, not per move.
  const PICK_POINT = 6, PICK_LINE = 5, DOT = 3.5; // pixels (DOT: a point's drawn radius)
  const ray = new THREE.Raycaster();
  const viewMatrix = new THREE.Matrix4();
  function projectLayer(li) {
    let p = projected.get(li);
    if (p) return p;
    const pos = layers[li].geo.getAttribute("position").array;
    camera.updateMatrixWorld();
    const m = viewMatrix.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse).elements;
    const r = renderer.domElement.getBoundingClientRect();
    p = new Float32Array(pos.length);
    for (let i = 0; i < pos.length; i += 3) {
      const x = pos[i], y = pos[i + 1], z = pos[i + 2];
      const w = m[3] * x + m[7] * y + m[11] * z + m[15];
      p[i] = ((m[0] * x + m[4] * y + m[8] * z + m[12]) / w + 1) / 2 * r.width;
      p[i + 1] = (1 - (m[1] * x + m[5] * y + m[9] * z + m[13]) / w) / 2 * r.height;
      // Depth in normalised device coordinates; 2 (outside) behind the camera.
      p[i + 2] = w > 0 ? (m[2] * x + m[6] * y + m[10] * z + m[14]) / w : 2;
    }
    projected.set(li, p);
    return p;
  }
  // The nearest face hit at client (x, y): its depth (NDC) and object, or null.
  function faceAt(sx, sy, r) {
    ray.setFromCamera(new THREE.Vector2((sx / r.width) * 2 - 1, -(sy / r.height) * 2 + 1), camera);
    const objs = layers.filter((l) => l.obj.visible && l.L.kind === "faces").map((l) => l.obj);
    for (const hit of ray.intersectObjects(objs, false)) {
      const li = layers.findIndex((l) => l.obj === hit.object);
      if (li < 0 || hit.faceIndex === null || hit.faceIndex === undefined) continue;
      return { li, k: layers[li].owner[hit.faceIndex], z: hit.point.clone().project(camera).z };
    }
    return null;
  }
  function pickAt(sx, sy) {
    const face = faceAt(sx, sy, renderer.domElement.getBoundingClientRect());
    return thinAt(sx, sy, face) || (face ? { li: face.li, k: face.k } : null);
  }
  // The point, else the line, drawn nearest (sx, sy) within reach and not behind `face`.
  function thinAt(sx, sy, face) {
    const inFront = (z) => z >= -1 && z <= 1 && (!face || z <= face.z + 1e-6);
    // Over a face, a point or line must be nearly under the pointer to win over it.
    const reach = { points: face ? 4 : PICK_POINT, lines: face ? 2 : PICK_LINE };
    const found = {};
    for (const kind of ["points", "lines"]) {
      let best = null, bestD = reach[kind], bestZ = Infinity;
      const better = (d, z) => d < bestD || (d === bestD && z < bestZ);
      layers.forEach((layer, li) => {
        if (!layer.obj.visible || layer.L.kind !== kind) return;
        const p = projectLayer(li);
        if (kind === "points") {
          for (let v = 0; 3 * v < p.length; v++) {
            const z = p[3 * v + 2];
            if (!inFront(z)) continue;
            const d = Math.hypot(p[3 * v] - sx, p[3 * v + 1] - sy);
            if (better(d, z)) { bestD = d; bestZ = z; best = { li, k: layer.owner[v] }; }
          }
        } else {
          const idx = layer.geo.index.array;
          for (let s = 0; s < idx.length; s += 2) {
            const a = 3 * idx[s], b = 3 * idx[s + 1];
            const ax = p[a], ay = p[a + 1], dx = p[b] - ax, dy = p[b + 1] - ay;
            const l2 = dx * dx + dy * dy;
            const t = l2 > 0 ? Math.min(1, Math.max(0, ((sx - ax) * dx + (sy - ay) * dy) / l2)) : 0;
            const d = Math.hypot(ax + t * dx - sx, ay + t * dy - sy);
            if (d > bestD) continue;
            const z = p[a + 2] + t * (p[b + 2] - p[a + 2]);
            if (p[a + 2] > 1 || p[b + 2] > 1 || !inFront(z)) continue;
            if (better(d, z)) { bestD = d; bestZ = z; best = { li, k: layer.owner[s / 2] }; }
          }
        }
      });
      found[kind] = best && { ...best, d: bestD };
    }
    // A point under its dot wins; else the nearer of the point and the line (the point on a tie).
    const { points: pt, lines: ln } = found;
    const hit = pt && (pt.d <= DOT || !ln || pt.d <= ln.d) ? pt : ln;
    return hit ? { li: hit.li, k: hit.k } : null;
  }
  function pick(ev) {
    const r = renderer.domElement.getBoundingClientRect();
    return pickAt(ev.clientX - r.left, ev.clientY - r.top);
  }
  let down = null;
  renderer.domElement.addEventListener("pointerdown", (e) => { down = [e.clientX, e.clientY]; });
  renderer.domElement.addEventListener("pointerup", (e) => {
    if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4) {
      const hit = pick(e);
      if (hit) select(hit.li, hit.k, false);
    }
    down = null;
  });
  let hoverQueued = false;
  renderer.domElement.addEventListener("pointermove", (e) => {
    if (hoverQueued || e.buttons) return;
    hoverQueued = true;
    requestAnimationFrame(() => {
      hoverQueued = false;
      const hit = pick(e);
      if (!hit) { tip.style.display = "none"; return; }
      const o = layers[hit.li].L.objects[hit.k];
      const r = node.getBoundingClientRect();
      tip.textContent = `${o.id}: ${figuresOf(layers[hit.li].L, o).slice(0, 2).map(([a, b]) => `${a} ${b}`).join(", ")}`;
      tip.style.left = `${e.clientX - r.left + 14}px`;
      tip.style.top = `${e.clientY - r.top + 10}px`;
      tip.style.display = "block";
    });
  });
  renderer.domElement.addEventListener("pointerleave", () => { tip.style.display = "none"; });

  // Layer list and legends (shared with the SVG fallback): `visible` is the 3D object's.
  for (const layer of layers) {
    Object.defineProperty(layer, "visible", { get: () => layer.obj.visible, set: (v) => { layer.obj.visible = v; } });
  }
  layerControls(layers, layersBox, legend, (layer, what) => { if (what === "coloring") paint(layer); render(); });
  const viewButtons = el("div", { class: "lv-views" }, "View: ");
  for (const name of Object.keys(VIEWS)) {
    viewButtons.append(el("button", { type: "button", "data-view": name, onclick: () => { view = name; fit(); } }, name));
  }
  viewButtons.append(el("button", { type: "button", onclick: () => fit() }, "fit"));
  layersBox.append(viewButtons, el("p", { class: "lv-sub lv-dims" }, `overall ${dims(size)} (x × y × z)`));

  function resize() {
    const w = node.clientWidth, h = node.clientHeight;
    if (!w || !h) return;
    renderer.setSize(w, h);
    for (const l of layers) l.fat?.viewport(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    render();
  }
  new ResizeObserver(resize).observe(node);
  resize();
  fit();

  const { index, find } = finder(layers, (li, k) => select(li, k, true));
  return {
    node,
    find,
    shown: resize,
    // Milliseconds a hover pick takes: the first after a frame (which projects the layers)
    // and the mean of `n` more at spread positions, for tests that report it.
    pickTime(n) {
      const r = renderer.domElement.getBoundingClientRect();
      render();
      let t = performance.now();
      pickAt(r.width / 2, r.height / 2);
      const first = performance.now() - t;
      t = performance.now();
      for (let i = 0; i < n; i++) pickAt(((i * 0.618034) % 1) * r.width, ((i * 0.754878) % 1) * r.height);
      return [first, (performance.now() - t) / n];
    },
    // Where an object is drawn on the screen (client pixels), for tests that click it: a point
    // itself, a line's longest segment's middle, the centroid of a face's largest triangle
    // that nothing hides; null where it is hidden or off screen.
    screenOf(id) {
      const hit = index.get(id.toLowerCase());
      if (!hit) return null;
      const [li, k] = hit;
      const layer = layers[li];
      if (!layer.obj.visible) return null;
      const r = renderer.domElement.getBoundingClientRect();
      const p = projectLayer(li);
      const vs = layer.vertsOf(k);
      const on = ([x, y]) => x >= 0 && y >= 0 && x <= r.width && y <= r.height;
      const isFront = (f) => f !== null && f.li === li && f.k === k;
      let at = null;
      const mine = (x, y) => { const h = thinAt(x, y, null); return h !== null && h.li === li && h.k === k; };
      if (layer.L.kind === "points") {
        const c = [p[3 * vs[0]], p[3 * vs[0] + 1], p[3 * vs[0] + 2]];
        at = on(c) && mine(c[0], c[1]) ? c : null; // null: another point on the same spot
      } else if (layer.L.kind === "lines") {
        // Along its segments, longest first, a spot no other point or line is nearer to.
        const segs = [];
        for (let i = 0; i < vs.length; i += 2) segs.push([vs[i], vs[i + 1]]);
        const len = ([a, b]) => Math.hypot(p[3 * b] - p[3 * a], p[3 * b + 1] - p[3 * a + 1]);
        segs.sort((u, w) => len(w) - len(u));
        for (const [a, b] of segs.slice(0, 8)) {
          for (const t of [0.5, 0.35, 0.65, 0.2, 0.8]) {
            const c = [0, 1, 2].map((j) => p[3 * a + j] + t * (p[3 * b + j] - p[3 * a + j]));
            if (on(c) && mine(c[0], c[1])) { at = c; break; }
          }
          if (at) break;
        }
      } else {
        // The centroid of its largest triangle on screen that it shows, nothing drawn over.
        let best = -1;
        for (let i = 0; i < vs.length; i += 3) {
          const q = vs.slice(i, i + 3).map((v) => [p[3 * v], p[3 * v + 1], p[3 * v + 2]]);
          const size = Math.abs((q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]));
          const c = [0, 1, 2].map((j) => (q[0][j] + q[1][j] + q[2][j]) / 3);
          if (size > best && on(c) && ((f) => isFront(f) && !thinAt(c[0], c[1], f))(faceAt(c[0], c[1], r))) { best = size; at = c; }
        }
      }
      if (!at || !on(at) || at[2] < -1 || at[2] > 1) return null;
      // A point or line behind a face is hidden there.
      const f = layer.per === 3 ? null : faceAt(at[0], at[1], r);
      if (f && f.z < at[2] - 1e-6) return null;
      return [r.left + at[0], r.top + at[1]];
    },
  };
}

// ---------------------------------------------------------------- without WebGL
function hasWebGL() {
  try {
    const c = document.createElement("canvas");
    return !!(window.WebGLRenderingContext && (c.getContext("webgl2") || c.getContext("webgl")));
  } catch (e) {
    return false;
  }
}

// Elements an SVG projection draws at most (beyond, whole objects are left out, and said).
const FLAT_LIMIT = 200000;

// The 3D layers as a static SVG projection (plan, front or side) for a browser without WebGL:
// the same colours, layer list, legends, figures and search; a click selects.
function buildFlat(data, stage, layersBox, legend, info) {
  const node = el("div", { class: "lv-flat" });
  stage.append(node);
  const notice = el("p", { class: "lv-notice" }, "This browser has no WebGL (it is off, or the machine has none): " +
    "the 3D view is replaced by a flat projection of the model. Colours, legends, figures and search work as in 3D; orbiting does not.");
  const leftOut = el("span");
  notice.append(leftOut);
  const buttons = el("div", { class: "lv-views" }, "View: ");
  const svg = svgEl("svg", { class: "lv-flat-svg", preserveAspectRatio: "xMidYMid meet" });
  node.append(notice, buttons, svg);
  const layers = data.layers.map((L) => {
    const pos = new Float32Array(bytes(L.positions));
    const idx = new Uint32Array(bytes(L.indices));
    const per = L.kind === "faces" ? 3 : L.kind === "lines" ? 2 : 1;
    return { L, pos, idx, per, visible: L.visible, coloring: L.colorings.length ? 0 : -1, shapes: [] };
  });
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (const layer of layers) {
    if (!layer.visible) continue;
    for (let i = 0; i < layer.pos.length; i++) {
      lo[i % 3] = Math.min(lo[i % 3], layer.pos[i]);
      hi[i % 3] = Math.max(hi[i % 3], layer.pos[i]);
    }
  }
  const size = lo.map((v, i) => (Number.isFinite(v) ? hi[i] - v : 0));
  layersBox.append(buttons, el("p", { class: "lv-sub lv-dims" }, `overall ${dims(size)} (x × y × z)`));
  // Per view: the two screen axes (index, sign) and the axis toward the viewer.
  const AXES = { plan: [[0, 1], [1, -1], 2], front: [[0, 1], [2, -1], 1], side: [[1, 1], [2, -1], 0] };
  const toward = { plan: 1, front: -1, side: 1 };
  // Flat models in plan, the rest from the front.
  let view = isFlat(size) ? "plan" : "front";
  let selected = null;
  function draw() {
    svg.replaceChildren();
    const [[ax, sx], [ay, sy], az] = AXES[view];
    const span = Math.max(size[ax], size[ay], 1e-9);
    svg.setAttribute("viewBox", `${sx > 0 ? lo[ax] : -hi[ax]} ${sy > 0 ? lo[ay] : -hi[ay]} ${size[ax] || span} ${size[ay] || span}`);
    const px = span / 800;
    const g = svgEl("g");
    let budget = FLAT_LIMIT, left = 0;
    const items = [];
    layers.forEach((layer, li) => {
      layer.shapes = [];
      if (!layer.visible) return;
      const { L, pos, idx, per } = layer;
      const c = L.colorings[layer.coloring];
      const sc = c ? scaleOf(c) : null;
      const base = L.kind === "lines" ? [40, 60, 90] : L.kind === "points" ? [200, 80, 30] : [160, 170, 185];
      L.objects.forEach((o, k) => {
        if (o.count > budget) { left += 1; return; }
        budget -= o.count;
        const rgb = (c ? colourOf(c, sc, c.values[k]) : base).map(Math.round);
        const colour = `rgb(${rgb.join(",")})`;
        const at = (v) => `${sx * pos[3 * v + ax]},${sy * pos[3 * v + ay]}`;
        let d = "", depth = 0;
        if (L.kind === "points") {
          const v = o.first;
          depth = toward[view] * pos[3 * v + az];
          items.push([depth, li, k, svgEl("circle", { cx: sx * pos[3 * v + ax], cy: sy * pos[3 * v + ay], r: 3 * px, fill: colour })]);
          return;
        }
        for (let e = o.first; e < o.first + o.count; e++) {
          const vs = Array.from(idx.subarray(e * per, e * per + per));
          if (per === 3) {
            // Every triangle wound the same way on screen, so that the path's nonzero fill
            // covers the union (a plate's two faces, wound opposite, would cancel).
            const [a, b, c] = vs.map((v) => [sx * pos[3 * v + ax], sy * pos[3 * v + ay]]);
            if ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) < 0) vs.reverse();
          }
          d += `M${vs.map(at).join("L")}${per === 3 ? "Z" : ""}`;
          for (const v of vs) depth += toward[view] * pos[3 * v + az];
        }
        depth /= o.count * per;
        const style = per === 3 ? { fill: colour, stroke: colour, "stroke-width": 0.3 * px } : { fill: "none", stroke: colour, "stroke-width": 1.6, "vector-effect": "non-scaling-stroke" };
        items.push([depth, li, k, svgEl("path", { d, ...style })]);
      });
    });
    // Far first; lines and points over the faces at the same depth.
    items.sort((a, b) => a[0] - b[0] || (layers[b[1]].per === 3) - (layers[a[1]].per === 3));
    for (const [, li, k, shape] of items) {
      shape.addEventListener("click", () => select(li, k));
      shape.dataset.id = layers[li].L.objects[k].id;
      layers[li].shapes[k] = shape;
      g.append(shape);
    }
    svg.append(g);
    leftOut.textContent = left ? ` ${left} objects are too many to draw here and are left out.` : "";
    if (selected) select(selected[0], selected[1]);
  }
  for (const name of Object.keys(AXES)) {
    buttons.append(el("button", { type: "button", "data-view": name, onclick: () => { view = name; draw(); } }, name));
  }
  function select(li, k) {
    svg.querySelector(".sel")?.classList.remove("sel");
    const L = layers[li].L, o = L.objects[k];
    layers[li].shapes[k]?.classList.add("sel");
    selected = [li, k];
    info.replaceChildren(...figuresTable(o.id, L.name, figuresOf(L, o)));
    info.dataset.selected = o.id;
  }
  // A found object framed: the view zoomed to three times its box (at least a twentieth of
  // the model), centred on it.
  function frame(li, k) {
    const shape = layers[li].shapes[k];
    if (!shape) return;
    const b = shape.getBBox();
    const [x, y, w, h] = svg.getAttribute("viewBox").split(" ").map(Number);
    const side = Math.max(3 * Math.max(b.width, b.height), Math.max(w, h) / 20);
    const cx = b.x + b.width / 2, cy = b.y + b.height / 2;
    svg.setAttribute("viewBox", `${cx - side / 2} ${cy - side / 2} ${side} ${side}`);
  }
  layerControls(layers, layersBox, legend, () => draw());
  zoomable(svg);
  draw();
  return { node, find: finder(layers, (li, k) => { select(li, k); frame(li, k); }).find };
}

// ---------------------------------------------------------------- sheets
const LAYER_STYLE = {
  CUT_OUTER: "stroke:#111;stroke-width:1.2", CUT_INNER: "stroke:#1565c0;stroke-width:1",
  ETCH: "stroke:#c62828;stroke-width:0.6", LEAD: "stroke:#2e7d32;stroke-width:0.8",
  JOINT: "stroke:#ef6c00;stroke-width:1.5", SHEET: "stroke:#9e9e9e;stroke-width:1;stroke-dasharray:6 4",
  REMNANT: "stroke:#8bc34a;stroke-width:0.8;stroke-dasharray:3 3",
};

function buildSheets(data, stage, info) {
  const node = el("div", { class: "lv-sheets" });
  stage.append(node);
  const legend = el("p", { class: "lv-sub" });
  for (const [k, s] of Object.entries(LAYER_STYLE)) {
    const sw = svgEl("svg", { width: 22, height: 8 });
    sw.append(svgEl("line", { x1: 1, y1: 4, x2: 21, y2: 4, style: s }));
    legend.append(sw, ` ${k.toLowerCase().replace("_", " ")}  `);
  }
  node.append(legend, el("p", { class: "lv-sub" }, "Blue numbers: the cut order on each sheet. Wheel to zoom, drag to pan, click a part."));
  const partEls = [];
  let selectedEl = null;
  data.sheets.forEach((sheet, si) => {
    const [w, h] = sheet.size;
    const svg = svgEl("svg", { viewBox: `${-0.02 * w} ${-1.02 * h} ${1.04 * w} ${1.04 * h}`, class: "lv-sheet" });
    const g = svgEl("g", { transform: "scale(1,-1)" });
    g.append(svgEl("rect", { x: 0, y: 0, width: w, height: h, style: "fill:#fff;stroke:#9e9e9e;stroke-width:1" }));
    const scale = Math.max(w, h) / 900;
    const placed = [];
    let hidden = 0;
    for (const p of sheet.paths) {
      const pts = [];
      for (let i = 0; i < p.points.length; i += 2) pts.push(`${p.points[i]},${p.points[i + 1]}`);
      const e = svgEl(p.closed ? "polygon" : "polyline", { points: pts.join(" "), style: `fill:none;${LAYER_STYLE[p.layer] || "stroke:#555"}`, "vector-effect": "non-scaling-stroke" });
      g.append(e);
    }
    sheet.parts.forEach((part, pi) => {
      const [x0, y0, x1, y1] = part.bbox;
      const hit = svgEl("rect", { x: x0, y: y0, width: x1 - x0, height: y1 - y0, class: "lv-part" });
      hit.addEventListener("click", () => selectPart(si, pi, false));
      hit.append(svgEl("title"));
      hit.firstChild.textContent = part.id;
      g.append(hit);
      // A cut-order number where it overlaps no number already placed (in cut order); the
      // others are in the part's figures.
      const fs = 14 * scale, tw = 0.62 * fs * String(part.order).length;
      const label = [part.start[0], part.start[1], part.start[0] + tw, part.start[1] + fs];
      if (placed.every((o) => label[0] >= o[2] || label[2] <= o[0] || label[1] >= o[3] || label[3] <= o[1])) {
        placed.push(label);
        const t = svgEl("text", { x: part.start[0], y: -part.start[1], transform: "scale(1,-1)", class: "lv-order", "font-size": fs });
        t.textContent = part.order;
        g.append(t);
      } else hidden += 1;
      partEls.push({ si, pi, hit, id: part.id.toLowerCase() });
    });
    svg.append(g);
    zoomable(svg);
    const fig = el("figure", { class: "lv-sheet-fig", id: `sheet-${si}` }, svg,
      el("figcaption", {}, `${sheet.name}: ${sheet.figures.map(([k, v]) => `${k} ${v}`).join(" · ")}` +
        (hidden ? ` (${hidden} cut-order numbers left off where they would overlap others: click a part for its own)` : "")));
    fig.addEventListener("click", (e) => {
      if (e.target.classList?.contains("lv-part")) return;
      info.replaceChildren(...figuresTable(sheet.name, "sheet", sheet.figures));
    });
    node.append(fig);
  });

  function selectPart(si, pi, scroll) {
    const sheet = data.sheets[si];
    const part = sheet.parts[pi];
    selectedEl?.classList.remove("sel");
    selectedEl = partEls.find((p) => p.si === si && p.pi === pi).hit;
    selectedEl.classList.add("sel");
    info.replaceChildren(...figuresTable(part.id, `part on ${sheet.name}`, part.figures));
    info.dataset.selected = part.id;
    if (scroll) selectedEl.closest("figure").scrollIntoView({ block: "center" });
  }
  return {
    node,
    find(q, exact) {
      const p = partEls.find((p) => (exact ? p.id === q : p.id.includes(q)));
      return p ? () => selectPart(p.si, p.pi, true) : null;
    },
  };
}

function zoomable(svg) {
  const vb = () => svg.getAttribute("viewBox").split(" ").map(Number);
  svg.addEventListener("wheel", (e) => {
    e.preventDefault();
    const [x, y, w, h] = vb();
    const r = svg.getBoundingClientRect();
    const fx = (e.clientX - r.left) / r.width, fy = (e.clientY - r.top) / r.height;
    const k = e.deltaY > 0 ? 1.2 : 1 / 1.2;
    svg.setAttribute("viewBox", `${x + fx * w * (1 - k)} ${y + fy * h * (1 - k)} ${w * k} ${h * k}`);
  }, { passive: false });
  let drag = null;
  svg.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY, vb()]; });
  svg.addEventListener("pointermove", (e) => {
    if (!drag || !e.buttons) return;
    const [cx, cy, [x, y, w, h]] = drag;
    const r = svg.getBoundingClientRect();
    svg.setAttribute("viewBox", `${x - ((e.clientX - cx) * w) / r.width} ${y - ((e.clientY - cy) * h) / r.height} ${w} ${h}`);
  });
  svg.addEventListener("pointerup", () => { drag = null; });
}

// ---------------------------------------------------------------- print layers
function buildPrint(P, stage, info) {
  const node = el("div", { class: "lv-print" });
  stage.append(node);
  const n = P.images.length;
  const slider = el("input", { type: "range", min: 0, max: Math.max(0, n - 1), value: 0, "aria-label": "layer" });
  const label = el("span", { class: "lv-layer-label" });
  const byLayer = new Map();
  for (const i of P.islands) {
    if (!byLayer.has(i.layer)) byLayer.set(i.layer, []);
    byLayer.get(i.layer).push(i);
  }
  const islandLayers = [...byLayer.keys()].sort((a, b) => a - b);
  const prev = el("button", { type: "button", onclick: () => jump(-1) }, "◀ island");
  const next = el("button", { type: "button", onclick: () => jump(1) }, "island ▶");
  const [x0, y0, x1, y1] = P.region;
  const pad = 0.06 * Math.max(x1 - x0, y1 - y0);
  const svg = svgEl("svg", { viewBox: `${x0 - pad} ${-y1 - pad} ${x1 - x0 + 2 * pad} ${y1 - y0 + 2 * pad}`, class: "lv-layer-img" });
  const img = svgEl("image", { x: x0, y: -y1, width: x1 - x0, height: y1 - y0, preserveAspectRatio: "none" });
  img.setAttribute("style", "image-rendering:pixelated");
  const marks = svgEl("g");
  svg.append(svgEl("rect", { x: x0 - pad, y: -y1 - pad, width: x1 - x0 + 2 * pad, height: y1 - y0 + 2 * pad, fill: "#000" }), img, marks);
  zoomable(svg);
  node.append(el("div", { class: "lv-print-bar" }, prev, slider, next, label), svg);
  const size = Math.max(x1 - x0, y1 - y0);

  function go(k) {
    k = Math.max(0, Math.min(n - 1, Math.round(k) || 0));
    slider.value = k;
    const url = P.images[k];
    if (url) img.setAttribute("href", url); else img.removeAttribute("href");
    marks.replaceChildren();
    const here = byLayer.get(k) || [];
    for (const i of here) {
      const r = Math.max(Math.sqrt(i.area_mm2 / Math.PI) * 1.8, size * 0.012);
      const c = svgEl("circle", { cx: i.x_mm, cy: -i.y_mm, r, class: "lv-island" });
      c.append(svgEl("title"));
      c.firstChild.textContent = `island at (${i.x_mm.toFixed(2)}, ${i.y_mm.toFixed(2)}) mm, ${i.area_mm2.toFixed(3)} mm²`;
      marks.append(c);
    }
    const z = ((k + 1) * P.layer_mm).toFixed(3);
    label.textContent = `layer ${k} of ${n} (top at ${z} mm): ${here.length === 1 ? "1 island starts" : `${here.length} islands start`} here`;
    const rows = [["layer", `${k} of ${n}`], ["top", `${z} mm`], ["islands starting here", String(here.length)]];
    here.slice(0, 20).forEach((i, j) => rows.push([`island ${j + 1}`, `(${i.x_mm.toFixed(2)}, ${i.y_mm.toFixed(2)}) mm, ${i.area_mm2.toFixed(3)} mm²`]));
    info.replaceChildren(...figuresTable(`layer ${k}`, P.name, rows.concat(P.figures)));
    info.dataset.selected = `layer ${k}`;
    node.dataset.layer = k;
  }
  function jump(dir) {
    const k = Number(slider.value);
    const t = dir > 0 ? islandLayers.find((l) => l > k) : [...islandLayers].reverse().find((l) => l < k);
    if (t !== undefined) go(t);
  }
  slider.addEventListener("input", () => go(Number(slider.value)));
  let started = false;
  return {
    node,
    go,
    shown() { if (!started) { started = true; go(Number(slider.value)); } },
    find(q) {
      const m = /^layer\s*(\d+)$/.exec(q);
      return m ? () => { started = true; go(Number(m[1])); } : null;
    },
  };
}

// ---------------------------------------------------------------- start
let THREE, OrbitControls;
try {
  const data = JSON.parse(text("lamina-data"));
  if (data.layers.length) {
    const core = scriptUrl(text("three-core"));
    const moduleUrl = scriptUrl(text("three-module").replaceAll('"./three.core.min.js"', JSON.stringify(core)));
    THREE = await import(moduleUrl);
    ({ OrbitControls } = await import(scriptUrl(text("three-orbit").replaceAll("from 'three'", `from ${JSON.stringify(moduleUrl)}`))));
  }
  start(data);
} catch (e) {
  root.append(el("p", { class: "lv-error" }, `The viewer could not start: ${e && e.message ? e.message : e}`));
  throw e;
}
