//! The sizing report: one self-contained HTML page with the frame in the 3D viewer, SVG views of
//! the structure coloured by utilisation and by gauge, the deformed shape, the figures' definitions
//! and tables.

use crate::text::html;
use std::fmt::Write as _;

use glam::DVec3;

use super::material::Material;
use super::sizing::Sizing;

/// What the sizing figures mean (sizing.json's `definitions` and the page say the same).
pub const UTILISATION: &str = "the largest over the ultimate combinations (EN 1990 6.10) and five points along the member of: stress = von Mises of the largest corner normal stress (N, My, Mz) and the largest shear stress (torsion + 1.5 V/A) over f_y/gamma_M0; buckling = compression over the weak-axis flexural buckling resistance as a pin-ended strut (EN 1993-1-1 6.3.1.2, curve c), chi A f_y/gamma_M1; lateral-torsional = the largest in-plane moment over chi_LT W_el f_y/gamma_M1 (6.3.2.2, curve d), M_cr = C1 pi/L sqrt(E I_weak G I_t) of the rectangle restrained only at its nodes, C1 from the moment diagram by the quarter-point formula (at most 2.5); interaction = (6.61) and (6.62) with Annex B's factors for elastic sections, C_m = C_mLT = 1, k_zy = 1";
pub const WELD_UTILISATION: &str = "EN 1993-1-8 4.5.3.3 simplified method: the force per length on the two fillet welds (throat a = throat factor x the thinner plate at the node) along each member end's depth, over f_u/(sqrt(3) beta_w gamma_M2) a; the largest over the node's member ends and the ultimate combinations";
/// EN 1993-1-8 §4.5.2(2): a fillet weld's throat is at least 3 mm.
pub const MIN_THROAT: f64 = 3.0;
pub const COMBINATIONS: &str = "EN 1990 with Table A1.2(B): ULS (6.10) the permanent loads (self-weight, or a load marked :G) at 1.35, each variable load (point or wind) leading at 1.5 and the others at 1.5 psi0, and again with the permanent loads at 1.0 (favourable); SLS characteristic (6.14b) the permanent loads at 1, each variable load leading at 1 and the others at psi0; psi0 = 0.6 for wind, 0.7 for point loads (imposed, categories A to D). Members and welds are checked under the ULS combinations, the deflection under the SLS ones";
pub const DISPLACEMENT: &str =
    "under the sum of the loads, at the model's node (mid-height of the axis)";

/// The frame in the viewer: members coloured by utilisation or gauge, nodes by displacement or
/// weld utilisation.
fn viewer(s: &Sizing) -> String {
    use crate::view::{embed, fig, Coloring, Kind, LayerBuilder, Scene};
    let m = &s.model;
    let origin = crate::view::pack::middle(m.nodes.iter().copied());
    let mut members = LayerBuilder::new("members", Kind::Lines, origin);
    for (k, e) in m.members.iter().enumerate() {
        let c = &s.checks[k];
        members.lines(
            format!("E{k}"),
            vec![
                fig("nodes", format!("N{} – N{}", e.a, e.b)),
                fig("gauge", format!("{} mm", s.gauges[k])),
                fig("depth", format!("{:.1} mm", e.section.depth)),
                fig(
                    "utilisation",
                    format!(
                        "{:.3} ({}, {})",
                        c.utilisation, c.check, s.cases[c.case].name
                    ),
                ),
            ],
            &[[m.nodes[e.a], m.nodes[e.b]]],
        );
    }
    let mut util = Coloring::scale(
        "utilisation",
        "",
        UTILISATION,
        s.checks.iter().map(|c| Some(c.utilisation)).collect(),
    );
    util.limit = Some(1.0);
    let gauges: Vec<String> = s.gauges.iter().map(|g| format!("{g} mm")).collect();
    let gauge = Coloring::categories("gauge", "the plate thickness the sizing chose", &gauges);
    let total = s.total();
    let mut nodes = LayerBuilder::new("nodes", Kind::Points, origin);
    let mut moved = Vec::new();
    for (i, &p) in m.nodes.iter().enumerate() {
        let d = total.displacements[i];
        let len = DVec3::new(d[0], d[1], d[2]).length();
        moved.push(Some(len));
        let mut f = vec![fig("displacement", format!("{len:.4} mm"))];
        if let Some(w) = &s.welds[i] {
            f.push(fig(
                "weld utilisation",
                format!("{:.3} ({})", w.utilisation, s.cases[w.case].name),
            ));
        }
        nodes.point(format!("N{i}"), f, p);
    }
    let mut weld = Coloring::scale(
        "weld utilisation",
        "",
        WELD_UTILISATION,
        s.welds
            .iter()
            .map(|w| w.as_ref().map(|w| w.utilisation))
            .collect(),
    );
    weld.limit = Some(1.0);
    let displaced = Coloring::scale("displacement", "mm", DISPLACEMENT, moved);
    let scene = Scene {
        title: "sizing".into(),
        origin: origin.to_array(),
        layers: vec![
            members.finish(vec![util, gauge], true),
            nodes.finish(vec![displaced, weld], true),
        ],
        ..Default::default()
    };
    format!(
        "<h2>Look around</h2><p>The analysis model: a member per edge between nodes at mid-height of the node axes. Hover or click a member or node for its figures; find one by its id (E or N and its index).</p>{}",
        embed(&scene, "70vh")
    )
}

