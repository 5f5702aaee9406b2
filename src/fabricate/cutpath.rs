//! The cut path of a sheet: in which order the machine marks and cuts, where each contour is
//! pierced, and the tool path it follows with the beam on (contours offset by half the kerf),
//! with the rapid travel between.
//!
//! Order: all etching first (tags, sheet and remnant labels, while every part is still held by
//! the sheet), then part by part, each part's holes before its outer contour. With
//! [`CutOrder::Travel`] the parts follow a nearest-neighbour tour improved by 2-opt and Or-opt
//! moves on the exact rapid travel (each part entered at its first contour's start and left at
//! its outer contour's end), and each part is pierced at the corner that shortens the travel
//! between its neighbours; the result is never longer than the plain nearest-neighbour tour
//! over the same contours, which is kept when it is not beaten. With [`CutOrder::Spread`]
//! successive parts lie far apart, to spread the heat on thin sheet. Etching is ordered the
//! same way per part (or label), stroke by stroke, each stroke cut in whichever direction is
//! shorter to reach.
//!
//! Kerf: the tool path runs `kerf / 2` to the right of each contour's direction, outside the
//! counter-clockwise outer contours and inside the clockwise holes: edges shifted along their
//! normal, joined by an arc about the corner where the path turns left (the part's corner stays
//! sharp and the offset is exact, as a disc rolled round the corner) and at the lines' meeting
//! point where it turns right. Leads are moved with their contour's start. Etching is not
//! offset.
//!
//! Rapid travel runs from the sheet's origin to the first path and from the end of each path to
//! the start of the next; the machine's return home is not counted.

use glam::DVec2;

use crate::fabricate::cutsheet::Drawn;

/// A move with the beam on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Seg {
    /// A straight move to the point.
    Line(DVec2),
    /// An arc to `to` about `centre`, counter-clockwise when `ccw`.
    Arc { to: DVec2, centre: DVec2, ccw: bool },
}

impl Seg {
    /// Where the move ends.
    pub fn end(&self) -> DVec2 {
        match *self {
            Seg::Line(p) => p,
            Seg::Arc { to, .. } => to,
        }
    }

    /// Length of the move from `from`, mm.
    pub fn length(&self, from: DVec2) -> f64 {
        match *self {
            Seg::Line(p) => from.distance(p),
            Seg::Arc { to, centre, ccw } => {
                let (a, b) = (from - centre, to - centre);
                let mut sweep = a.perp_dot(b).atan2(a.dot(b));
                if ccw && sweep < 0.0 {
                    sweep += std::f64::consts::TAU;
                } else if !ccw && sweep > 0.0 {
                    sweep -= std::f64::consts::TAU;
                }
                sweep.abs() * a.length()
            }
        }
    }
}

/// What a tool path does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// Marking: tags and labels.
    Etch,
    /// A hole.
    Inner,
    /// A part's outer contour, or one piece of it between micro-joints.
    Outer,
    /// The rest of an outer contour after a common line: it starts in the line's kerf, so
    /// there is nothing to pierce.
    FromKerf,
}

/// One run with the beam on.
#[derive(Clone, Debug, PartialEq)]
pub struct ToolPath {
    pub op: Op,
    /// The plate (index into the nest's plates), None for sheet and remnant labels.
    pub part: Option<usize>,
    /// Where the beam comes on.
    pub start: DVec2,
    pub segs: Vec<Seg>,
}

impl ToolPath {
    /// Where the beam goes off.
    pub fn end(&self) -> DVec2 {
        self.segs.last().map_or(self.start, Seg::end)
    }

    /// Length with the beam on, mm.
    pub fn length(&self) -> f64 {
        let mut at = self.start;
        let mut sum = 0.0;
        for s in &self.segs {
            sum += s.length(at);
            at = s.end();
        }
        sum
    }
}

/// How parts follow one another.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CutOrder {
    /// Short rapid travel. The default.
    #[default]
    Travel,
    /// Successive parts far apart, to spread the heat.
    Spread,
}

impl CutOrder {
    /// As nest.json and the command line write it.
    pub fn name(self) -> &'static str {
        match self {
            CutOrder::Travel => "travel",
            CutOrder::Spread => "spread",
        }
    }
}

/// A part as the ordering sees it: its outline on the sheet (counter-clockwise) and its hole
/// centres.
#[derive(Clone, Copy, Debug)]
pub struct PartShape<'a> {
    pub outline: &'a [DVec2],
    pub holes: &'a [DVec2],
    /// The outline vertices it may be pierced at (common-line pairs: the second part's cut
    /// starts at its shared side's end, the first part's keeps off the shared side); None:
    /// any corner worth piercing at.
    pub pierce_at: Option<&'a [usize]>,
}

/// A proposed cut order for one sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct Order {
    /// Parts (indices into the shapes given) in cutting order.
    pub parts: Vec<usize>,
    /// Per part (by index): the outline vertex to pierce at.
    pub pierce: Vec<usize>,
    /// Per part (by index): its holes in cutting order.
    pub holes: Vec<Vec<usize>>,
}

/// Corners worth piercing at: vertices where the outline turns left by at least 15°; all
/// left turns where there are none such, every vertex where there is no left turn.
fn corners(outline: &[DVec2]) -> Vec<usize> {
    let n = outline.len();
    let turn = |k: usize| {
        let a = outline[k] - outline[(k + n - 1) % n];
        let b = outline[(k + 1) % n] - outline[k];
        let s = a.length() * b.length();
        if s > 0.0 {
            a.perp_dot(b) / s
        } else {
            0.0
        }
    };
    let sharp: Vec<usize> = (0..n)
        .filter(|&k| turn(k) >= 15f64.to_radians().sin())
        .collect();
    if !sharp.is_empty() {
        return sharp;
    }
    let left: Vec<usize> = (0..n).filter(|&k| turn(k) > 0.0).collect();
    if !left.is_empty() {
        return left;
    }
    (0..n).collect()
}

fn centroid(points: &[DVec2]) -> DVec2 {
    points.iter().copied().sum::<DVec2>() / points.len().max(1) as f64
}

