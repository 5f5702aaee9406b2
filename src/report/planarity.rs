//! The planarity report of a set of panels, from `planarize` or `audit`: a summary (maximum,
//! mean and 95th-percentile deviation, panels above the tolerance, the solver's convergence
//! curve), the worst panels, a histogram, and three views (top, front, isometric) of the panels
//! coloured by deviation. As JSON, and as one self-contained HTML page with inline SVG.

use crate::text::html;
use std::fmt::Write as _;

use glam::DVec3;

use crate::rationalize::panels::QuadMetrics;

/// How many panels the worst-panel table lists.
pub const WORST: usize = 20;
/// Histogram bins.
pub const BINS: usize = 20;
/// The most panels a view draws (the page stays a few megabytes).
pub const VIEW_PANELS: usize = 20_000;
/// The most panels the embedded 3D viewer shows (about 40 MB of page).
pub const VIEWER_PANELS: usize = 200_000;

/// The figure a tolerance is held against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// ISO 1101 minimum-zone flatness.
    #[default]
    Flatness,
    /// The largest distance from the least-squares plane.
    BestFit,
    /// The distance of the fourth corner from the plane of the other three.
    Corner,
}

impl Metric {
    pub fn name(self) -> &'static str {
        match self {
            Metric::Flatness => "flatness",
            Metric::BestFit => "best-fit",
            Metric::Corner => "corner",
        }
    }

    /// The figure of a panel.
    pub fn of(self, m: &QuadMetrics) -> f64 {
        match self {
            Metric::Flatness => m.flatness,
            Metric::BestFit => m.best_fit,
            Metric::Corner => m.deviation,
        }
    }
}

/// Each figure of a panel row, as the JSON report and the page define it.
pub const DEFINITIONS: [(&str, &str); 10] = [
    ("flatness", "ISO 1101 flatness, mm: the width of the thinnest zone between two parallel planes that holds every corner of the panel (the minimum zone), exact"),
    ("best_fit", "mm: the largest distance of a corner from the least-squares plane through the corners"),
    ("deviation", "the corner figure, mm: the distance of the fourth corner from the plane through the other three (quads; for other polygons the largest distance from the plane through the centroid with the Newell normal); on a twisted square 2 times the flatness and 4 times the best-fit figure"),
    ("diagonal_distance", "mm: the distance between the lines of the two diagonals (quads)"),
    ("diagonal_rel_edge", "the diagonal distance over the mean edge length (COMPAS's planarity)"),
    ("diagonal_rel_diagonal", "warp: the diagonal distance over the mean diagonal length (libigl's planarity)"),
    ("torsion_deg", "degrees: the angle between the planes (q0, q1, q3) and (q0, q1, q2) along the edge q0q1 (quads)"),
    ("normal", "the unit normal of the minimum zone, turned to agree with the polygon's Newell normal"),
    ("tolerance", "mm: the largest held figure the panel may have: the one tolerance given, or its class's mm + relative × size, size being the largest distance between two of its corners"),
    ("pass", "whether the held figure (the summary's metric) is at most the panel's tolerance"),
];

/// What the report is about: where the panels came from and how they were solved.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Context {
    pub title: String,
    pub source: String,
    pub method: Option<String>,
    pub iterations: Option<usize>,
    pub seconds: Option<f64>,
    pub alpha_requested: Option<f64>,
    pub alpha_used: Option<f64>,
    /// The objective (or deviation) after each iteration.
    pub history: Vec<f64>,
    pub notes: Vec<String>,
}

#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PanelRow {
    pub index: usize,
    /// The network edge's nodes, when the panels came from a network.
    pub nodes: Option<[u32; 2]>,
    /// The panel's own name (a plate's tag), its DXF layer, its OBJ group or assembly group.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub layer: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
    /// The tolerance this panel is held to, mm, and the class (rule) that gave it.
    pub tolerance: f64,
    #[serde(skip)]
    pub class: Option<usize>,
    #[serde(rename = "class", skip_serializing_if = "Option::is_none")]
    pub class_name: Option<String>,
    /// Whether the held figure is within the tolerance.
    pub pass: bool,
    #[serde(flatten)]
    pub metrics: QuadMetrics,
}