/// Green (0) to yellow to red (1 and over).
fn ramp(t: f64) -> String {
    let t = t.clamp(0.0, 1.0);
    let (r, g) = if t < 0.5 {
        (2.0 * t, 1.0)
    } else {
        (1.0, 2.0 * (1.0 - t))
    };
    format!(
        "#{:02x}{:02x}30",
        (40.0 + 200.0 * r) as u8,
        (40.0 + 160.0 * g) as u8
    )
}

/// Front (x, z) and isometric projections of lines, each with its colour and width.
/// The front and isometric views of `lines`, side by side.
fn figures(h: &mut String, lines: &[(DVec3, DVec3, String, f64)]) {
    for iso in [false, true] {
        let _ = write!(
            h,
            "<figure>{}<figcaption>{}</figcaption></figure>",
            view(lines, iso, 520.0),
            if iso { "isometric" } else { "front (x, z)" }
        );
    }
}

fn view(lines: &[(DVec3, DVec3, String, f64)], iso: bool, size: f64) -> String {
    let project = |p: DVec3| -> (f64, f64) {
        if iso {
            let c = std::f64::consts::FRAC_PI_6.cos();
            ((p.x - p.y) * c, (p.x + p.y) * 0.5 - p.z)
        } else {
            (p.x, -p.z)
        }
    };
    let pts: Vec<(f64, f64)> = lines
        .iter()
        .flat_map(|(a, b, _, _)| [project(*a), project(*b)])
        .collect();
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for &(x, y) in &pts {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    let span = (hi.0 - lo.0).max(hi.1 - lo.1).max(1e-9);
    let k = (size - 20.0) / span;
    let h = (hi.1 - lo.1) * k + 20.0;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{size}\" height=\"{h:.0}\" viewBox=\"0 0 {size} {h:.0}\">"
    );
    for (a, b, colour, width) in lines {
        let (pa, pb) = (project(*a), project(*b));
        let _ = write!(
            s,
            "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{colour}\" stroke-width=\"{width}\"/>",
            (pa.0 - lo.0) * k + 10.0,
            (pa.1 - lo.1) * k + 10.0,
            (pb.0 - lo.0) * k + 10.0,
            (pb.1 - lo.1) * k + 10.0
        );
    }
    s.push_str("</svg>");
    s
}