/// Two parts that share a side the kerf apart, to be cut on a common line: the first's side
/// `edge` (from its vertex `edge` to the next, counter-clockwise) is cut along the line half
/// the kerf off it, which is also half the kerf off the second's side `other_edge`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommonLine {
    pub first: usize,
    pub edge: usize,
    pub second: usize,
    pub other_edge: usize,
    /// The line cut, mm on the sheet.
    pub from: DVec2,
    pub to: DVec2,
}

/// Outlines (counter-clockwise, on one sheet) that share a whole side `gap` apart: a side of
/// one whose ends lie within `fit` of a side of another moved `gap` along its outward normal,
/// the other's side running the other way. Each outline is in at most one pair; the first of a
/// pair is the one listed first.
pub fn common_lines(outlines: &[Vec<DVec2>], gap: f64, fit: f64) -> Vec<CommonLine> {
    let boxes: Vec<(DVec2, DVec2)> = outlines
        .iter()
        .map(|o| {
            o.iter()
                .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), q| {
                    (lo.min(*q), hi.max(*q))
                })
        })
        .collect();
    let mut by_x: Vec<usize> = (0..outlines.len()).collect();
    by_x.sort_by(|&a, &b| boxes[a].0.x.total_cmp(&boxes[b].0.x).then(a.cmp(&b)));
    let reach = gap + fit;
    let mut taken = vec![false; outlines.len()];
    let mut found = Vec::new();
    for (pos, &i) in by_x.iter().enumerate() {
        // Neighbours later in x order whose boxes come within reach (a pair is met from the
        // one whose box starts first).
        let mut candidates: Vec<usize> = by_x[pos + 1..]
            .iter()
            .copied()
            .take_while(|&j| boxes[j].0.x <= boxes[i].1.x + reach)
            .filter(|&j| {
                boxes[j].0.y <= boxes[i].1.y + reach && boxes[j].1.y >= boxes[i].0.y - reach
            })
            .collect();
        candidates.sort_unstable();
        for j in candidates {
            let (first, second) = (i.min(j), i.max(j));
            if taken[first] || taken[second] {
                continue;
            }
            let (a, b) = (&outlines[first], &outlines[second]);
            let shared = (0..a.len()).find_map(|e| {
                let (p, q) = (a[e], a[(e + 1) % a.len()]);
                let d = q - p;
                if d.length() <= 2.0 * fit {
                    return None;
                }
                let n = DVec2::new(d.y, -d.x).normalize();
                let (u, v) = (q + n * gap, p + n * gap);
                (0..b.len())
                    .find(|&f| b[f].distance(u) <= fit && b[(f + 1) % b.len()].distance(v) <= fit)
                    .map(|f| (e, f, p + n * (0.5 * gap), q + n * (0.5 * gap)))
            });
            if let Some((edge, other_edge, from, to)) = shared {
                taken[first] = true;
                taken[second] = true;
                found.push(CommonLine {
                    first,
                    edge,
                    second,
                    other_edge,
                    from,
                    to,
                });
            }
        }
    }
    found.sort_by_key(|c| c.first);
    found
}

/// Proposes the order of a sheet's parts, each part's pierce corner and the order of its
/// holes, starting from `from` (where the etching ended). The final order is set by
/// [`plan_sheet`] on the exact tool paths.
pub fn order_parts(parts: &[PartShape], from: DVec2, order: CutOrder) -> Order {
    let n = parts.len();
    let corner_sets: Vec<Vec<usize>> = parts
        .iter()
        .map(|p| {
            let all = corners(p.outline);
            match p.pierce_at {
                Some(allowed) if !allowed.is_empty() => {
                    let sharp: Vec<usize> =
                        all.into_iter().filter(|k| allowed.contains(k)).collect();
                    if sharp.is_empty() {
                        allowed.to_vec()
                    } else {
                        sharp
                    }
                }
                _ => all,
            }
        })
        .collect();
    let reps: Vec<DVec2> = parts.iter().map(|p| centroid(p.outline)).collect();
    let tour = match order {
        CutOrder::Spread => spread(&reps, from),
        CutOrder::Travel => {
            let mut t = nearest_tour(from, &reps, &reps);
            two_opt(from, &reps, &reps, &mut t);
            t
        }
    };
    let mut pierce: Vec<usize> = corner_sets.iter().map(|c| c[0]).collect();
    let mut holes: Vec<Vec<usize>> = parts.iter().map(|p| (0..p.holes.len()).collect()).collect();
    let mut tour = tour;
    // Pierce corners and hole orders for the neighbours the tour gives, then the tour again
    // for those pierce points.
    for round in 0..3 {
        let mut at = from;
        for (k, &i) in tour.iter().enumerate() {
            let p = &parts[i];
            holes[i] = nearest_tour(at, p.holes, p.holes);
            let last = holes[i].last().map_or(at, |&h| p.holes[h]);
            let next = tour.get(k + 1).map(|&j| {
                let q = &parts[j];
                nearest_hole(q.holes, p.outline[pierce[i]]).unwrap_or(q.outline[pierce[j]])
            });
            pierce[i] = *corner_sets[i]
                .iter()
                .min_by(|&&a, &&b| {
                    let cost = |v: usize| {
                        let v = p.outline[v];
                        last.distance(v) + next.map_or(0.0, |q| v.distance(q))
                    };
                    cost(a).total_cmp(&cost(b)).then(a.cmp(&b))
                })
                .expect("an outline has a vertex");
            at = p.outline[pierce[i]];
        }
        if order == CutOrder::Spread || round == 2 {
            break;
        }
        let entry: Vec<DVec2> = (0..n)
            .map(|i| {
                holes[i]
                    .first()
                    .map_or(parts[i].outline[pierce[i]], |&h| parts[i].holes[h])
            })
            .collect();
        let exit: Vec<DVec2> = (0..n).map(|i| parts[i].outline[pierce[i]]).collect();
        two_opt(from, &entry, &exit, &mut tour);
        or_opt(from, &entry, &exit, &mut tour);
    }
    Order {
        parts: tour,
        pierce,
        holes,
    }
}

