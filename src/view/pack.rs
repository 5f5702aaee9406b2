//! Scenes from the stages' outputs: networks, meshes, panels (axes), plates with their welds and
//! sizing in 3D; cut sheets and print layers are in `flat`.

use glam::{DVec2, DVec3};
use thiserror::Error;

use super::{fig, Coloring, Kind, Layer, LayerBuilder, MAX_ELEMENTS};
use crate::analyze::sizing::CheckEdge;
use crate::fabricate::plates_file::{CoreRecord, PlateRecord, WeldNode};
use crate::files::ReadError;
use crate::mesh::TriMesh;
use crate::network::Network;
use crate::rationalize::axes::Axes;
use crate::rationalize::plates::{prism, HOLE_SEGMENTS};
use crate::rationalize::welds;
use crate::report::planarity::{Metric, PanelRow, DEFINITIONS};

#[derive(Debug, Error)]
pub enum ViewError {
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error(transparent)]
    Sl1(#[from] crate::fabricate::sl1::Sl1Error),
    #[error(
        "{what}: {count} {unit}, more than the viewer takes ({limit}){}",
        if hint.is_empty() { String::new() } else { format!("; {hint}") }
    )]
    TooLarge {
        what: String,
        count: usize,
        limit: usize,
        unit: &'static str,
        hint: &'static str,
    },
    #[error("{}: {msg}", path.display())]
    Input {
        path: std::path::PathBuf,
        msg: String,
    },
}

/// Refuses a layer of more than `MAX_ELEMENTS` elements before it is built.
fn bound(
    what: &str,
    count: usize,
    unit: &'static str,
    hint: &'static str,
) -> Result<(), ViewError> {
    if count > MAX_ELEMENTS {
        return Err(ViewError::TooLarge {
            what: what.into(),
            count,
            limit: MAX_ELEMENTS,
            unit,
            hint,
        });
    }
    Ok(())
}

/// The middle of the points' bounding box (the scene origin), or zero for none.
pub fn middle(points: impl IntoIterator<Item = DVec3>) -> DVec3 {
    let (lo, hi) = points.into_iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    if lo.is_finite() && hi.is_finite() {
        (lo + hi) / 2.0
    } else {
        DVec3::ZERO
    }
}

pub fn mm(v: f64) -> String {
    format!("{v:.3} mm")
}

fn mm6(v: f64) -> String {
    format!("{v:.6} mm")
}

fn deg(v: f64) -> String {
    format!("{v:.2}°")
}

fn xyz(p: DVec3) -> String {
    format!("{:.3}, {:.3}, {:.3}", p.x, p.y, p.z)
}

/// Networks with more nodes than this open with their nodes hidden.
pub const SHOWN_NODES: usize = 1500;

/// A network: members (lines, coloured by radius) and nodes (points, by degree).
pub fn network(net: &Network, origin: DVec3) -> Result<Vec<Layer>, ViewError> {
    let hint = "simplify it first (lamina simplify)";
    bound("network", net.edges.len(), "members", hint)?;
    bound("network", net.nodes.len(), "nodes", hint)?;
    let n = net.nodes.len();
    if let Some(k) = net
        .edges
        .iter()
        .position(|e| e.a as usize >= n || e.b as usize >= n)
    {
        return Err(ViewError::Input {
            path: "network".into(),
            msg: format!("edge {k} joins a node beyond the {n} nodes"),
        });
    }
    let mut degree = vec![0u32; n];
    for e in &net.edges {
        degree[e.a as usize] += 1;
        degree[e.b as usize] += 1;
    }
    let mut members = LayerBuilder::new("members", Kind::Lines, origin);
    for (k, e) in net.edges.iter().enumerate() {
        let (a, b) = (net.nodes[e.a as usize].p, net.nodes[e.b as usize].p);
        members.lines(
            format!("E{k}"),
            vec![
                fig("nodes", format!("N{} – N{}", e.a, e.b)),
                fig("length", mm(a.distance(b))),
                fig("radius", mm(e.radius)),
            ],
            &[[a, b]],
        );
    }
    // A network without radii (all 0) has no radius to colour by.
    let radius = net.edges.iter().any(|e| e.radius != 0.0).then(|| {
        Coloring::scale(
            "radius",
            "mm",
            "the member's radius as the network gives it (vein thickness)",
            net.edges.iter().map(|e| Some(e.radius)).collect(),
        )
    });
    let mut nodes = LayerBuilder::new("nodes", Kind::Points, origin);
    for (k, n) in net.nodes.iter().enumerate() {
        let mut f = vec![
            fig("position", xyz(n.p)),
            fig("members", degree[k].to_string()),
            fig("radius", mm(n.radius)),
        ];
        if let Some(v) = n.normal {
            f.push(fig("normal", format!("{:.4}, {:.4}, {:.4}", v.x, v.y, v.z)));
        }
        nodes.point(format!("N{k}"), f, n.p);
    }
    let degrees = Coloring::categories(
        "members at the node",
        "how many members meet at the node (1: a tip)",
        &degree.iter().map(|d| d.to_string()).collect::<Vec<_>>(),
    );
    // Thousands of node dots hide the members: then they start hidden (a checkbox away).
    let few = net.nodes.len() <= SHOWN_NODES;
    Ok(vec![
        members.finish(radius.into_iter().collect(), true),
        nodes.finish(vec![degrees], few),
    ])
}