pub fn sizing_html(s: &Sizing, material: &Material, source: &str) -> String {
    let m = &s.model;
    let total = s.total();
    let (dnode, dmax) = s.max_displacement();
    let gmin = s.gauges.iter().copied().fold(f64::MAX, f64::min);
    let gmax = s.gauges.iter().copied().fold(0.0, f64::max);
    let by = |f: &dyn Fn(usize) -> (String, f64)| -> Vec<(DVec3, DVec3, String, f64)> {
        m.members
            .iter()
            .enumerate()
            .map(|(k, e)| {
                let (c, w) = f(k);
                (m.nodes[e.a], m.nodes[e.b], c, w)
            })
            .collect()
    };
    let util = by(&|k| (ramp(s.checks[k].utilisation), 2.0));
    let gauge = by(&|k| {
        let t = if gmax > gmin {
            (s.gauges[k] - gmin) / (gmax - gmin)
        } else {
            0.0
        };
        (ramp(t), 1.0 + 3.0 * t)
    });
    // Deformed: the largest displacement drawn as a tenth of the span.
    let scale = if dmax > 0.0 { 0.1 * s.span / dmax } else { 0.0 };
    let moved = |i: usize| {
        let d = total.displacements[i];
        m.nodes[i] + DVec3::new(d[0], d[1], d[2]) * scale
    };
    let mut deformed: Vec<(DVec3, DVec3, String, f64)> = m
        .members
        .iter()
        .map(|e| (m.nodes[e.a], m.nodes[e.b], "#bbb".to_string(), 1.0))
        .collect();
    deformed.extend(
        m.members
            .iter()
            .map(|e| (moved(e.a), moved(e.b), "#1f4fbf".to_string(), 1.5)),
    );
    let (max_u, max_w) = (s.max_utilisation(), s.max_weld_utilisation());
    let mut h = String::new();
    let _ = write!(
        h,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Sizing: {src}</title>\
         <style>body{{font:15px/1.45 system-ui,sans-serif;margin:2em auto;max-width:75em;color:#222}}\
         table{{border-collapse:collapse}}td,th{{padding:2px 10px;border-bottom:1px solid #ddd;text-align:right}}\
         .views{{display:flex;flex-wrap:wrap;gap:1em}}figure{{margin:0}}.bad{{color:#a3161a}}</style></head><body>\
         <h1>Sizing: {src}</h1>",
        src = html(source)
    );
    let _ = write!(
        h,
        "<table><tr><th style=\"text-align:left\">material</th><td>{} (E {} MPa, f<sub>y</sub> {} MPa, f<sub>u</sub> {} MPa, γ<sub>M0</sub> {})</td></tr>\
         <tr><th style=\"text-align:left\">analysis</th><td>{}</td></tr>\
         <tr><th style=\"text-align:left\">members / nodes</th><td>{} / {}</td></tr>\
         <tr><th style=\"text-align:left\">load cases</th><td>{}</td></tr>\
         <tr><th style=\"text-align:left\">rounds</th><td>{}{}; {} of stiffening</td></tr>\
         <tr><th style=\"text-align:left\">mass</th><td>{:.2} kg</td></tr>\
         <tr><th style=\"text-align:left\">largest utilisation (members / welds)</th><td>{:.3} / {:.3}</td></tr>\
         <tr><th style=\"text-align:left\">largest displacement</th><td>{:.3} mm at node {}{}</td></tr>\
         <tr><th style=\"text-align:left\">equilibrium residual</th><td>{:.1e}</td></tr></table>",
        html(&material.name),
        material.e,
        material.fy,
        material.fu,
        material.gamma_m0,
        match s.shells {
            None => "frame: a Timoshenko beam per member, rigid joints at mid-height of the node axes".to_string(),
            Some(n) => format!("the panels as flat shells, {n} elements up each, welded along the node axes"),
        },
        m.members.len(),
        m.nodes.len(),
        s.cases.iter().map(|c| html(&c.name)).collect::<Vec<_>>().join("; "),
        s.rounds,
        if s.converged { "" } else { " (the cap: not settled)" },
        s.deflection_rounds,
        s.mass_kg,
        max_u,
        max_w,
        dmax,
        dnode,
        s.deflection_limit
            .map(|l| format!(" (limit {l:.3} mm)"))
            .unwrap_or_default(),
        total.residual
    );
    let _ = write!(
        h,
        "<h2>Figures</h2><dl><dt>utilisation</dt><dd>{}</dd><dt>weld utilisation</dt><dd>{}</dd><dt>displacement (mm)</dt><dd>{}</dd></dl>",
        html(UTILISATION),
        html(WELD_UTILISATION),
        html(DISPLACEMENT)
    );
    h.push_str(&viewer(s));
    h.push_str("<h2>Utilisation</h2><p>Green 0, yellow 0.5, red 1 or more: the larger of the stress and buckling checks over every case.</p><div class=\"views\">");
    figures(&mut h, &util);
    let _ = write!(
        h,
        "</div><h2>Gauges</h2><p>From {gmin} mm (green, thin) to {gmax} mm (red, thick).</p><div class=\"views\">"
    );
    figures(&mut h, &gauge);
    let _ = write!(
        h,
        "</div><h2>Deformed shape</h2><p>Under the sum of the loads, displacements × {} (the largest drawn as a tenth of the span); grey undeformed.</p><div class=\"views\">",
        crate::text::sig3(scale)
    );
    figures(&mut h, &deformed);
    h.push_str("</div><h2>Most utilised members</h2><table><tr><th>edge</th><th>nodes</th><th>gauge mm</th><th>depth mm</th><th>utilisation</th><th>check</th><th>load</th></tr>");
    let mut order: Vec<usize> = (0..m.members.len()).collect();
    order.sort_by(|&a, &b| {
        s.checks[b]
            .utilisation
            .total_cmp(&s.checks[a].utilisation)
            .then(a.cmp(&b))
    });
    for &k in order.iter().take(25) {
        let c = &s.checks[k];
        let _ = write!(
            h,
            "<tr><td>{k}</td><td>{}–{}</td><td>{}</td><td>{:.1}</td><td{}>{:.3}</td><td>{}</td><td>{}</td></tr>",
            m.members[k].a,
            m.members[k].b,
            s.gauges[k],
            m.members[k].section.depth,
            if c.utilisation > 1.0 { " class=\"bad\"" } else { "" },
            c.utilisation,
            c.check,
            html(&s.cases[c.case].name)
        );
    }
    h.push_str("</table><h2>Reactions</h2><table><tr><th>node</th><th>F<sub>x</sub> N</th><th>F<sub>y</sub> N</th><th>F<sub>z</sub> N</th><th>M<sub>x</sub> N·mm</th><th>M<sub>y</sub> N·mm</th><th>M<sub>z</sub> N·mm</th></tr>");
    for (node, r) in &total.reactions {
        let _ = write!(
            h,
            "<tr><td>{node}</td><td>{:.2}</td><td>{:.2}</td><td>{:.2}</td><td>{:.0}</td><td>{:.0}</td><td>{:.0}</td></tr>",
            r[0], r[1], r[2], r[3], r[4], r[5]
        );
    }
    h.push_str("</table></body></html>\n");
    h
}