fn nearest_hole(holes: &[DVec2], from: DVec2) -> Option<DVec2> {
    holes.iter().copied().min_by(|a, b| {
        a.distance_squared(from)
            .total_cmp(&b.distance_squared(from))
    })
}

/// Successive parts far apart: the next part is the nearest of those at least a quarter of
/// the layout's diagonal away, or the farthest when none is.
fn spread(reps: &[DVec2], from: DVec2) -> Vec<usize> {
    let lo = reps.iter().fold(DVec2::INFINITY, |m, q| m.min(*q));
    let hi = reps.iter().fold(DVec2::NEG_INFINITY, |m, q| m.max(*q));
    let far = 0.25 * (hi - lo).length();
    let mut left: Vec<usize> = (0..reps.len()).collect();
    let mut tour = Vec::with_capacity(reps.len());
    let mut at = from;
    let mut first = true;
    while !left.is_empty() {
        let d = |i: usize| reps[i].distance(at);
        let pick = if first {
            (0..left.len()).min_by(|&a, &b| d(left[a]).total_cmp(&d(left[b])))
        } else {
            (0..left.len())
                .filter(|&k| d(left[k]) >= far)
                .min_by(|&a, &b| d(left[a]).total_cmp(&d(left[b])))
                .or_else(|| (0..left.len()).max_by(|&a, &b| d(left[a]).total_cmp(&d(left[b]))))
        }
        .expect("parts are left");
        first = false;
        let i = left.remove(pick);
        at = reps[i];
        tour.push(i);
    }
    tour
}

/// Nearest-neighbour tour from `from` over items entered at `entry` and left at `exit`; ties
/// go to the lower index.
pub fn nearest_tour(from: DVec2, entry: &[DVec2], exit: &[DVec2]) -> Vec<usize> {
    let n = entry.len();
    let mut used = vec![false; n];
    let mut tour = Vec::with_capacity(n);
    let mut at = from;
    for _ in 0..n {
        let mut best: Option<(f64, usize)> = None;
        for (i, e) in entry.iter().enumerate() {
            if used[i] {
                continue;
            }
            let d = at.distance_squared(*e);
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, i));
            }
        }
        let (_, i) = best.expect("an item is left");
        used[i] = true;
        at = exit[i];
        tour.push(i);
    }
    tour
}

/// Rapid travel of a tour, mm.
pub fn tour_travel(from: DVec2, entry: &[DVec2], exit: &[DVec2], tour: &[usize]) -> f64 {
    let mut at = from;
    let mut sum = 0.0;
    for &i in tour {
        sum += at.distance(entry[i]);
        at = exit[i];
    }
    sum
}

/// Most improving passes of 2-opt and Or-opt.
const PASSES: usize = 100;
/// An improvement smaller than this is none, mm.
const GAIN: f64 = 1e-9;

/// 2-opt on an open tour from `from` with fixed entry and exit points per item: a stretch of
/// the tour is visited backwards (each item still entered at its entry), kept when it shortens
/// the travel.
pub fn two_opt(from: DVec2, entry: &[DVec2], exit: &[DVec2], tour: &mut [usize]) {
    let n = tour.len();
    if n < 2 {
        return;
    }
    let d = |a: DVec2, b: DVec2| a.distance(b);
    for _ in 0..PASSES {
        // Forward and backward sums of the links inside the tour.
        let mut fwd = vec![0.0; n];
        let mut bwd = vec![0.0; n];
        for k in 1..n {
            fwd[k] = fwd[k - 1] + d(exit[tour[k - 1]], entry[tour[k]]);
            bwd[k] = bwd[k - 1] + d(exit[tour[k]], entry[tour[k - 1]]);
        }
        let mut best: Option<(f64, usize, usize)> = None;
        for i in 0..n - 1 {
            let prev = if i == 0 { from } else { exit[tour[i - 1]] };
            for j in i + 1..n {
                let (ti, tj) = (tour[i], tour[j]);
                let mut old = d(prev, entry[ti]) + fwd[j] - fwd[i];
                let mut new = d(prev, entry[tj]) + bwd[j] - bwd[i];
                if j + 1 < n {
                    let next = entry[tour[j + 1]];
                    old += d(exit[tj], next);
                    new += d(exit[ti], next);
                }
                let gain = old - new;
                if gain > GAIN && best.is_none_or(|(g, _, _)| gain > g) {
                    best = Some((gain, i, j));
                }
            }
        }
        match best {
            Some((_, i, j)) => tour[i..=j].reverse(),
            None => return,
        }
    }
}

/// Or-opt on an open tour: a run of one to three items moved elsewhere in the same direction,
/// kept when it shortens the travel.
pub fn or_opt(from: DVec2, entry: &[DVec2], exit: &[DVec2], tour: &mut Vec<usize>) {
    let n = tour.len();
    if n < 3 {
        return;
    }
    let d = |a: DVec2, b: DVec2| a.distance(b);
    for _ in 0..PASSES {
        let before = tour_travel(from, entry, exit, tour);
        let mut improved = false;
        'moves: for len in 1..=3.min(n - 1) {
            for i in 0..=n - len {
                // The run tour[i..i+len], taken out.
                let prev = if i == 0 { from } else { exit[tour[i - 1]] };
                let first = entry[tour[i]];
                let last = exit[tour[i + len - 1]];
                let next = tour.get(i + len).map(|&t| entry[t]);
                let out_gain = d(prev, first) + next.map_or(0.0, |q| d(last, q))
                    - next.map_or(0.0, |q| d(prev, q));
                for j in 0..=n {
                    // Insert before position j of the original tour (outside the run).
                    if j >= i && j <= i + len {
                        continue;
                    }
                    let a = if j == 0 { from } else { exit[tour[j - 1]] };
                    let b = tour.get(j).map(|&t| entry[t]);
                    let in_cost =
                        d(a, first) + b.map_or(0.0, |q| d(last, q)) - b.map_or(0.0, |q| d(a, q));
                    if out_gain - in_cost > GAIN {
                        let run: Vec<usize> = tour.drain(i..i + len).collect();
                        let at = if j > i { j - len } else { j };
                        tour.splice(at..at, run);
                        improved = true;
                        break 'moves;
                    }
                }
            }
        }
        if !improved {
            return;
        }
        debug_assert!(tour_travel(from, entry, exit, tour) < before);
    }
}