/// A mesh, one object per connected body, with its triangle count, area and (when closed)
/// volume.
pub fn mesh(m: &TriMesh, name: &str, origin: DVec3) -> Result<Layer, ViewError> {
    bound(
        name,
        m.triangles.len(),
        "triangles",
        "mesh it coarser (solid --tolerance) or cut it up",
    )?;
    let n = m.positions.len();
    if let Some(k) = m
        .triangles
        .iter()
        .position(|t| t.iter().any(|&v| v as usize >= n))
    {
        return Err(ViewError::Input {
            path: name.into(),
            msg: format!("triangle {k} names a vertex beyond the {n} vertices"),
        });
    }
    // Bodies: triangles joined through shared vertices.
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for t in &m.triangles {
        for k in 1..3 {
            let (a, b) = (root(&mut parent, t[0]), root(&mut parent, t[k]));
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    let mut bodies: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for (k, t) in m.triangles.iter().enumerate() {
        bodies.entry(root(&mut parent, t[0])).or_default().push(k);
    }
    let mut layer = LayerBuilder::new(name, Kind::Faces, origin);
    let mut areas = Vec::new();
    for (b, tris) in bodies.values().enumerate() {
        let mut local = std::collections::HashMap::new();
        let mut points = Vec::new();
        let mut triangles = Vec::with_capacity(tris.len());
        let (mut area, mut volume) = (0.0, 0.0);
        for &k in tris {
            let t = m.triangles[k];
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            area += 0.5 * (b - a).cross(c - a).length();
            volume += a.dot(b.cross(c)) / 6.0;
            triangles.push(t.map(|v| {
                *local.entry(v).or_insert_with(|| {
                    points.push(m.positions[v as usize]);
                    points.len() as u32 - 1
                })
            }));
        }
        let sub = TriMesh {
            positions: points.clone(),
            triangles: triangles.clone(),
            colors: None,
        };
        let closed = sub.check_manifold().closed;
        let mut f = vec![
            fig("triangles", tris.len().to_string()),
            fig("area", format!("{area:.2} mm²")),
        ];
        f.push(if closed {
            fig("volume", format!("{:.2} mm³ (closed)", volume.abs()))
        } else {
            fig("volume", "not closed")
        });
        layer.faces(format!("body {}", b + 1), f, &points, &triangles, &[]);
        areas.push(Some(area));
    }
    // One body takes one colour; several are told apart by their areas.
    let colorings = if areas.len() > 1 {
        vec![Coloring::scale(
            "area",
            "mm²",
            "the body's surface area",
            areas,
        )]
    } else {
        Vec::new()
    };
    Ok(layer.finish(colorings, true))
}

/// Panels from rows of a planarity report (or built the same way): coloured by the figure held
/// to the tolerance, flatness, torsion and pass.
pub fn panels(
    quads: &[Vec<DVec3>],
    rows: &[PanelRow],
    metric: Metric,
    origin: DVec3,
) -> Result<Layer, ViewError> {
    bound(
        "panels",
        2 * quads.len(),
        "triangles",
        "audit fewer panels at a time",
    )?;
    let mut layer = LayerBuilder::new("panels", Kind::Faces, origin);
    let held = metric.name();
    for (q, r) in quads.iter().zip(rows) {
        let m = &r.metrics;
        let n = q.len() as u32;
        let tris: Vec<[u32; 3]> = (1..n.saturating_sub(1)).map(|k| [0, k, k + 1]).collect();
        let ring: Vec<[u32; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
        let mut f = Vec::new();
        if let Some(name) = &r.name {
            f.push(fig("name", name.clone()));
        }
        if let Some([a, b]) = r.nodes {
            f.push(fig("edge", format!("E{} (nodes N{a} – N{b})", r.index)));
        }
        f.push(fig(&format!("{held} (held)"), mm6(metric.of(m))));
        f.push(fig("tolerance", mm6(r.tolerance)));
        f.push(fig("within tolerance", if r.pass { "yes" } else { "no" }));
        if metric != Metric::Corner {
            f.push(fig("corner deviation", mm6(m.deviation)));
        }
        if metric != Metric::Flatness {
            f.push(fig("flatness", mm6(m.flatness)));
        }
        if metric != Metric::BestFit {
            f.push(fig("best fit", mm6(m.best_fit)));
        }
        f.push(fig("diagonal distance", mm6(m.diagonal_distance)));
        f.push(fig("torsion", format!("{:.4}°", m.torsion_deg)));
        if let Some(c) = &r.class_name {
            f.push(fig("class", c.clone()));
        }
        layer.faces(format!("P{}", r.index), f, q, &tris, &ring);
    }
    let definition = |k: &str| {
        DEFINITIONS
            .iter()
            .find(|(n, _)| *n == k)
            .map(|(_, d)| d.to_string())
            .unwrap_or_default()
    };
    let key = match metric {
        Metric::Flatness => "flatness",
        Metric::BestFit => "best_fit",
        Metric::Corner => "deviation",
    };
    let mut by_held = Coloring::scale(
        &format!("{held} (held to the tolerance)"),
        "mm",
        &definition(key),
        rows.iter().map(|r| Some(metric.of(&r.metrics))).collect(),
    );
    let first = rows.first().map(|r| r.tolerance);
    if rows.iter().all(|r| Some(r.tolerance) == first) {
        by_held.limit = first;
    }
    let mut colorings = vec![by_held];
    if metric != Metric::Flatness {
        colorings.push(Coloring::scale(
            "flatness",
            "mm",
            &definition("flatness"),
            rows.iter().map(|r| Some(r.metrics.flatness)).collect(),
        ));
    }
    colorings.push(Coloring::scale(
        "torsion",
        "°",
        &definition("torsion_deg"),
        rows.iter().map(|r| Some(r.metrics.torsion_deg)).collect(),
    ));
    let pass: Vec<Option<usize>> = rows.iter().map(|r| Some(usize::from(!r.pass))).collect();
    colorings.push(Coloring::classes(
        "within tolerance",
        "whether the held figure is at most the panel's tolerance",
        &super::PASS_FAIL,
        &pass,
    ));
    Ok(layer.finish(colorings, true))
}

/// Panel rows of axes as `planarize` solved them (the corner figure, held to `tolerance`).
pub fn axes_rows(axes: &Axes, tolerance: f64) -> (Vec<Vec<DVec3>>, Vec<PanelRow>) {
    let quads: Vec<Vec<DVec3>> = axes.quads().iter().map(|q| q.to_vec()).collect();
    let rows = quads
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let metrics = crate::rationalize::panels::polygon_metrics(q);
            PanelRow {
                index: k,
                nodes: Some(axes.edges[k]),
                tolerance,
                pass: metrics.deviation <= tolerance,
                metrics,
                ..PanelRow::default()
            }
        })
        .collect();
    (quads, rows)
}

/// The node axes as lines, each with its height and how far it turned from its reference.
pub fn node_axes(axes: &Axes, origin: DVec3) -> Result<Layer, ViewError> {
    bound("axes", axes.positions.len(), "nodes", "")?;
    let mut layer = LayerBuilder::new("node axes", Kind::Lines, origin);
    let mut turned = Vec::new();
    for (k, &p) in axes.positions.iter().enumerate() {
        let (d, h, r) = (axes.axes[k], axes.heights[k], axes.reference[k]);
        let angle = d.angle_between(r).to_degrees();
        turned.push(Some(angle));
        layer.lines(
            format!("N{k}"),
            vec![
                fig("position", xyz(p)),
                fig("axis", format!("{:.4}, {:.4}, {:.4}", d.x, d.y, d.z)),
                fig("height", mm(h)),
                fig("turned from its reference", deg(angle)),
            ],
            &[[p, p + d * h]],
        );
    }
    let c = Coloring::scale(
        "turned from its reference",
        "°",
        "the angle between the node's axis and its reference direction (the surface normal)",
        turned,
    );
    Ok(layer.finish(vec![c], true))
}

/// What the plates view shows beside the plates themselves.
#[derive(Clone, Copy, Default)]
pub struct PlateExtras<'a> {
    /// Target root gap and its tolerance, mm, and the nodes of welds.json.
    pub welds: Option<(f64, f64, &'a [WeldNode])>,
    /// The sizing file's result per network edge.
    pub checks: Option<&'a [CheckEdge]>,
}

/// Plates as solids (coloured by group, gauge and, with a sizing file, utilisation), node
/// cores, and with welds.json each pair of plates at a node as a marker.
pub fn plates(
    plates: &[PlateRecord],
    cores: &[CoreRecord],
    extras: PlateExtras,
    origin: DVec3,
) -> Result<(Vec<Layer>, Vec<String>), ViewError> {
    bound("plates", plates.len() * 64, "triangles", "")?;
    let mut notes = Vec::new();
    // Plates and cores are counted apart (each layer lists its count): cores are their own layer.
    let mut layer = LayerBuilder::new("plates", Kind::Faces, origin);
    let (mut groups, mut gauges, mut util) = (Vec::new(), Vec::new(), Vec::new());
    // Per plate and node: the middle of the plate's edge at that node (where its weld runs).
    let mut seam_of: std::collections::HashMap<(&str, u32), DVec3> = Default::default();
    for p in plates {
        let m = &p.matrix;
        let world = |q: DVec2, z: f64| {
            DVec3::new(
                m[0][0] * q.x + m[0][1] * q.y + m[0][2] * z + m[0][3],
                m[1][0] * q.x + m[1][1] * q.y + m[1][2] * z + m[1][3],
                m[2][0] * q.x + m[2][1] * q.y + m[2][2] * z + m[2][3],
            )
        };
        let (points, tris) = prism(&p.outline, &p.holes, p.hole_diameter(), p.thickness, world);
        let n = p.outline.len() as u32;
        let loop_points = points.len() as u32 / 2;
        let mut outline: Vec<[u32; 2]> = Vec::new();
        for k in 0..n {
            let j = (k + 1) % n;
            outline.extend([
                [k, j],
                [loop_points + k, loop_points + j],
                [k, loop_points + k],
            ]);
        }
        let mut f = vec![
            fig("group", p.group.to_string()),
            fig("gauge", mm(p.thickness)),
            fig("area", format!("{:.0} mm²", p.area())),
            fig("nodes", format!("N{} – N{}", p.ends[0].0, p.ends[1].0)),
        ];
        if let Some(e) = p.edge {
            f.push(fig("edge", format!("E{e}")));
        }
        for (end, (node, welded)) in ["welded at its first end", "welded at its second end"]
            .iter()
            .zip(&p.ends)
        {
            if !welded.is_empty() {
                f.push(fig(end, format!("N{node}: to {}", welded.join(", "))));
            }
        }
        if let Some(b) = &p.bolted_to {
            let bolt = p
                .bolt
                .as_ref()
                .map(|b| {
                    format!(
                        ", {} × {} {} (hole {} mm)",
                        p.holes.len(),
                        b.size,
                        b.length,
                        b.hole_diameter
                    )
                })
                .unwrap_or_default();
            f.push(fig("bolted to", format!("{b}{bolt}")));
        }
        let check = p.edge.and_then(|e| extras.checks?.get(e as usize));
        if let Some(c) = check {
            f.push(fig(
                "utilisation",
                format!("{:.3} ({}, {})", c.utilisation, c.check, c.load),
            ));
            f.push(fig("sized gauge", mm(c.gauge)));
        }
        util.push(check.map(|c| c.utilisation));
        groups.push(format!("group {}", p.group));
        gauges.push(mm(p.thickness));
        for (end, (node, _)) in p.ends.iter().enumerate() {
            seam_of.insert(
                (p.id.as_str(), *node),
                world(end_middle(&p.outline, end), 0.0),
            );
        }
        layer.faces(p.id.clone(), f, &points, &tris, &outline);
    }
    let mut colorings = vec![
        Coloring::categories(
            "group",
            "the assembly group (the tag's first number)",
            &groups,
        ),
        Coloring::categories("gauge", "the plate's thickness", &gauges),
    ];
    if extras.checks.is_some() {
        let mut u = Coloring::scale(
            "utilisation",
            "",
            "the member's largest utilisation over the load cases (stress or buckling over its resistance, lamina size); 1 is the limit",
            util,
        );
        u.limit = Some(1.0);
        colorings.insert(0, u);
    }
    let mut layers = vec![layer.finish(colorings, true)];
    let mut tubes = LayerBuilder::new("node cores", Kind::Faces, origin);
    let mut core_groups = Vec::new();
    for c in cores {
        let (points, tris) = tube(c);
        tubes.faces(
            c.id.clone(),
            vec![
                fig("node core", format!("at N{}", c.node)),
                fig("tube", format!("{} × {} mm", c.outer_diameter, c.wall)),
                fig("length", mm(c.length)),
            ],
            &points,
            &tris,
            &[],
        );
        core_groups.push(format!("group {}", c.group));
    }
    if !cores.is_empty() {
        layers.push(tubes.finish(
            vec![Coloring::categories(
                "group",
                "the assembly group of the node the tube stands on",
                &core_groups,
            )],
            true,
        ));
    }
    if let Some((gap, tol, nodes)) = extras.welds {
        let (layer, unplaced) = welds(nodes, gap, tol, &seam_of, origin)?;
        layers.push(layer);
        if unplaced > 0 {
            notes.push(format!(
                "{unplaced} weld pairs name a plate plates.json does not hold at that node: not drawn"
            ));
        }
    }
    Ok((layers, notes))
}

/// The middle of a plate outline's edge at one end: its two corners nearest that end along the
/// plate's x (the edge's direction from its first node), averaged.
fn end_middle(outline: &[DVec2], end: usize) -> DVec2 {
    let mut xs: Vec<DVec2> = outline.to_vec();
    xs.sort_by(|a, b| a.x.total_cmp(&b.x));
    let two: Vec<DVec2> = if end == 0 {
        xs.iter().take(2).copied().collect()
    } else {
        xs.iter().rev().take(2).copied().collect()
    };
    two.iter().copied().sum::<DVec2>() / two.len().max(1) as f64
}

/// A core tube as a closed mesh (outer and inner `HOLE_SEGMENTS`-gons).
fn tube(c: &CoreRecord) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let axis = DVec3::from_array(c.axis).normalize_or(DVec3::Z);
    let base = DVec3::from_array(c.base);
    let (x, y) = axis.any_orthonormal_pair();
    let n = HOLE_SEGMENTS as u32;
    let (ro, ri) = (c.outer_diameter / 2.0, c.outer_diameter / 2.0 - c.wall);
    let mut v = Vec::new();
    for (r, h) in [(ro, 0.0), (ro, c.length), (ri, 0.0), (ri, c.length)] {
        for k in 0..n {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
            v.push(base + (x * a.cos() + y * a.sin()) * r + axis * h);
        }
    }
    let at = |ring: u32, k: u32| ring * n + k % n;
    let mut t = Vec::new();
    for k in 0..n {
        for (r0, r1, flip) in [(0, 1, false), (2, 3, true), (1, 3, false), (2, 0, false)] {
            let (a, b, c, d) = (at(r0, k), at(r0, k + 1), at(r1, k + 1), at(r1, k));
            if flip {
                t.extend([[a, c, b], [a, d, c]]);
            } else {
                t.extend([[a, b, c], [a, c, d]]);
            }
        }
    }
    (v, t)
}