/// A tolerance class of an audit and how its panels fared.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Class {
    pub name: String,
    /// What the class matches and allows, as the rule file says it.
    pub rule: String,
    pub panels: usize,
    pub above_tolerance: usize,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Summary {
    pub panels: usize,
    /// The figure the tolerance is held against; the max, mean and 95th percentile are of it.
    pub metric: Metric,
    /// The tolerance of every panel, or of those no class rule matched; None when only the
    /// rules give tolerances.
    pub tolerance: Option<f64>,
    /// The tolerance classes, when a rule file gave them (the last, "default", for panels no
    /// rule matched).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub classes: Vec<Class>,
    /// The largest ratio of the held figure to the panel's own tolerance.
    pub max_ratio: f64,
    pub max_deviation: f64,
    pub mean_deviation: f64,
    pub p95_deviation: f64,
    pub above_tolerance: usize,
    pub within_tolerance: bool,
    pub max_flatness: f64,
    pub max_best_fit: f64,
    pub max_corner: f64,
    pub max_diagonal_distance: f64,
    pub max_torsion_deg: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Histogram {
    /// Bin edges in mm, BINS + 1 of them.
    pub edges: Vec<f64>,
    pub counts: Vec<usize>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    #[serde(flatten)]
    pub context: Context,
    pub summary: Summary,
    pub definitions: std::collections::BTreeMap<&'static str, &'static str>,
    pub worst: Vec<PanelRow>,
    pub histogram: Histogram,
    pub panels: Vec<PanelRow>,
    /// Panel corners for the views; not written to JSON (the panels file has them).
    #[serde(skip)]
    pub quads: Vec<Vec<DVec3>>,
}

impl Report {
    /// The report of `rows`, each with its tolerance (and class, an index into `classes`, given
    /// as (name, rule) pairs); `tolerance` is the default one.
    pub fn new(
        context: Context,
        mut rows: Vec<PanelRow>,
        quads: Vec<Vec<DVec3>>,
        tolerance: Option<f64>,
        classes: Vec<(String, String)>,
        metric: Metric,
    ) -> Report {
        let n = rows.len();
        let mut classes: Vec<Class> = classes
            .into_iter()
            .map(|(name, rule)| Class {
                name,
                rule,
                panels: 0,
                above_tolerance: 0,
            })
            .collect();
        let mut above = 0;
        let mut max_ratio: f64 = 0.0;
        for r in rows.iter_mut() {
            let figure = metric.of(&r.metrics);
            // NaN (no flatness for a huge polygon) fails.
            r.pass = figure <= r.tolerance;
            above += usize::from(!r.pass);
            max_ratio = max_ratio.max(figure / r.tolerance);
            if let Some(c) = r.class.and_then(|k| classes.get_mut(k)) {
                c.panels += 1;
                c.above_tolerance += usize::from(!r.pass);
                r.class_name = Some(c.name.clone());
            }
        }
        let mut devs: Vec<f64> = rows.iter().map(|r| metric.of(&r.metrics)).collect();
        let max = devs.iter().copied().fold(0.0, f64::max);
        let mean = if n > 0 {
            devs.iter().sum::<f64>() / n as f64
        } else {
            0.0
        };
        let p95 = if n > 0 {
            let k = ((n as f64 * 0.95).ceil() as usize).clamp(1, n) - 1;
            *devs.select_nth_unstable_by(k, f64::total_cmp).1
        } else {
            0.0
        };
        // NaN when no panel has the figure (flatness of polygons beyond the exact search).
        let largest = |f: &dyn Fn(&QuadMetrics) -> f64| {
            rows.iter().map(|r| f(&r.metrics)).fold(f64::NAN, f64::max)
        };
        let summary = Summary {
            panels: n,
            metric,
            tolerance,
            classes,
            max_ratio,
            max_deviation: max,
            mean_deviation: mean,
            p95_deviation: p95,
            above_tolerance: above,
            within_tolerance: above == 0,
            max_flatness: largest(&|m| m.flatness),
            max_best_fit: largest(&|m| m.best_fit),
            max_corner: largest(&|m| m.deviation),
            max_diagonal_distance: rows
                .iter()
                .map(|r| r.metrics.diagonal_distance)
                .fold(0.0, f64::max),
            max_torsion_deg: rows
                .iter()
                .map(|r| r.metrics.torsion_deg)
                .fold(0.0, f64::max),
        };
        // The worst panels relative to their own tolerances (failures first), NaN first of all.
        let ratio = |k: usize| {
            let r = metric.of(&rows[k].metrics) / rows[k].tolerance;
            if r.is_nan() {
                f64::INFINITY
            } else {
                r
            }
        };
        let by_ratio = |&a: &usize, &b: &usize| ratio(b).total_cmp(&ratio(a)).then(a.cmp(&b));
        let mut order: Vec<usize> = (0..n).collect();
        if n > WORST {
            order.select_nth_unstable_by(WORST, by_ratio);
            order.truncate(WORST);
        }
        order.sort_by(by_ratio);
        let worst = order.iter().map(|&k| rows[k].clone()).collect();
        let top = if max > 0.0 {
            max
        } else {
            tolerance.unwrap_or(1.0)
        };
        let edges: Vec<f64> = (0..=BINS).map(|k| top * k as f64 / BINS as f64).collect();
        let mut counts = vec![0usize; BINS];
        for d in devs.iter().filter(|d| !d.is_nan()) {
            let k = ((d / top) * BINS as f64) as usize;
            counts[k.min(BINS - 1)] += 1;
        }
        Report {
            context,
            summary,
            definitions: DEFINITIONS.into_iter().collect(),
            worst,
            histogram: Histogram { edges, counts },
            panels: rows,
            quads,
        }
    }

    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("reports serialise") + "\n"
    }

    /// One self-contained HTML page.
    pub fn html(&self) -> String {
        let s = &self.summary;
        let c = &self.context;
        let mut h = String::new();
        let _ = write!(
            h,
            "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>{}</title>\n\
             <style>body{{font:15px/1.45 system-ui,sans-serif;margin:2em auto;max-width:72em;color:#222}}\
             table{{border-collapse:collapse}}td,th{{padding:2px 10px;border-bottom:1px solid #ddd;text-align:right}}\
             .views{{display:flex;flex-wrap:wrap;gap:1em}}.views figure{{margin:0}}\
             .ok{{color:#186a1e}}.bad{{color:#a3161a}}</style></head><body>\n<h1>{}</h1>\n",
            html(&c.title),
            html(&c.title)
        );
        let within = match (s.tolerance, s.classes.is_empty()) {
            (Some(t), true) => format!("{t} mm"),
            _ => "their class's tolerance".to_string(),
        };
        let verdict = if s.within_tolerance {
            format!(
                "<p class=\"ok\">All {} panels are within {within} ({}).</p>",
                s.panels,
                s.metric.name()
            )
        } else {
            format!(
                "<p class=\"bad\">{} of {} panels exceed {within} ({}).</p>",
                s.above_tolerance,
                s.panels,
                s.metric.name()
            )
        };
        h.push_str(&verdict);
        h.push_str("<table>\n");
        let mut row = |k: &str, v: String| {
            let _ = writeln!(
                h,
                "<tr><th style=\"text-align:left\">{k}</th><td>{v}</td></tr>"
            );
        };
        row("source", html(&c.source));
        if let Some(m) = &c.method {
            row("method", html(m));
        }
        if let Some(i) = c.iterations {
            row("iterations", i.to_string());
        }
        if let Some(t) = c.seconds {
            row("time", format!("{:.3} ms", t * 1e3));
        }
        if let (Some(a), Some(u)) = (c.alpha_requested, c.alpha_used) {
            row(
                "α requested / used",
                format!("{} / {}", crate::text::sig3(a), crate::text::sig3(u)),
            );
        }
        let held = s.metric.name();
        row("held to the tolerance", held.to_string());
        if let Some(t) = s.tolerance {
            let what = if s.classes.is_empty() {
                "tolerance"
            } else {
                "default tolerance"
            };
            row(what, format!("{t} mm"));
        }
        row(
            &format!("max {held} / tolerance"),
            format!("{:.4}", s.max_ratio),
        );
        row(&format!("max {held}"), format!("{:.6} mm", s.max_deviation));
        row(
            &format!("mean {held}"),
            format!("{:.6} mm", s.mean_deviation),
        );
        row(
            &format!("95th percentile of {held}"),
            format!("{:.6} mm", s.p95_deviation),
        );
        row(
            "max flatness (ISO 1101)",
            format!("{:.6} mm", s.max_flatness),
        );
        row("max best-fit distance", format!("{:.6} mm", s.max_best_fit));
        row("max corner figure", format!("{:.6} mm", s.max_corner));
        row(
            "max diagonal distance",
            format!("{:.6} mm", s.max_diagonal_distance),
        );
        row("max torsion", format!("{:.4}°", s.max_torsion_deg));
        h.push_str("</table>\n");
        if !s.classes.is_empty() {
            h.push_str("<h2>Tolerance classes</h2>\n<table><tr><th>class</th><th>rule</th><th>panels</th><th>above</th></tr>\n");
            for k in &s.classes {
                let _ = writeln!(
                    h,
                    "<tr><td>{}</td><td style=\"text-align:left\">{}</td><td>{}</td><td class=\"{}\">{}</td></tr>",
                    html(&k.name),
                    html(&k.rule),
                    k.panels,
                    if k.above_tolerance == 0 { "ok" } else { "bad" },
                    k.above_tolerance
                );
            }
            h.push_str("</table>\n");
        }
        for note in &c.notes {
            let _ = writeln!(h, "<p>{}</p>", html(note));
        }
        h.push_str("<h2>Figures</h2>\n<dl>\n");
        for (k, v) in DEFINITIONS {
            let _ = writeln!(h, "<dt>{k}</dt><dd>{}</dd>", html(v));
        }
        h.push_str("</dl>\n");
        h.push_str(&self.viewer());
        let _ = writeln!(
            h,
            "<h2>Panels by {}</h2>\n<div class=\"views\">",
            s.metric.name()
        );
        for (name, view) in [
            ("top", View::Top),
            ("front", View::Front),
            ("isometric", View::Iso),
        ] {
            let _ = writeln!(
                h,
                "<figure>{}<figcaption>{name}</figcaption></figure>",
                self.view_svg(view)
            );
        }
        let _ = writeln!(
            h,
            "</div>\n<p>Colour: green at 0, red at the panel's tolerance or above.{}</p>",
            if self.panels.len() > VIEW_PANELS {
                format!(
                    " The views draw {} of the {} panels: those above their tolerance first, then an even sample of the rest.",
                    self.drawn().len(),
                    self.panels.len()
                )
            } else {
                String::new()
            }
        );
        let _ = writeln!(
            h,
            "<h2>Histogram</h2>\n<p>How many panels have each value of the held figure ({}; defined above), in {BINS} equal bins from 0 to the largest.</p>",
            s.metric.name()
        );
        h.push_str(&self.histogram_svg());
        if !c.history.is_empty() {
            // Projection records its largest deviation; the solvers their objective.
            let projection = c
                .method
                .as_deref()
                .is_some_and(|m| m.to_lowercase().contains("projection"));
            let (label, what) = if projection {
                (
                    "largest panel deviation, mm (log scale)",
                    "The largest corner deviation over the panels after each sweep.",
                )
            } else {
                (
                    "objective E, no unit (log scale)",
                    "The objective after each iteration: E = Σ over edges of w·(ê·(dᵢ × dⱼ))² + α·Σ over nodes of |dᵢ − bᵢ|², the first term zero exactly when every panel is planar (ê the edge's unit direction, dᵢ the node axes), the second holding axes near their references bᵢ (α as used above).",
                )
            };
            let _ = writeln!(h, "<h2>Convergence</h2>\n<p>{what}</p>");
            h.push_str(&curve_svg(&c.history, label));
        }
        h.push_str("<h2>Worst panels (by figure over tolerance)</h2>\n<table><tr><th>panel</th><th>nodes</th><th>name / layer / group</th><th>tolerance mm</th><th>flatness mm</th>\
                    <th>best fit mm</th><th>corner mm</th><th>diagonals mm</th><th>diag / edge</th><th>diag / diag</th><th>torsion °</th></tr>\n");
        for r in &self.worst {
            let m = &r.metrics;
            let label: Vec<&str> = [&r.name, &r.layer, &r.group]
                .into_iter()
                .flatten()
                .map(String::as_str)
                .collect();
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td class=\"{}\">{}</td><td>{:.6}</td><td>{:.6}</td><td>{:.6}</td><td>{:.6}</td><td>{:.2e}</td><td>{:.2e}</td><td>{:.4}</td></tr>",
                r.index,
                r.nodes.map_or(String::new(), |[a, b]| format!("{a}–{b}")),
                html(&label.join(" / ")),
                if r.pass { "ok" } else { "bad" },
                r.tolerance,
                m.flatness,
                m.best_fit,
                m.deviation,
                m.diagonal_distance,
                m.diagonal_rel_edge,
                m.diagonal_rel_diagonal,
                m.torsion_deg
            );
        }
        h.push_str("</table>\n</body></html>\n");
        h
    }

    /// The panels in the 3D viewer, coloured by the held figure (or a note when there are too
    /// many for a page).
    fn viewer(&self) -> String {
        if self.panels.len() > VIEWER_PANELS {
            return format!(
                "<p>{} panels: more than the 3D viewer embeds ({VIEWER_PANELS}); the views below draw a sample.</p>\n",
                self.panels.len()
            );
        }
        let origin = crate::view::pack::middle(self.quads.iter().flatten().copied());
        match crate::view::pack::panels(&self.quads, &self.panels, self.summary.metric, origin) {
            Ok(layer) => {
                let scene = crate::view::Scene {
                    title: self.context.title.clone(),
                    origin: origin.to_array(),
                    layers: vec![layer],
                    ..Default::default()
                };
                format!(
                    "<h2>Look around</h2>\n<p>Drag to turn, right-drag to pan, wheel to zoom; hover or click a panel for its figures; find a panel by its id (P and its index).</p>\n{}",
                    crate::view::embed(&scene, "70vh")
                )
            }
            Err(e) => format!("<p>No 3D view: {}</p>\n", html(&e.to_string())),
        }
    }

    fn view_svg(&self, view: View) -> String {
        let project = |p: DVec3| -> (f64, f64) {
            match view {
                View::Top => (p.x, -p.y),
                View::Front => (p.x, -p.z),
                View::Iso => {
                    // Looking down (1, 1, 1): x right-down, y left-down, z up.
                    let c = std::f64::consts::FRAC_PI_6.cos();
                    ((p.x - p.y) * c, (p.x + p.y) * 0.5 - p.z)
                }
            }
        };
        let drawn = self.drawn();
        let pts: Vec<(f64, f64)> = drawn
            .iter()
            .flat_map(|&k| &self.quads[k])
            .map(|p| project(*p))
            .collect();
        let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
        for &(x, y) in &pts {
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        if pts.is_empty() {
            return String::new();
        }
        let (w, hgt) = ((hi.0 - lo.0).max(1e-9), (hi.1 - lo.1).max(1e-9));
        let size = 360.0;
        let k = size / w.max(hgt);
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0}\" height=\"{:.0}\" viewBox=\"-4 -4 {:.1} {:.1}\">",
            w * k + 8.0,
            hgt * k + 8.0,
            w * k + 8.0,
            hgt * k + 8.0
        );
        for &i in &drawn {
            let (q, row) = (&self.quads[i], &self.panels[i]);
            let t = (self.summary.metric.of(&row.metrics) / row.tolerance).clamp(0.0, 1.0);
            let t = if t.is_nan() { 1.0 } else { t };
            let (r, g) = ((40.0 + 200.0 * t) as u8, (160.0 - 130.0 * t) as u8);
            let mut d = String::new();
            for (i, p) in q.iter().enumerate() {
                let (x, y) = project(*p);
                let _ = write!(
                    d,
                    "{}{:.2} {:.2}",
                    if i == 0 { "M" } else { " L" },
                    (x - lo.0) * k,
                    (y - lo.1) * k
                );
            }
            let _ = write!(
                s,
                "<path d=\"{d} Z\" fill=\"rgb({r},{g},60)\" fill-opacity=\"0.55\" stroke=\"#333\" stroke-width=\"0.3\"/>"
            );
        }
        s.push_str("</svg>");
        s
    }

    /// The panels the views draw: all of them up to `VIEW_PANELS`, else `VIEW_PANELS` of
    /// them: every failing one (an even sample if there are more) and an even sample of the
    /// others in the room left.
    fn drawn(&self) -> Vec<usize> {
        let n = self.panels.len().min(self.quads.len());
        if n <= VIEW_PANELS {
            return (0..n).collect();
        }
        let failing = self.panels[..n].iter().filter(|r| !r.pass).count();
        let fail_room = failing.min(VIEW_PANELS);
        let pass_room = VIEW_PANELS - fail_room;
        let stride = |count: usize, room: usize| {
            if room == 0 {
                usize::MAX
            } else {
                count.div_ceil(room).max(1)
            }
        };
        let (fail_stride, pass_stride) =
            (stride(failing, fail_room), stride(n - failing, pass_room));
        let (mut fails, mut passes) = (0usize, 0usize);
        (0..n)
            .filter(|&k| {
                let (seen, every) = if self.panels[k].pass {
                    (&mut passes, pass_stride)
                } else {
                    (&mut fails, fail_stride)
                };
                *seen += 1;
                (*seen - 1) % every == 0
            })
            .collect()
    }

    fn histogram_svg(&self) -> String {
        let hgm = &self.histogram;
        let max = hgm.counts.iter().copied().max().unwrap_or(1).max(1) as f64;
        let (bw, hh, left) = (24.0, 160.0, 64.0);
        let width = bw * BINS as f64 + left + 30.0;
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{}\" font-size=\"11\">",
            hh + 64.0
        );
        for (k, &c) in hgm.counts.iter().enumerate() {
            let bh = hh * c as f64 / max;
            let _ = write!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"#5a8f4e\"><title>{:.4}–{:.4} mm: {c}</title></rect>",
                k as f64 * bw + left,
                hh - bh + 10.0,
                bw - 2.0,
                bh,
                hgm.edges[k],
                hgm.edges[k + 1]
            );
        }
        let right = bw * BINS as f64 + left;
        let held = self.summary.metric.name();
        let _ = write!(
            s,
            "<line x1=\"{left}\" y1=\"{b}\" x2=\"{right}\" y2=\"{b}\" stroke=\"#444\"/>\
             <line x1=\"{l}\" y1=\"10\" x2=\"{l}\" y2=\"{b}\" stroke=\"#444\"/>\
             <text x=\"{left}\" y=\"{t}\" text-anchor=\"middle\">0</text>\
             <text x=\"{right}\" y=\"{t}\" text-anchor=\"middle\">{top:.4}</text>\
             <text x=\"{l2}\" y=\"14\" text-anchor=\"end\">{max}</text>\
             <text x=\"{l2}\" y=\"{b}\" text-anchor=\"end\">0</text>\
             <text x=\"{mid}\" y=\"{xt}\" text-anchor=\"middle\" font-size=\"12\">{held} of the panel, mm ({BINS} bins)</text>\
             <text transform=\"translate(16 {ym}) rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">panels</text></svg>",
            b = hh + 10.0,
            l = left - 2.0,
            l2 = left - 6.0,
            t = hh + 24.0,
            top = hgm.edges[BINS],
            max = max as usize,
            mid = (left + right) / 2.0,
            xt = hh + 44.0,
            ym = hh / 2.0 + 10.0,
        );
        s
    }
}