/// A contour offset by `r` to the right of its direction: edges shifted along their right
/// normal, an arc about the vertex where the path turns left, the shifted lines' meeting point
/// where it turns right. Returns the start and the moves; `closed` runs back to the start.
pub fn offset_right(points: &[DVec2], closed: bool, r: f64) -> (DVec2, Vec<Seg>) {
    let mut p: Vec<DVec2> = Vec::with_capacity(points.len());
    for q in points {
        if p.last() != Some(q) {
            p.push(*q);
        }
    }
    if closed && p.len() > 1 && p.first() == p.last() {
        p.pop();
    }
    let n = p.len();
    if n < 2 {
        return (p.first().copied().unwrap_or(DVec2::ZERO), Vec::new());
    }
    let edges = if closed { n } else { n - 1 };
    let normal: Vec<DVec2> = (0..edges)
        .map(|k| {
            let d = (p[(k + 1) % n] - p[k]).normalize();
            DVec2::new(d.y, -d.x)
        })
        .collect();
    // At vertex v between edges a (in) and b (out): where the incoming line ends, and the arc
    // (if any) to where the outgoing one starts.
    let corner = |v: usize, a: usize, b: usize| -> (DVec2, Option<Seg>) {
        let (na, nb) = (normal[a], normal[b]);
        let turn = DVec2::new(-na.y, na.x).perp_dot(DVec2::new(-nb.y, nb.x));
        if r == 0.0 || turn.abs() < 1e-12 {
            return (p[v] + nb * r, None);
        }
        if turn > 0.0 {
            (
                p[v] + na * r,
                Some(Seg::Arc {
                    to: p[v] + nb * r,
                    centre: p[v],
                    ccw: true,
                }),
            )
        } else {
            (p[v] + (na + nb) * (r / (1.0 + na.dot(nb))), None)
        }
    };
    let mut segs = Vec::with_capacity(2 * n);
    if closed {
        let (meet0, arc0) = corner(0, n - 1, 0);
        let start = arc0.map_or(meet0, |s| s.end());
        for v in (1..n).chain([0]) {
            let (meet, arc) = corner(v, (v + n - 1) % n, v % n);
            segs.push(Seg::Line(meet));
            segs.extend(arc);
        }
        (start, segs)
    } else {
        let start = p[0] + normal[0] * r;
        for v in 1..n - 1 {
            let (meet, arc) = corner(v, v - 1, v);
            segs.push(Seg::Line(meet));
            segs.extend(arc);
        }
        segs.push(Seg::Line(p[n - 1] + normal[n - 2] * r));
        (start, segs)
    }
}

/// A sheet's program: every tool path in order, and the rapid travel between them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SheetPlan {
    pub paths: Vec<ToolPath>,
    /// Plates (indices) in cutting order.
    pub parts: Vec<usize>,
    /// The etched polylines in order and direction (as the DXF draws them).
    pub etch: Vec<Vec<DVec2>>,
    /// Rapid travel from the origin through every path, mm.
    pub rapid_mm: f64,
    /// Rapid moves (one before each path).
    pub rapids: usize,
    /// Half the kerf the contours are offset by, mm.
    pub offset: f64,
}

impl SheetPlan {
    /// The rapid travel of the paths in their order, from the origin, mm.
    pub fn travel(paths: &[ToolPath]) -> f64 {
        let mut at = DVec2::ZERO;
        let mut sum = 0.0;
        for p in paths {
            sum += at.distance(p.start);
            at = p.end();
        }
        sum
    }
}

/// The tool paths of one part as it is cut: holes in their drawn order, then the outer contour
/// (or its pieces between micro-joints), offset by `r`, with the leads moved along.
pub fn part_paths(index: usize, d: &Drawn, r: f64) -> Vec<ToolPath> {
    let mut out = Vec::with_capacity(d.holes.len() + 1);
    let lead = |k: usize| d.leads.get(k).copied();
    for (k, h) in d.holes.iter().enumerate() {
        let mut ring = crate::rationalize::plates::hole_polygon(h.centre, h.diameter);
        ring[1..].reverse();
        let (start, segs) = offset_right(&ring, true, r);
        out.push(with_leads(
            Op::Inner,
            index,
            ring[0],
            start,
            segs,
            lead(2 * k),
            lead(2 * k + 1),
        ));
    }
    let base = 2 * d.holes.len();
    let pieces = d.outer_pieces();
    let closed = d.joints.is_empty();
    let count = pieces.len();
    for (k, piece) in pieces.iter().enumerate() {
        let (mut start, mut segs) = offset_right(piece, closed, r);
        if d.common && closed {
            (start, segs) = without_last_side(start, segs);
        }
        let lead_in = if k == 0 { lead(base) } else { None };
        let lead_out = if k + 1 == count { lead(base + 1) } else { None };
        out.push(with_leads(
            if d.common { Op::FromKerf } else { Op::Outer },
            index,
            piece[0],
            start,
            segs,
            lead_in,
            lead_out,
        ));
    }
    out
}

/// A closed offset path (as [`offset_right`] gives it) less its run along the last side: it
/// starts where that run ends (at the first vertex's corner) and ends where it began.
fn without_last_side(start: DVec2, mut segs: Vec<Seg>) -> (DVec2, Vec<Seg>) {
    // The closed path ends with the line along the last side, then the first corner's arc
    // (none at a right turn or without a kerf), which ends at the start.
    let arc = match segs.last() {
        Some(Seg::Arc { .. }) => segs.pop(),
        _ => None,
    };
    match segs.pop() {
        Some(Seg::Line(along_end)) => {
            let mut out: Vec<Seg> = arc.into_iter().collect();
            out.append(&mut segs);
            (along_end, out)
        }
        other => {
            // Not the shape offset_right gives: cut it whole.
            segs.extend(other);
            segs.extend(arc);
            (start, segs)
        }
    }
}

