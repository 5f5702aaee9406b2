//! Room to fit and tighten a seam's bolts: the washer and head on one face of the stack, the
//! washer, nut and the bolt's end past it on the other, and a socket over the nut (the head is
//! held with a spanner from the side), as cylinders on the bolt's axis; none may cross another
//! plate or a node core. The nut goes on the +z face, or on the −z face where only that is
//! clear; a bolt clear either way moves along its row to the nearest place that keeps EN
//! 1993-1-8 Table 3.3 (the edge distances and both pitches to its neighbours) and is clear;
//! where none is, it is left out if the row keeps two bolts and its largest pitch without it
//! (the seam's bolt checks are made again), else the clash is reported.
//!
//! Shapes are convex prisms compared by the separating axis theorem (face normals and the
//! cross products of edge directions): exact for the plates (their outlines are convex; the
//! holes are left in, on the safe side), and each cylinder is the prism of the polygon drawn
//! around it, which holds it, so a clash is never missed (a false one is at most 0.5 % of the
//! radius outside the cylinder).

use glam::{DVec2, DVec3};

use super::bolts::{self, BoltSize};
use super::plates::{Placement, PlateSet};

/// Sides of the polygon drawn around a cylinder.
const SIDES: usize = 32;
/// How far bolts may be moved along their row in one step when looking for room, mm.
const STEP: f64 = 0.5;

/// The socket that tightens the bolts: its radius and how far it reaches from the washer, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Socket {
    pub radius: f64,
    pub height: f64,
}

impl Socket {
    /// `R:H` in mm.
    pub fn parse(s: &str) -> Result<Socket, String> {
        let (r, h) = s
            .split_once(':')
            .ok_or_else(|| format!("`{s}`: expected RADIUS:HEIGHT in mm, like 16:40"))?;
        let num = |v: &str| -> Result<f64, String> {
            v.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x > 0.0 && *x <= 1000.0)
                .ok_or_else(|| format!("`{s}`: `{v}` is not a length from 0 to 1000 mm"))
        };
        Ok(Socket {
            radius: num(r)?,
            height: num(h)?,
        })
    }

    /// A socket for the size: around the nut's corners with a 3 mm wall, 40 mm long.
    pub fn for_size(bolt: &BoltSize) -> Socket {
        Socket {
            radius: bolt.across_flats / 3f64.sqrt() + 3.0,
            height: 40.0,
        }
    }
}

/// A convex solid: its corners, face normals and edge directions.
#[derive(Clone, Debug)]
pub struct Convex {
    points: Vec<DVec3>,
    normals: Vec<DVec3>,
    edges: Vec<DVec3>,
    centre: DVec3,
    radius: f64,
}