#[derive(Clone, Copy)]
enum View {
    Top,
    Front,
    Iso,
}

/// The convergence curve on a log scale, with a tick at each power of ten it spans.
fn curve_svg(history: &[f64], label: &str) -> String {
    let vals: Vec<f64> = history.iter().map(|v| v.max(1e-300).log10()).collect();
    let (lo, hi) = vals
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
    // Whole decades around the values, so every tick is a power of ten.
    let (lo, hi) = (lo.floor(), hi.ceil().max(lo.floor() + 1.0));
    let span = hi - lo;
    let (w, h, left) = (560.0, 200.0, 70.0);
    let n = (vals.len().max(2) - 1) as f64;
    let x = |i: f64| left + w * i / n;
    let y = |v: f64| 10.0 + h * (hi - v) / span;
    let mut d = String::new();
    for (i, v) in vals.iter().enumerate() {
        let _ = write!(
            d,
            "{}{:.1} {:.1}",
            if i == 0 { "M" } else { " L" },
            x(i as f64),
            y(*v)
        );
    }
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-size=\"11\">\
         <line x1=\"{left}\" y1=\"{b}\" x2=\"{r}\" y2=\"{b}\" stroke=\"#444\"/>\
         <line x1=\"{left}\" y1=\"10\" x2=\"{left}\" y2=\"{b}\" stroke=\"#444\"/>",
        w + left + 20.0,
        h + 60.0,
        b = h + 10.0,
        r = left + w,
    );
    let step = (span / 8.0).ceil().max(1.0);
    let mut e = lo;
    while e <= hi + 1e-9 {
        let _ = write!(
            s,
            "<line x1=\"{:.1}\" y1=\"{yy:.1}\" x2=\"{left}\" y2=\"{yy:.1}\" stroke=\"#444\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">10<tspan dy=\"-5\" font-size=\"9\">{}</tspan></text>",
            left - 4.0,
            left - 8.0,
            y(e) + 4.0,
            e as i64,
            yy = y(e),
        );
        e += step;
    }
    let last = vals.len().saturating_sub(1);
    let _ = write!(
        s,
        "<path d=\"{d}\" fill=\"none\" stroke=\"#2b5d8a\" stroke-width=\"1.5\"/>\
         <text x=\"{left}\" y=\"{t}\" text-anchor=\"middle\">0</text>\
         <text x=\"{r}\" y=\"{t}\" text-anchor=\"middle\">{last}</text>\
         <text x=\"{mid}\" y=\"{xt}\" text-anchor=\"middle\" font-size=\"12\">iteration</text>\
         <text transform=\"translate(16 {ym}) rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">{label}</text></svg>",
        t = h + 24.0,
        r = left + w,
        mid = left + w / 2.0,
        xt = h + 44.0,
        ym = h / 2.0 + 10.0,
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rationalize::panels::quad_metrics;

    #[test]
    fn summary_figures_and_a_self_contained_page() {
        let quads: Vec<Vec<DVec3>> = (0..10)
            .map(|k| {
                let lift = k as f64 * 0.001;
                vec![
                    DVec3::new(k as f64, 0.0, 0.0),
                    DVec3::new(k as f64 + 1.0, 0.0, 0.0),
                    DVec3::new(k as f64 + 1.0, lift, 1.0),
                    DVec3::new(k as f64, 0.0, 1.0),
                ]
            })
            .collect();
        let rows: Vec<PanelRow> = quads
            .iter()
            .enumerate()
            .map(|(k, q)| PanelRow {
                index: k,
                tolerance: 0.005,
                metrics: quad_metrics([q[0], q[1], q[2], q[3]]),
                ..Default::default()
            })
            .collect();
        let r = Report::new(
            Context {
                title: "test".into(),
                history: vec![1.0, 0.1, 0.01],
                ..Default::default()
            },
            rows,
            quads,
            Some(0.005),
            Vec::new(),
            Metric::Corner,
        );
        assert!((r.summary.max_deviation - 0.009).abs() < 1e-12);
        assert_eq!(r.summary.above_tolerance, 4);
        assert!(!r.summary.within_tolerance);
        assert_eq!(r.worst[0].index, 9);
        assert_eq!(r.histogram.counts.iter().sum::<usize>(), 10);
        let html = r.html();
        assert_eq!(html.matches("<svg").count(), 5, "3 views, histogram, curve");
        assert!(
            !html.contains("http://") || !html.contains("src=\"http"),
            "no outside resources"
        );
        let json: serde_json::Value = serde_json::from_str(&r.json()).expect("valid JSON");
        assert_eq!(json["summary"]["panels"], 10);
    }
}