/// A contour's path with its leads: the lead-in moved so that it ends where the offset contour
/// starts, the lead-out leaving from where it ends in the drawn lead's direction.
fn with_leads(
    op: Op,
    index: usize,
    pierce: DVec2,
    start: DVec2,
    mut segs: Vec<Seg>,
    lead_in: Option<[DVec2; 2]>,
    lead_out: Option<[DVec2; 2]>,
) -> ToolPath {
    let end = segs.last().map_or(start, Seg::end);
    let mut path = ToolPath {
        op,
        part: Some(index),
        start,
        segs: Vec::new(),
    };
    if let Some([a, b]) = lead_in {
        let shift = start - pierce;
        debug_assert!(b.distance(pierce) < 1e-9);
        path.start = a + shift;
        path.segs.push(Seg::Line(b + shift));
    }
    path.segs.append(&mut segs);
    if let Some([a, b]) = lead_out {
        path.segs.push(Seg::Line(end + (b - a)));
    }
    path
}

/// Neighbours each endpoint keeps for the etching's 2-opt.
const NEIGHBOURS: usize = 10;

/// A uniform grid over points, for nearest-neighbour queries.
struct Grid {
    lo: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<usize>>,
}

impl Grid {
    fn new(points: &[DVec2]) -> Grid {
        let lo = points.iter().fold(DVec2::INFINITY, |m, q| m.min(*q));
        let hi = points.iter().fold(DVec2::NEG_INFINITY, |m, q| m.max(*q));
        let size = (hi - lo).max(DVec2::splat(1e-9));
        // About two points a cell.
        let cell = (size.x * size.y / (0.5 * points.len().max(1) as f64))
            .sqrt()
            .max(size.max_element() / 4096.0)
            .max(1e-9);
        let nx = ((size.x / cell) as usize + 1).min(4096);
        let ny = ((size.y / cell) as usize + 1).min(4096);
        let mut g = Grid {
            lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (i, p) in points.iter().enumerate() {
            let k = g.key(*p);
            g.cells[k].push(i);
        }
        g
    }

    fn coords(&self, p: DVec2) -> (usize, usize) {
        let c = ((p - self.lo) / self.cell).max(DVec2::ZERO);
        (
            (c.x as usize).min(self.nx - 1),
            (c.y as usize).min(self.ny - 1),
        )
    }

    fn key(&self, p: DVec2) -> usize {
        let (x, y) = self.coords(p);
        y * self.nx + x
    }

    /// The cells at Chebyshev distance `ring` from cell (cx, cy), within the grid. Points in
    /// them lie at least (ring − 1) cells from any point of that cell (or beyond the grid's
    /// side it was clamped to).
    fn ring(&self, (cx, cy): (usize, usize), ring: usize) -> impl Iterator<Item = usize> + '_ {
        let (x0, x1) = (cx.saturating_sub(ring), (cx + ring).min(self.nx - 1));
        let (y0, y1) = (cy.saturating_sub(ring), (cy + ring).min(self.ny - 1));
        (y0..=y1).flat_map(move |y| {
            (x0..=x1)
                .filter(move |&x| {
                    x + ring == cx || x == cx + ring || y + ring == cy || y == cy + ring
                })
                .map(move |x| y * self.nx + x)
        })
    }

    /// The `k` nearest points to `p` that `keep` accepts, nearest first (ties to the lower
    /// index): rings of cells outwards until the ring is farther than the k-th found.
    fn nearest(
        &self,
        points: &[DVec2],
        p: DVec2,
        k: usize,
        keep: impl Fn(usize) -> bool,
    ) -> Vec<usize> {
        let centre = self.coords(p);
        let mut found: Vec<(f64, usize)> = Vec::new();
        let rings = self.nx.max(self.ny);
        for ring in 0..=rings {
            // Points in cells at Chebyshev distance `ring` lie at least (ring − 1) cells away.
            if found.len() >= k {
                let far = found[k - 1].0;
                let reach = (ring as f64 - 1.0).max(0.0) * self.cell;
                if reach * reach > far {
                    break;
                }
            }
            for c in self.ring(centre, ring) {
                for &i in &self.cells[c] {
                    if keep(i) {
                        found.push((points[i].distance_squared(p), i));
                    }
                }
            }
            found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            found.truncate(k);
            if ring >= self.nx && ring >= self.ny {
                break;
            }
        }
        found.into_iter().map(|(_, i)| i).collect()
    }
}