impl Convex {
    /// The convex `outline` (in a frame) between heights `z0` and `z1` along its normal.
    pub fn prism(outline: &[DVec2], frame: &Placement, z0: f64, z1: f64) -> Convex {
        let mut points = Vec::with_capacity(2 * outline.len());
        for z in [z0, z1] {
            points.extend(outline.iter().map(|p| frame.world(*p, z)));
        }
        let mut normals = vec![frame.z];
        let mut edges = vec![frame.z];
        for k in 0..outline.len() {
            let d = outline[(k + 1) % outline.len()] - outline[k];
            let along = frame.x * d.x + frame.y * d.y;
            if let Some(a) = along.try_normalize() {
                edges.push(a);
                normals.push(a.cross(frame.z));
            }
        }
        let centre = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
        let radius = points
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0, f64::max);
        Convex {
            points,
            normals,
            edges,
            centre,
            radius,
        }
    }

    /// A cylinder of `radius` on the line through `base` along the unit `axis`, from `base`
    /// to `length` along it: the prism of the polygon drawn around it.
    pub fn cylinder(base: DVec3, axis: DVec3, radius: f64, length: f64) -> Convex {
        let u = axis.any_orthonormal_vector();
        let frame = Placement {
            origin: base,
            x: u,
            y: axis.cross(u),
            z: axis,
        };
        let r = radius / (std::f64::consts::PI / SIDES as f64).cos();
        let outline: Vec<DVec2> = (0..SIDES)
            .map(|i| DVec2::from_angle(std::f64::consts::TAU * i as f64 / SIDES as f64) * r)
            .collect();
        Convex::prism(&outline, &frame, 0.0, length)
    }

    fn span(&self, axis: DVec3) -> (f64, f64) {
        self.points
            .iter()
            .map(|p| p.dot(axis))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    }

    /// Whether the two cross by more than `tolerance` on every axis.
    pub fn crosses(&self, other: &Convex, tolerance: f64) -> bool {
        if self.centre.distance(other.centre) > self.radius + other.radius + tolerance {
            return false;
        }
        let apart = |axis: DVec3| {
            let (a0, a1) = self.span(axis);
            let (b0, b1) = other.span(axis);
            a1 <= b0 + tolerance || b1 <= a0 + tolerance
        };
        if self.normals.iter().chain(&other.normals).any(|n| apart(*n)) {
            return false;
        }
        for a in &self.edges {
            for b in &other.edges {
                if let Some(n) = a.cross(*b).try_normalize() {
                    if apart(n) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// A bolt whose fitting or tightening room crosses a plate or core.
#[derive(Clone, Debug, PartialEq)]
pub struct Clash {
    /// The seam's plies (indices into `PlateSet::plates`), and the hole.
    pub plies: [usize; 2],
    pub hole: usize,
    /// `head`, `nut`, or the socket on either side.
    pub envelope: &'static str,
    /// What it crosses: a plate index, or a core's (`PlateSet::cores`) as `Err`.
    pub with: Result<usize, usize>,
}

/// What was done: bolts moved along their rows or turned over, and the clashes left.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Room {
    /// Per moved bolt: the plies, the hole, how far it moved, mm.
    pub moved: Vec<([usize; 2], usize, f64)>,
    /// Bolts whose nut goes on the stack's −z face (the plies' frame): the plies, the hole.
    pub nut_below: Vec<([usize; 2], usize)>,
    /// Bolts left out (no room anywhere along the row, and the row holds Table 3.3 without
    /// them): the plies, where the hole was.
    pub dropped: Vec<([usize; 2], DVec2)>,
    pub clashes: Vec<Clash>,
}

/// The envelopes of a bolt at `centre` (plate frame of the seam's plies) as convex shapes, with
/// their names: the washer and head on one face of the stack, the washer, nut and the bolt's
/// end on the other (+z, or −z when `below`), and the socket over the nut from the washer on.
fn envelopes(
    frame: &Placement,
    stack: [f64; 2],
    centre: DVec2,
    bolt: &BoltSize,
    socket: &Socket,
    below: bool,
) -> Vec<(&'static str, Convex)> {
    let corners = bolt.across_flats / 3f64.sqrt();
    let fitting = (0.5 * bolt.washer_od).max(corners);
    let at = frame.world(centre, 0.0);
    let (head_face, nut_face, out) = if below {
        (stack[1], stack[0], -frame.z)
    } else {
        (stack[0], stack[1], frame.z)
    };
    let head = bolt.washer + bolt.head;
    let nut = bolt.washer + bolt.nut + 2.0 * bolt.pitch;
    vec![
        (
            "head and washer",
            Convex::cylinder(at + frame.z * head_face, -out, fitting, head),
        ),
        (
            "nut and washer",
            Convex::cylinder(at + frame.z * nut_face, out, fitting, nut),
        ),
        (
            "socket on the nut",
            Convex::cylinder(
                at + frame.z * nut_face + out * bolt.washer,
                out,
                socket.radius,
                socket.height,
            ),
        ),
    ]
}

/// Checks every seam's bolts against every other plate and the cores, moving a clashing bolt
/// along its row where a place keeps Table 3.3 and is clear. `socket` None: one for each size
/// ([`Socket::for_size`]).
pub fn make_room(set: &mut PlateSet, socket: Option<Socket>) -> Room {
    if set.plates.iter().all(|p| p.bolt.is_none()) {
        return Room::default();
    }
    let solids: Vec<Convex> = set
        .plates
        .iter()
        .map(|p| {
            Convex::prism(
                &p.outline,
                &p.placement,
                -0.5 * p.thickness,
                0.5 * p.thickness,
            )
        })
        .collect();
    let cores: Vec<Convex> = set
        .cores
        .iter()
        .map(|c| Convex::cylinder(c.base, c.axis, 0.5 * c.size.diameter, c.length))
        .collect();
    let mut room = Room::default();
    for edge in 0..set.by_edge.len() {
        let [a, b] = match set.by_edge[edge][..] {
            [a, b] => [a, b],
            _ => continue,
        };
        let Some(bolting) = set.plates[a].bolt else {
            continue;
        };
        let bolt = bolting.size;
        let socket = socket.unwrap_or_else(|| Socket::for_size(&bolt));
        // The stack's faces in ply a's frame: a is on −z, b on +z, face to face.
        let (pa, pb) = (&set.plates[a], &set.plates[b]);
        let frame = pa.placement;
        let stack = [-0.5 * pa.thickness, 0.5 * pa.thickness + pb.thickness];
        let overlap = overlap_outline(&pa.outline, &pb.outline);
        let thinner = pa.thickness.min(pb.thickness);
        let clash_with = |c: DVec2, below: bool| -> Option<(&'static str, Result<usize, usize>)> {
            for (name, env) in envelopes(&frame, stack, c, &bolt, &socket, below) {
                for (i, s) in solids.iter().enumerate() {
                    if i != a && i != b && env.crosses(s, 1e-9) {
                        return Some((name, Ok(i)));
                    }
                }
                for (i, s) in cores.iter().enumerate() {
                    if env.crosses(s, 1e-9) {
                        return Some((name, Err(i)));
                    }
                }
            }
            None
        };
        // The nut on +z where that is clear, else on −z: the first clash, or None and the side.
        let clash_at = |c: DVec2| -> Result<bool, (&'static str, Result<usize, usize>)> {
            match clash_with(c, false) {
                None => Ok(false),
                Some(first) => clash_with(c, true).map_or(Ok(true), |_| Err(first)),
            }
        };
        let mut holes = set.plates[a].holes.clone();
        let mut h = 0;
        while h < holes.len() {
            let first = match clash_at(holes[h]) {
                Ok(below) => {
                    if below {
                        room.nut_below.push(([a, b], h));
                    }
                    h += 1;
                    continue;
                }
                Err(first) => first,
            };
            match slide(&holes, h, &overlap, &bolt, thinner, &clash_at) {
                Some((to, below)) => {
                    room.moved.push(([a, b], h, to.distance(holes[h])));
                    if below {
                        room.nut_below.push(([a, b], h));
                    }
                    holes[h] = to;
                }
                // Left out where the row keeps two bolts and its largest pitch without it.
                None if holes.len() > 2
                    && (h == 0
                        || h + 1 == holes.len()
                        || holes[h - 1].distance(holes[h + 1])
                            <= bolts::max_pitch(thinner) + 1e-9) =>
                {
                    room.dropped.push(([a, b], holes[h]));
                    holes.remove(h);
                    continue;
                }
                None => room.clashes.push(Clash {
                    plies: [a, b],
                    hole: h,
                    envelope: first.0,
                    with: first.1,
                }),
            }
            h += 1;
        }
        set.plates[a].holes = holes.clone();
        set.plates[b].holes = holes;
    }
    room
}

/// The plies' common outline (both convex, in the same frame).
pub fn overlap_outline(a: &[DVec2], b: &[DVec2]) -> Vec<DVec2> {
    let mut out = a.to_vec();
    for k in 0..b.len() {
        let (p, q) = (b[k], b[(k + 1) % b.len()]);
        let inward = (q - p).perp().normalize_or_zero();
        out = crate::geom::clip_convex(&out, p, inward);
    }
    out
}

/// The nearest place for hole `h` along its row (the line through its neighbours, or across for
/// a row of two) that keeps e ≥ 1.2 d0 from the overlap's edges, p ≥ least and ≤ largest pitch
/// to its neighbours, and is clear (with the nut on −z if that is the side); None if there is
/// none.
type ClashAt<'a> = dyn Fn(DVec2) -> Result<bool, (&'static str, Result<usize, usize>)> + 'a;

fn slide(
    holes: &[DVec2],
    h: usize,
    overlap: &[DVec2],
    bolt: &BoltSize,
    thinner: f64,
    clash_at: &ClashAt,
) -> Option<(DVec2, bool)> {
    let other = if h > 0 { h - 1 } else { h + 1 };
    let dir = (holes[h] - *holes.get(other)?).try_normalize()?;
    // A row along the member keeps p1 ≥ 2.2 d0; one across it (a short seam's) p2 ≥ 2.4 d0.
    let least = if dir.x.abs() >= 0.5 {
        bolts::min_pitch(bolt)
    } else {
        bolts::min_pitch_across(bolt)
    };
    let largest = bolts::max_pitch(thinner);
    let e = bolts::edge_distance(bolt);
    let fits = |c: DVec2| {
        let inside = (0..overlap.len()).all(|k| {
            let (p, q) = (overlap[k], overlap[(k + 1) % overlap.len()]);
            (q - p).normalize_or_zero().perp_dot(c - p) >= e - 1e-9
        });
        let pitched = [h.checked_sub(1), Some(h + 1)]
            .into_iter()
            .flatten()
            .filter_map(|j| holes.get(j))
            .all(|n| (least - 1e-9..=largest + 1e-9).contains(&n.distance(c)));
        inside && pitched
    };
    let reach = largest + e;
    let steps = (reach / STEP).ceil() as usize;
    for i in 1..=steps {
        for sign in [1.0, -1.0] {
            let c = holes[h] + dir * (sign * STEP * i as f64);
            if fits(c) {
                if let Ok(below) = clash_at(c) {
                    return Some((c, below));
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square_plate(origin: DVec3, z: DVec3) -> Convex {
        let x = z.any_orthonormal_vector();
        let frame = Placement {
            origin,
            x,
            y: z.cross(x),
            z,
        };
        let outline = [
            DVec2::new(-50.0, -50.0),
            DVec2::new(50.0, -50.0),
            DVec2::new(50.0, 50.0),
            DVec2::new(-50.0, 50.0),
        ];
        Convex::prism(&outline, &frame, -1.0, 1.0)
    }

    #[test]
    fn the_separating_axis_test_sees_crossing_and_clear_shapes() {
        // A cylinder standing on a plate: touching is not a clash, 0.1 mm in is.
        let plate = square_plate(DVec3::ZERO, DVec3::Z);
        let on = Convex::cylinder(DVec3::new(0.0, 0.0, 1.0), DVec3::Z, 10.0, 20.0);
        assert!(!on.crosses(&plate, 1e-9));
        let into = Convex::cylinder(DVec3::new(0.0, 0.0, 0.9), DVec3::Z, 10.0, 20.0);
        assert!(into.crosses(&plate, 1e-9));
        // Beside the plate's edge, clear by 0.5 mm at the polygon's flat (its corner is 10 /
        // cos(π/32) out): the circumscribed polygon is clear too.
        let beside = Convex::cylinder(DVec3::new(60.6, 0.0, -5.0), DVec3::Z, 10.0, 10.0);
        assert!(!beside.crosses(&plate, 1e-9));
        // A plate tilted into the cylinder's side (a crossing only an edge-edge axis rules
        // out when it does not happen).
        let tilted = square_plate(
            DVec3::new(0.0, 0.0, 30.0),
            DVec3::new(1.0, 0.0, 1.0).normalize(),
        );
        let tall = Convex::cylinder(DVec3::ZERO, DVec3::Z, 5.0, 40.0);
        assert!(tall.crosses(&tilted, 1e-9));
        let short = Convex::cylinder(DVec3::ZERO, DVec3::Z, 5.0, 10.0);
        assert!(!short.crosses(&tilted, 1e-9));
    }

    #[test]
    fn sockets_parse_and_refuse_nonsense() {
        assert_eq!(
            Socket::parse("16:40"),
            Ok(Socket {
                radius: 16.0,
                height: 40.0
            })
        );
        for bad in ["16", "0:40", "-1:40", "nan:40", "16:1e9", "a:b"] {
            assert!(Socket::parse(bad).is_err(), "{bad}");
        }
    }
}
