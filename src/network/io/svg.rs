//! SVG render of a network: one line per edge, stroke width = 2 × edge radius in mm (a hairline
//! where the radius is 0), isolated nodes as dots. Page units are mm.

use std::fmt::Write as _;
use std::path::Path;

use super::Projection;
use crate::files::{write_atomic, WriteError};
use crate::network::Network;

pub fn write(net: &Network, path: &Path) -> Result<(), WriteError> {
    let svg = render_svg_string(net);
    write_atomic(path, |w| std::io::Write::write_all(w, svg.as_bytes()))
}

/// The SVG text of a network render, for embedding in report pages.
pub fn render_svg_string(net: &Network) -> String {
    let proj = Projection::fit(net);
    let [w, h] = proj.extent();
    let hairline = w.max(h) * 1e-3;
    let margin = w.max(h) * 0.02 + net.edges.iter().map(|e| e.radius).fold(0.0, f64::max);
    let (vw, vh) = (w + 2.0 * margin, h + 2.0 * margin);
    let mut s = String::with_capacity(64 * net.edges.len() + 512);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{vw:.3}mm" height="{vh:.3}mm" viewBox="{:.4} {:.4} {vw:.4} {vh:.4}">"#,
        -margin, -margin
    );
    let _ = writeln!(
        s,
        "<title>lamina network: {} nodes, {} edges</title>",
        net.nodes.len(),
        net.edges.len()
    );
    let _ = writeln!(
        s,
        r##"<rect x="{:.4}" y="{:.4}" width="{vw:.4}" height="{vh:.4}" fill="#ffffff"/>"##,
        -margin, -margin
    );
    let _ = writeln!(
        s,
        r##"<g fill="none" stroke="#1d3b2a" stroke-linecap="round" stroke-width="{hairline:.4}">"##
    );
    // Edges to missing nodes cannot be drawn; writers refuse such networks before this.
    let n = net.nodes.len() as u32;
    for e in net.edges.iter().filter(|e| e.a < n && e.b < n) {
        let [x1, y1] = proj.page(net.nodes[e.a as usize].p);
        let [x2, y2] = proj.page(net.nodes[e.b as usize].p);
        let _ = write!(
            s,
            r#"<line x1="{x1:.4}" y1="{y1:.4}" x2="{x2:.4}" y2="{y2:.4}""#
        );
        if e.radius > 0.0 {
            let _ = write!(
                s,
                r#" stroke-width="{:.4}""#,
                (2.0 * e.radius).max(hairline)
            );
        }
        s.push_str("/>\n");
    }
    s.push_str("</g>\n");
    let adj = net.adjacency();
    for (i, n) in net.nodes.iter().enumerate() {
        if adj.degree(i as u32) == 0 {
            let [x, y] = proj.page(n.p);
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.4}" cy="{y:.4}" r="{:.4}" fill="#1d3b2a"/>"##,
                n.radius.max(hairline)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}