/// Etched polylines as tool paths in marking order from `from`: a nearest-neighbour tour
/// (each polyline entered at whichever end is nearer), then 2-opt moves over the ten nearest
/// endpoints of each link's end (a stretch of the tour marked backwards, each polyline in it
/// turned round), while one shortens the travel. Each polyline keeps its part (None for a
/// label).
pub fn order_etch(
    lines: &[(Option<usize>, Vec<DVec2>)],
    from: DVec2,
    improve: bool,
) -> Vec<ToolPath> {
    let live: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].1.len() >= 2)
        .collect();
    let n = live.len();
    if n == 0 {
        return Vec::new();
    }
    // Endpoint 2i is polyline i's first point, 2i + 1 its last.
    let ends: Vec<DVec2> = live
        .iter()
        .flat_map(|&i| {
            let l = &lines[i].1;
            [l[0], l[l.len() - 1]]
        })
        .collect();
    let grid = Grid::new(&ends);
    // Nearest neighbour: the tour as (polyline, turned round).
    let mut tour: Vec<(usize, bool)> = Vec::with_capacity(n);
    {
        let mut cells = grid.cells.clone();
        let mut at = from;
        for _ in 0..n {
            let centre = grid.coords(at);
            let mut best: Option<(f64, usize)> = None;
            for ring in 0..=grid.nx.max(grid.ny) {
                if let Some((d, _)) = best {
                    let reach = (ring as f64 - 1.0).max(0.0) * grid.cell;
                    if reach * reach > d {
                        break;
                    }
                }
                for c in grid.ring(centre, ring) {
                    for &e in &cells[c] {
                        let d = ends[e].distance_squared(at);
                        // Ties: a polyline's first point before any last point, then the
                        // earlier polyline.
                        let tie = |i: usize| (e % 2, e / 2) < (i % 2, i / 2);
                        if best.is_none_or(|(b, i)| d < b || (d == b && tie(i))) {
                            best = Some((d, e));
                        }
                    }
                }
            }
            let (_, e) = best.expect("an endpoint is left");
            let item = e / 2;
            for q in [2 * item, 2 * item + 1] {
                let k = grid.key(ends[q]);
                cells[k].retain(|&x| x != q);
            }
            let turned = e % 2 == 1;
            at = ends[2 * item + usize::from(!turned)];
            tour.push((item, turned));
        }
    }
    // 2-opt over neighbour lists.
    let passes = if improve { PASSES } else { 0 };
    let near: Vec<Vec<usize>> = (0..if improve { 2 * n } else { 0 })
        .map(|e| grid.nearest(&ends, ends[e], NEIGHBOURS, |q| q / 2 != e / 2))
        .collect();
    let near_from = if improve {
        grid.nearest(&ends, from, NEIGHBOURS, |_| true)
    } else {
        Vec::new()
    };
    let start = |t: &(usize, bool)| 2 * t.0 + usize::from(t.1);
    let end = |t: &(usize, bool)| 2 * t.0 + usize::from(!t.1);
    let mut pos = vec![0usize; n];
    for (k, t) in tour.iter().enumerate() {
        pos[t.0] = k;
    }
    let d = |a: DVec2, b: DVec2| a.distance(b);
    for _ in 0..passes {
        let mut improved = false;
        for i in 0..n {
            // The link into position i, from `x` (the origin or the end before it); new
            // links from x to the end of a later polyline j.
            let x = if i == 0 {
                from
            } else {
                ends[end(&tour[i - 1])]
            };
            let cands = if i == 0 {
                &near_from
            } else {
                &near[end(&tour[i - 1])]
            };
            let mut best: Option<(f64, usize)> = None;
            for &q in cands {
                let j = pos[q / 2];
                if j < i || q != end(&tour[j]) {
                    continue;
                }
                let si = ends[start(&tour[i])];
                let ej = ends[q];
                let mut gain = d(x, si) - d(x, ej);
                if j + 1 < n {
                    let sn = ends[start(&tour[j + 1])];
                    gain += d(ej, sn) - d(si, sn);
                }
                if gain > GAIN && best.is_none_or(|(g, _)| gain > g) {
                    best = Some((gain, j));
                }
            }
            // New links from the start of a later polyline j + 1 back to the start of i.
            for &q in &near[start(&tour[i])] {
                let m = pos[q / 2];
                if m <= i || q != start(&tour[m]) {
                    continue;
                }
                let j = m - 1;
                let si = ends[start(&tour[i])];
                let ej = ends[end(&tour[j])];
                let sn = ends[q];
                let gain = d(x, si) + d(ej, sn) - d(x, ej) - d(si, sn);
                if gain > GAIN && best.is_none_or(|(g, _)| gain > g) {
                    best = Some((gain, j));
                }
            }
            if let Some((_, j)) = best {
                tour[i..=j].reverse();
                for k in i..=j {
                    tour[k].1 = !tour[k].1;
                    pos[tour[k].0] = k;
                }
                improved = true;
            }
        }
        // Or-opt: one polyline moved (either way round) next to a near endpoint elsewhere.
        for p in 0..n {
            let t = tour[p];
            let (sp, ep) = (ends[start(&t)], ends[end(&t)]);
            let prev = if p == 0 {
                from
            } else {
                ends[end(&tour[p - 1])]
            };
            let next = tour.get(p + 1).map(|u| ends[start(u)]);
            let out_gain =
                d(prev, sp) + next.map_or(0.0, |q| d(ep, q)) - next.map_or(0.0, |q| d(prev, q));
            if out_gain <= GAIN {
                continue;
            }
            // (gain, insert before this position of the tour without p, turned).
            let mut best: Option<(f64, usize, bool)> = None;
            for &q in near[2 * t.0].iter().chain(&near[2 * t.0 + 1]) {
                let m = pos[q / 2];
                // Where p would go: after m when q is m's end, before it when its start.
                let after = q == end(&tour[m]);
                let slot = if after { m + 1 } else { m };
                // Neighbours of the slot once p is out.
                let a_pos = (0..slot).rev().find(|&k| k != p);
                let b_pos = (slot..n).find(|&k| k != p);
                let a = a_pos.map_or(from, |k| ends[end(&tour[k])]);
                let b = b_pos.map(|k| ends[start(&tour[k])]);
                for turned in [false, true] {
                    let (s2, e2) = if turned { (ep, sp) } else { (sp, ep) };
                    let cost = d(a, s2) + b.map_or(0.0, |q| d(e2, q)) - b.map_or(0.0, |q| d(a, q));
                    let gain = out_gain - cost;
                    if gain > GAIN && best.is_none_or(|(g, _, _)| gain > g) {
                        let at = if slot > p { slot - 1 } else { slot };
                        best = Some((gain, at, turned));
                    }
                }
            }
            if let Some((_, at, turned)) = best {
                let mut moved = tour.remove(p);
                if turned {
                    moved.1 = !moved.1;
                }
                tour.insert(at, moved);
                let (lo, hi) = (p.min(at), p.max(at));
                for k in lo..=hi {
                    pos[tour[k].0] = k;
                }
                improved = true;
            }
        }
        if !improved {
            break;
        }
    }
    tour.iter()
        .map(|&(item, turned)| {
            let (part, l) = &lines[live[item]];
            let mut pts = l.clone();
            if turned {
                pts.reverse();
            }
            ToolPath {
                op: Op::Etch,
                part: *part,
                start: pts[0],
                segs: pts[1..].iter().map(|&q| Seg::Line(q)).collect(),
            }
        })
        .collect()
}

