// Peer for the venation benchmark: open space colonisation written the way most JavaScript
// sketches of Runions et al. 2005 write it, with no spatial index: every step, every source
// scans every node for its closest, each pulled node grows one segment of length D, and every
// source is tested against every new node for the kill distance. This is our own plain
// re-implementation of that common pattern, not any particular project's code.
//
// usage: node venation_naive.js job.json   (job: {outline, root, sources, step, kill, max_iterations})
"use strict";
const fs = require("fs");
const job = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
const outline = job.outline;

function inside(x, y) {
  let c = false;
  for (let i = 0, j = outline.length - 1; i < outline.length; j = i++) {
    const [xi, yi] = outline[i], [xj, yj] = outline[j];
    if ((yi > y) !== (yj > y) && x < ((xj - xi) * (y - yi)) / (yj - yi) + xi) c = !c;
  }
  return c;
}

const nx = [job.root[0]], ny = [job.root[1]], parent = [-1];
let sx = job.sources.map((s) => s[0]), sy = job.sources.map((s) => s[1]);
const D = job.step, kill2 = job.kill * job.kill;
const t0 = Date.now();
let steps = 0;
for (; steps < job.max_iterations && sx.length > 0; steps++) {
  const n = nx.length;
  const px = new Float64Array(n), py = new Float64Array(n), pulled = new Uint8Array(n);
  for (let s = 0; s < sx.length; s++) {
    let best = -1, bd = Infinity;
    for (let v = 0; v < n; v++) {
      const dx = sx[s] - nx[v], dy = sy[s] - ny[v], d = dx * dx + dy * dy;
      if (d < bd) { bd = d; best = v; }
    }
    const l = Math.sqrt(bd);
    if (l > 0) { px[best] += (sx[s] - nx[best]) / l; py[best] += (sy[s] - ny[best]) / l; pulled[best] = 1; }
  }
  let grown = 0;
  for (let v = 0; v < n; v++) {
    if (!pulled[v]) continue;
    const l = Math.hypot(px[v], py[v]);
    if (l === 0) continue;
    const x = nx[v] + (D * px[v]) / l, y = ny[v] + (D * py[v]) / l;
    if (!inside(x, y)) continue;
    let crowded = false;
    for (let u = 0; u < nx.length && !crowded; u++) {
      const dx = x - nx[u], dy = y - ny[u];
      crowded = dx * dx + dy * dy < 0.25 * D * D;
    }
    if (crowded) continue;
    nx.push(x); ny.push(y); parent.push(v); grown++;
  }
  const keepX = [], keepY = [];
  for (let s = 0; s < sx.length; s++) {
    let dead = false;
    for (let v = n; v < nx.length && !dead; v++) {
      const dx = sx[s] - nx[v], dy = sy[s] - ny[v];
      dead = dx * dx + dy * dy < kill2;
    }
    if (!dead) { keepX.push(sx[s]); keepY.push(sy[s]); }
  }
  sx = keepX; sy = keepY;
  if (grown === 0) break;
}
console.log(JSON.stringify({ nodes: nx.length, steps, sources_left: sx.length, seconds: (Date.now() - t0) / 1000 }));
