//! Blade outlines from files: a closed loop in a network file (our JSON, OBJ `l`, or a closed
//! DXF polyline, read and welded as `lamina info` reads them), or an SVG `<polygon>`, closed
//! `<polyline>` or `<path>`.
//!
//! When a file holds several closed loops, the one enclosing the largest area is the blade.
//! SVG: curves are flattened (16 segments per Bézier; arcs become Béziers through svgtypes),
//! `transform` attributes of the element and its ancestors apply, user units are mm, and y is
//! flipped so the drawing's top stays the leaf's top.

use crate::text::printable;
use std::path::{Path, PathBuf};

use glam::DVec2;

use super::outline::{Outline, OutlineError};
use crate::files::ReadError;
use crate::network::io::{read_network, ReadOptions};

/// Segments per flattened Bézier curve.
const CURVE_SEGMENTS: usize = 16;

#[derive(Debug, thiserror::Error)]
pub enum OutlineFileError {
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error("{option} {path}: cannot read the file: {source}")]
    Io {
        option: &'static str,
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{option} {}: {}", .path.display(), printable(.msg))]
    Content {
        option: &'static str,
        path: PathBuf,
        msg: String,
    },
    #[error("{option} {path}: {source}")]
    Shape {
        option: &'static str,
        path: PathBuf,
        source: OutlineError,
    },
}

/// Reads the blade outline in `path`, by its extension.
pub fn read_outline(path: &Path) -> Result<Outline, OutlineFileError> {
    read_polygon(path, "outline=")
}

/// Reads a closed polygon (the largest loop) from `path`; `option` names it in errors.
pub fn read_polygon(path: &Path, option: &'static str) -> Result<Outline, OutlineFileError> {
    let content = |msg: String| OutlineFileError::Content {
        option,
        path: path.to_path_buf(),
        msg,
    };
    let ext = crate::files::extension(path);
    let loops = if ext == "svg" {
        let text = std::fs::read_to_string(path).map_err(|source| OutlineFileError::Io {
            option,
            path: path.to_path_buf(),
            source,
        })?;
        svg_loops(&text).map_err(content)?
    } else {
        let net = read_network(path, &ReadOptions::default())?.network;
        network_loops(&net)
    };
    let best = loops
        .into_iter()
        .filter(|l| l.len() >= 3)
        .max_by(|a, b| {
            // Non-finite areas order last and first; Outline::new refuses them.
            polygon_area(a).abs().total_cmp(&polygon_area(b).abs())
        })
        .ok_or_else(|| content("holds no closed outline with 3 or more points".into()))?;
    Outline::new(best).map_err(|source| OutlineFileError::Shape {
        option,
        path: path.to_path_buf(),
        source,
    })
}

fn polygon_area(p: &[DVec2]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| p[i].perp_dot(p[(i + 1) % n])).sum::<f64>()
}

/// Every component of the network that is one simple loop (all its nodes of degree 2), in order.
fn network_loops(net: &crate::network::Network) -> Vec<Vec<DVec2>> {
    let adj = net.adjacency();
    let (labels, count) = net.component_labels();
    let mut all_two = vec![true; count];
    let mut size = vec![0usize; count];
    for (v, &label) in labels.iter().enumerate() {
        let c = label as usize;
        size[c] += 1;
        all_two[c] &= adj.degree(v as u32) == 2;
    }
    let mut seen = vec![false; count];
    let mut loops = Vec::new();
    for (start, &label) in labels.iter().enumerate() {
        let c = label as usize;
        if seen[c] || !all_two[c] || size[c] < 3 {
            continue;
        }
        seen[c] = true;
        let mut ring = Vec::with_capacity(size[c]);
        let (mut prev, mut at) = (u32::MAX, start as u32);
        loop {
            ring.push(net.nodes[at as usize].p.truncate());
            let next = adj
                .neighbours(at)
                .iter()
                .map(|&(w, _)| w)
                .find(|&w| w != prev)
                .unwrap_or(prev);
            prev = at;
            at = next;
            if at == start as u32 || ring.len() > size[c] {
                break;
            }
        }
        loops.push(ring);
    }
    loops
}

/// The closed shapes of an SVG document, y flipped.
fn svg_loops(text: &str) -> Result<Vec<Vec<DVec2>>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("not valid SVG/XML: {e}"))?;
    let mut loops = Vec::new();
    for node in doc.descendants().filter(|n| n.is_element()) {
        let at = |msg: String| {
            let pos = doc.text_pos_at(node.range().start);
            format!("line {}: <{}>: {msg}", pos.row, node.tag_name().name())
        };
        let mut shapes: Vec<(Vec<DVec2>, bool)> = Vec::new();
        match node.tag_name().name() {
            "polygon" | "polyline" => {
                let pts: Vec<DVec2> =
                    svgtypes::PointsParser::from(node.attribute("points").unwrap_or(""))
                        .map(|(x, y)| DVec2::new(x, y))
                        .collect();
                let closed = node.tag_name().name() == "polygon"
                    || (pts.len() > 2 && pts.first() == pts.last());
                shapes.push((pts, closed));
            }
            "path" => {
                let d = node.attribute("d").unwrap_or("");
                shapes.extend(path_loops(d).map_err(at)?);
            }
            _ => continue,
        }
        let m = transform_of(node).map_err(at)?;
        for (pts, closed) in shapes {
            if closed {
                loops.push(
                    pts.into_iter()
                        .map(|p| {
                            let q = m(p);
                            DVec2::new(q.x, -q.y)
                        })
                        .collect(),
                );
            }
        }
    }
    Ok(loops)
}