/// The program of one sheet: the etching of `etch` (as [`order_etch`] takes it), then
/// the parts (plate index and drawing, in the proposed order) with their contours offset by
/// `r`. In [`CutOrder::Travel`] the parts are reordered on their exact entry and exit points
/// (2-opt and Or-opt from the proposed order and from a plain nearest-neighbour tour, the
/// shorter kept); in [`CutOrder::Spread`] the proposed order stands. `pairs` (positions in
/// `parts`) are cut one straight after the other: the second starts in the first's kerf.
pub fn plan_sheet(
    parts: &[(usize, &Drawn)],
    pairs: &[(usize, usize)],
    etch: &[(Option<usize>, Vec<DVec2>)],
    r: f64,
    order: CutOrder,
) -> SheetPlan {
    let mut paths_of: Vec<Vec<ToolPath>> =
        parts.iter().map(|(i, d)| part_paths(*i, d, r)).collect();
    // Units cut together: a part alone, or a pair, the second's paths after the first's.
    let mut members: Vec<Vec<usize>> = (0..parts.len()).map(|k| vec![k]).collect();
    for &(a, b) in pairs {
        let second = std::mem::take(&mut paths_of[b]);
        paths_of[a].extend(second);
        members[a].push(b);
        members[b].clear();
    }
    let (groups, members): (Vec<Vec<ToolPath>>, Vec<Vec<usize>>) = paths_of
        .into_iter()
        .zip(members)
        .filter(|(_, m)| !m.is_empty())
        .unzip();
    // Two plans: the etching improved, and a plain nearest-neighbour tour over the improved
    // order's polylines (whose end may suit the parts better); the shorter is kept. A
    // nearest-neighbour tour over the polylines as drawn (ties to the first) then the parts is
    // never shorter than the plan kept.
    let improved = best_etch(etch, DVec2::ZERO);
    let as_drawn: Vec<(Option<usize>, Vec<DVec2>)> =
        improved.iter().map(|p| (p.part, points(p))).collect();
    let plans = [improved, order_etch(&as_drawn, DVec2::ZERO, false)].map(|etch_paths| {
        let from = etch_paths.last().map_or(DVec2::ZERO, ToolPath::end);
        let tour = part_tour(&groups, from, order);
        let mut paths = etch_paths;
        paths.extend(tour.iter().flat_map(|&k| groups[k].iter().cloned()));
        (SheetPlan::travel(&paths), paths, tour)
    });
    let [a, b] = plans;
    let (rapid_mm, paths, tour) = if b.0 < a.0 { b } else { a };
    let etched: Vec<Vec<DVec2>> = paths
        .iter()
        .filter(|p| p.op == Op::Etch)
        .map(points)
        .collect();
    SheetPlan {
        rapids: paths.len(),
        paths,
        parts: tour
            .iter()
            .flat_map(|&k| members[k].iter().map(|&m| parts[m].0))
            .collect(),
        etch: etched,
        rapid_mm,
        offset: r,
    }
}

/// A path's points: its start and each move's end.
fn points(p: &ToolPath) -> Vec<DVec2> {
    std::iter::once(p.start)
        .chain(p.segs.iter().map(Seg::end))
        .collect()
}

/// The etching improved ([`order_etch`]), then again from a nearest-neighbour tour over the
/// result's polylines in their order and direction, while that shortens it (ties in a
/// nearest-neighbour tour go by order, and the strokes of a tag share their end points, so each
/// round starts from a different tour).
fn best_etch(lines: &[(Option<usize>, Vec<DVec2>)], from: DVec2) -> Vec<ToolPath> {
    let mut best = order_etch(lines, from, true);
    for _ in 0..4 {
        let again: Vec<(Option<usize>, Vec<DVec2>)> =
            best.iter().map(|p| (p.part, points(p))).collect();
        let next = order_etch(&again, from, true);
        if SheetPlan::travel(&next) < SheetPlan::travel(&best) - GAIN {
            best = next;
        } else {
            break;
        }
    }
    best
}