/// Each pair of plates side by side at a node: a marker between the middles of the two plates'
/// edges at the node (mid-height of the seam, in the wedge between them), coloured by access
/// class and by root gap. Returns the layer and how many pairs could not be placed.
fn welds(
    nodes: &[WeldNode],
    gap: f64,
    tolerance: f64,
    seam_of: &std::collections::HashMap<(&str, u32), DVec3>,
    origin: DVec3,
) -> Result<(Layer, usize), ViewError> {
    let pairs: usize = nodes.iter().map(|n| n.pairs.len()).sum();
    bound("welds", pairs, "pairs", "")?;
    let mut layer = LayerBuilder::new("welds", Kind::Points, origin);
    let (mut class, mut gaps, mut even) = (Vec::new(), Vec::new(), Vec::new());
    let mut unplaced = 0;
    for n in nodes {
        for (k, pair) in n.pairs.iter().enumerate() {
            // Older weld reports name a seam `A+B`: its first ply stands for it.
            let seam = |tag: &str| {
                let first = tag.split('+').next().unwrap_or(tag);
                seam_of.get(&(first, n.node)).copied()
            };
            let (Some(a), Some(b)) = (seam(&pair.plates[0]), seam(&pair.plates[1])) else {
                unplaced += 1;
                continue;
            };
            layer.point(
                format!("W{}-{}", n.node, k + 1),
                vec![
                    fig("node", format!("N{} ({})", n.node, n.status)),
                    fig("plates", format!("{} / {}", pair.plates[0], pair.plates[1])),
                    fig("root gap", mm(pair.root_gap_mm)),
                    fig(
                        "gap within tolerance",
                        format!(
                            "{} (target {gap} ± {tolerance} mm)",
                            if pair.gap_within_tolerance {
                                "yes"
                            } else {
                                "no"
                            }
                        ),
                    ),
                    fig("dihedral", deg(pair.dihedral_deg)),
                    fig("access", pair.access.clone()),
                ],
                (a + b) / 2.0,
            );
            // By the class's name; a report of another version by its angle, where that is
            // one of the classes' (0–180°).
            class.push(
                welds::WELD_CLASSES
                    .iter()
                    .position(|c| c.0 == pair.access)
                    .or_else(|| {
                        (pair.dihedral_deg <= 180.0).then(|| welds::weld_class(pair.dihedral_deg))
                    }),
            );
            gaps.push(Some(pair.root_gap_mm));
            even.push(Some(usize::from(!pair.gap_within_tolerance)));
        }
    }
    let layer = layer.finish(
        vec![
            Coloring::classes(
                "access",
                "the class of the angle between the two plates (0–180°): below 60° no prequalified fillet weld; 60–120° fillet (EN 1993-1-8 §4.3.2.1); 120–135° fillet under AWS D1.1 only; 135–180° butt weld",
                &welds::WELD_CLASSES,
                &class,
            ),
            Coloring::classes(
                "root gap",
                "whether the root gap (the distance between the two plates across the node axis) is within the target ± tolerance",
                &[
                    ("gap within tolerance", "#2ca02c"),
                    ("gap out of tolerance", "#d62728"),
                ],
                &even,
            ),
            Coloring::scale(
                "root gap (mm)",
                "mm",
                "the distance between the two plates in the plane perpendicular to the node axis: the weld's root opening",
                gaps,
            ),
        ],
        true,
    );
    Ok((layer, unplaced))
}