/// The product of the `transform` attributes from the root down to `node`.
fn transform_of(node: roxmltree::Node) -> Result<impl Fn(DVec2) -> DVec2, String> {
    let mut m = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    let chain: Vec<_> = node.ancestors().collect();
    for n in chain.into_iter().rev() {
        if let Some(t) = n.attribute("transform") {
            let t: svgtypes::Transform = t
                .parse()
                .map_err(|e| format!("bad transform \"{t}\": {e}"))?;
            let [a, b, c, d, e, f] = m;
            // m · t
            m = [
                a * t.a + c * t.b,
                b * t.a + d * t.b,
                a * t.c + c * t.d,
                b * t.c + d * t.d,
                a * t.e + c * t.f + e,
                b * t.e + d * t.f + f,
            ];
        }
    }
    Ok(move |p: DVec2| {
        DVec2::new(
            m[0] * p.x + m[2] * p.y + m[4],
            m[1] * p.x + m[3] * p.y + m[5],
        )
    })
}

/// The subpaths of path data, flattened; true where closed by Z or by returning to the start.
fn path_loops(d: &str) -> Result<Vec<(Vec<DVec2>, bool)>, String> {
    use svgtypes::SimplePathSegment as S;
    let mut out: Vec<(Vec<DVec2>, bool)> = Vec::new();
    let mut cur: Vec<DVec2> = Vec::new();
    let finish = |cur: &mut Vec<DVec2>, closed: bool, out: &mut Vec<(Vec<DVec2>, bool)>| {
        if !cur.is_empty() {
            let closed = closed || (cur.len() > 2 && cur.first() == cur.last());
            out.push((std::mem::take(cur), closed));
        }
    };
    for seg in svgtypes::SimplifyingPathParser::from(d) {
        let seg = seg.map_err(|e| format!("bad path data: {e}"))?;
        let last = cur.last().copied().unwrap_or(DVec2::ZERO);
        match seg {
            S::MoveTo { x, y } => {
                finish(&mut cur, false, &mut out);
                cur.push(DVec2::new(x, y));
            }
            S::LineTo { x, y } => cur.push(DVec2::new(x, y)),
            S::CurveTo {
                x1,
                y1,
                x2,
                y2,
                x,
                y,
            } => {
                let (c1, c2, end) = (DVec2::new(x1, y1), DVec2::new(x2, y2), DVec2::new(x, y));
                for k in 1..=CURVE_SEGMENTS {
                    let t = k as f64 / CURVE_SEGMENTS as f64;
                    let u = 1.0 - t;
                    cur.push(
                        last * (u * u * u)
                            + c1 * (3.0 * u * u * t)
                            + c2 * (3.0 * u * t * t)
                            + end * (t * t * t),
                    );
                }
            }
            S::Quadratic { x1, y1, x, y } => {
                let (c, end) = (DVec2::new(x1, y1), DVec2::new(x, y));
                for k in 1..=CURVE_SEGMENTS {
                    let t = k as f64 / CURVE_SEGMENTS as f64;
                    let u = 1.0 - t;
                    cur.push(last * (u * u) + c * (2.0 * u * t) + end * (t * t));
                }
            }
            S::ClosePath => {
                let start = cur.first().copied();
                finish(&mut cur, true, &mut out);
                // A segment after Z starts where the closed subpath started.
                if let Some(s) = start {
                    cur.push(s);
                }
            }
        }
    }
    // A lone point left after Z is not a subpath.
    if cur.len() > 1 {
        finish(&mut cur, false, &mut out);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_polygon_path_and_transform() -> Result<(), String> {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg">
          <g transform="translate(10 0)">
            <polygon points="0,0 4,0 4,4 0,4"/>
          </g>
          <path d="M 0 0 L 10 0 Q 10 10 0 10 Z"/>
          <polyline points="0,0 1,1 2,0"/>
        </svg>"#;
        let loops = svg_loops(svg)?;
        assert_eq!(loops.len(), 2, "the open polyline is not a loop");
        assert_eq!(loops[0][0], DVec2::new(10.0, 0.0));
        assert_eq!(loops[0][2], DVec2::new(14.0, -4.0), "y is flipped");
        assert_eq!(loops[1].len(), 2 + CURVE_SEGMENTS);
        Ok(())
    }

    #[test]
    fn bad_svg_names_the_line() {
        let svg = "<svg>\n<path d=\"M 0 0 L x\"/>\n</svg>";
        let e = svg_loops(svg).expect_err("bad path");
        assert!(e.starts_with("line 2: <path>"), "{e}");
    }
}