/// The order of the parts' groups of paths from `from`: as given in [`CutOrder::Spread`]; in
/// [`CutOrder::Travel`] the shorter of 2-opt and Or-opt from the order given and from a plain
/// nearest-neighbour tour, on each group's exact entry and exit points.
fn part_tour(groups: &[Vec<ToolPath>], from: DVec2, order: CutOrder) -> Vec<usize> {
    let entry: Vec<DVec2> = groups.iter().map(|g| g[0].start).collect();
    let exit: Vec<DVec2> = groups.iter().map(|g| g[g.len() - 1].end()).collect();
    let mut tour: Vec<usize> = (0..groups.len()).collect();
    if order == CutOrder::Travel {
        let mut nn = nearest_tour(from, &entry, &exit);
        for t in [&mut tour, &mut nn] {
            two_opt(from, &entry, &exit, t);
            or_opt(from, &entry, &exit, t);
        }
        if tour_travel(from, &entry, &exit, &nn) < tour_travel(from, &entry, &exit, &tour) {
            tour = nn;
        }
    }
    tour
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(at: DVec2, s: f64) -> Vec<DVec2> {
        vec![
            at,
            at + DVec2::new(s, 0.0),
            at + DVec2::new(s, s),
            at + DVec2::new(0.0, s),
        ]
    }

    #[test]
    fn a_common_lines_second_part_is_cut_from_the_lines_end_round_to_its_start() {
        // Two squares 0.4 apart along x: the right one's left side is the left one's right
        // side moved by the gap, running the other way.
        let a = square(DVec2::ZERO, 100.0);
        let b = square(DVec2::new(100.4, 0.0), 100.0);
        let found = common_lines(&[a.clone(), b.clone()], 0.4, 1e-6);
        assert_eq!(found.len(), 1);
        let c = found[0];
        assert_eq!((c.first, c.edge, c.second), (0, 1, 1));
        assert!(c.from.distance(DVec2::new(100.2, 0.0)) < 1e-12, "{c:?}");
        assert!(c.to.distance(DVec2::new(100.2, 100.0)) < 1e-12, "{c:?}");
        // The second square drawn from the shared side's end (its corner (100.4, 0)).
        let mut outline = b.clone();
        outline.rotate_left((c.other_edge + 1) % 4);
        let d = Drawn {
            outline,
            common: true,
            ..Default::default()
        };
        let paths = part_paths(1, &d, 0.2);
        assert_eq!(paths.len(), 1);
        assert_eq!(paths[0].op, Op::FromKerf);
        // From the line's start round three sides (a quarter arc at each of the four corners)
        // back onto the line's end.
        assert!(
            paths[0].start.distance(c.from) < 1e-12,
            "{:?}",
            paths[0].start
        );
        assert!(
            paths[0].end().distance(c.to) < 1e-12,
            "{:?}",
            paths[0].end()
        );
        let expected = 300.0 + std::f64::consts::TAU * 0.2;
        assert!(
            (paths[0].length() - expected).abs() < 1e-9,
            "{}",
            paths[0].length()
        );
        assert_eq!(d.pierces(), 0);
        assert!((d.cut_length() - 300.0).abs() < 1e-9);
        // Too far apart: no common line.
        assert!(common_lines(&[a, b], 0.3, 1e-6).is_empty());
    }

    #[test]
    fn a_square_offset_outwards_keeps_its_corners_as_arcs() {
        let (start, segs) = offset_right(&square(DVec2::ZERO, 10.0), true, 0.5);
        assert_eq!(start, DVec2::new(0.0, -0.5));
        // Four lines and four quarter arcs, back to the start.
        assert_eq!(segs.len(), 8);
        assert_eq!(segs.last().map(Seg::end), Some(start));
        let path = ToolPath {
            op: Op::Outer,
            part: None,
            start,
            segs,
        };
        let expected = 40.0 + std::f64::consts::TAU * 0.5;
        assert!((path.length() - expected).abs() < 1e-9, "{}", path.length());
    }

    #[test]
    fn a_clockwise_ring_offset_inwards_meets_at_its_corners() {
        let mut ring = square(DVec2::ZERO, 10.0);
        ring[1..].reverse();
        let (start, segs) = offset_right(&ring, true, 1.0);
        assert_eq!(start, DVec2::new(1.0, 1.0));
        assert_eq!(segs.len(), 4);
        for s in &segs {
            assert!(matches!(s, Seg::Line(_)));
            let p = s.end();
            assert!((p.x - 1.0).abs() < 1e-12 || (p.x - 9.0).abs() < 1e-12);
            assert!((p.y - 1.0).abs() < 1e-12 || (p.y - 9.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_travel_tour_is_never_longer_than_nearest_neighbour() {
        // A scattered field of points: 2-opt and Or-opt from the nearest-neighbour tour.
        let mut pts = Vec::new();
        let mut s = 7u64;
        for _ in 0..120 {
            s = crate::geom::mix64(s);
            let x = (s % 3000) as f64;
            s = crate::geom::mix64(s);
            let y = (s % 1500) as f64;
            pts.push(DVec2::new(x, y));
        }
        let nn = nearest_tour(DVec2::ZERO, &pts, &pts);
        let mut t = nn.clone();
        two_opt(DVec2::ZERO, &pts, &pts, &mut t);
        or_opt(DVec2::ZERO, &pts, &pts, &mut t);
        let (a, b) = (
            tour_travel(DVec2::ZERO, &pts, &pts, &nn),
            tour_travel(DVec2::ZERO, &pts, &pts, &t),
        );
        assert!(
            b < 0.95 * a,
            "2-opt {b:.0} mm against nearest neighbour {a:.0} mm"
        );
        let mut sorted = t.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..pts.len()).collect::<Vec<_>>());
    }

    #[test]
    fn the_etching_starts_as_a_plain_nearest_neighbour_tour() {
        // Strokes scattered over a sheet, some sharing end points.
        let mut s = 11u64;
        let mut r = || {
            s = crate::geom::mix64(s);
            (s % 100_000) as f64 / 100.0
        };
        let lines: Vec<(Option<usize>, Vec<DVec2>)> = (0..400)
            .map(|_| {
                let a = DVec2::new(r(), 0.5 * r());
                (None, vec![a, a + DVec2::new(r() * 0.01, r() * 0.01)])
            })
            .collect();
        // Brute force: from wherever the last ended to the nearest end left.
        let mut left: Vec<bool> = vec![true; lines.len()];
        let mut at = DVec2::ZERO;
        let mut brute = 0.0;
        for _ in 0..lines.len() {
            let mut best = (f64::INFINITY, 0, false);
            for (i, (_, l)) in lines.iter().enumerate() {
                if !left[i] {
                    continue;
                }
                for (rev, e) in [(false, l[0]), (true, l[1])] {
                    let d = at.distance(e);
                    if d < best.0 {
                        best = (d, i, rev);
                    }
                }
            }
            brute += best.0;
            left[best.1] = false;
            at = if best.2 {
                lines[best.1].1[0]
            } else {
                lines[best.1].1[1]
            };
        }
        let nn = SheetPlan::travel(&order_etch(&lines, DVec2::ZERO, false));
        assert!(
            (nn - brute).abs() < 1e-6,
            "grid {nn} against brute force {brute}"
        );
        let better = SheetPlan::travel(&order_etch(&lines, DVec2::ZERO, true));
        assert!(better < 0.95 * brute, "{better} against {brute}");
    }

    #[test]
    fn parts_are_pierced_at_a_corner_towards_their_neighbours() {
        let a = square(DVec2::new(0.0, 0.0), 100.0);
        let b = square(DVec2::new(200.0, 0.0), 100.0);
        let shapes = [
            PartShape {
                outline: &a,
                holes: &[],
                pierce_at: None,
            },
            PartShape {
                outline: &b,
                holes: &[],
                pierce_at: None,
            },
        ];
        let o = order_parts(&shapes, DVec2::new(0.0, -50.0), CutOrder::Travel);
        assert_eq!(o.parts, vec![0, 1]);
        // The first part is pierced (and left) at its corner facing the second, which is
        // pierced at its corner nearest to that.
        assert_eq!(o.pierce, vec![1, 0]);
    }
}
