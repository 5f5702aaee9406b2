//! Recursive bifurcation (Hanafin et al. §3.1 and §4, Figs. 2 and 4): a trunk, and at the end
//! of every branch two copies of it, turned one each way and scaled, down to a depth. With
//! ranges, each copy draws its own angle and scale factor (their Fig. 4). In 3D the plane of
//! each fork rolls about its parent branch (`roll`), as phyllotaxis does.
//!
//! Branches are made generation by generation (breadth first): nodes of one depth are
//! contiguous and a tree of depth d has 2^(d+1) − 1 edges.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::tree::{Span, Tree};

/// Deepest recursion allowed: 2^21 − 1 ≈ 2 million branches.
pub const MAX_DEPTH: u32 = 20;

/// The bifurcation's parameters. Lengths in mm, angles in degrees.
#[derive(Clone, Debug, PartialEq)]
pub struct BifurcationOptions {
    /// Generations of forks after the trunk. Default 6 (the paper's Fig. 2 right).
    pub depth: u32,
    /// Trunk length. Default 2000.
    pub length: f64,
    /// Angle between a branch and its parent, each side. Default 25.
    pub angle: Span,
    /// Length of a branch over its parent's. Default 0.75.
    pub scale: Span,
    /// Trunk radius. Default 60.
    pub radius: f64,
    /// Radius factor per generation. Default 0.8 (Murray's law for two equal children is
    /// 2^(−1/3) ≈ 0.794).
    pub radius_scale: f64,
    /// In 3D, how far each fork's plane turns about its parent branch (None: flat, in XY).
    pub roll: Option<f64>,
}

impl Default for BifurcationOptions {
    fn default() -> Self {
        BifurcationOptions {
            depth: 6,
            length: 2000.0,
            angle: Span::fixed(25.0),
            scale: Span::fixed(0.75),
            radius: 60.0,
            radius_scale: 0.8,
            roll: None,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BifurcationError {
    #[error("depth= {0} is more than {MAX_DEPTH} (2^(depth+1) − 1 branches)")]
    TooDeep(u32),
    #[error("--{0} must be a positive number, got {1}")]
    NotPositive(&'static str, f64),
    #[error("angle= must lie in 0..180 degrees, got {0}..{1}")]
    Angle(f64, f64),
}

impl BifurcationOptions {
    pub fn check(&self) -> Result<(), BifurcationError> {
        if self.depth > MAX_DEPTH {
            return Err(BifurcationError::TooDeep(self.depth));
        }
        for (name, v) in [
            ("length", self.length),
            ("scale", self.scale.min),
            ("radius", self.radius),
            ("radius-scale", self.radius_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(BifurcationError::NotPositive(name, v));
            }
        }
        let a = self.angle;
        if !(0.0..=180.0).contains(&a.min) || !(0.0..=180.0).contains(&a.max) {
            return Err(BifurcationError::Angle(a.min, a.max));
        }
        if let Some(r) = self.roll {
            if !r.is_finite() {
                return Err(BifurcationError::NotPositive("roll", r));
            }
        }
        Ok(())
    }
}

/// A branch whose end still forks: its end node, frame (heading, left, up), length, radius.
struct Tip {
    node: u32,
    h: DVec3,
    l: DVec3,
    u: DVec3,
    length: f64,
    radius: f64,
}

/// Grows the tree: the trunk from the origin up +Y, then `depth` generations of forks.
pub fn bifurcate(opts: &BifurcationOptions, seed: u64) -> Result<Tree, BifurcationError> {
    opts.check()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut tree = Tree::default();
    tree.add(DVec3::ZERO, None, opts.radius);
    let trunk = tree.add(DVec3::Y * opts.length, Some(0), opts.radius);
    let mut tips = vec![Tip {
        node: trunk,
        h: DVec3::Y,
        l: DVec3::NEG_X,
        u: DVec3::Z,
        length: opts.length,
        radius: opts.radius,
    }];
    for _ in 0..opts.depth {
        let mut next = Vec::with_capacity(tips.len() * 2);
        for tip in &tips {
            let (mut l, mut u) = (tip.l, tip.u);
            if let Some(roll) = opts.roll {
                let (s, c) = roll.to_radians().sin_cos();
                (l, u) = (l * c + u * s, u * c - l * s);
            }
            for side in [1.0, -1.0] {
                let a = opts.angle.draw(&mut rng).to_radians() * side;
                let k = opts.scale.draw(&mut rng);
                let (s, c) = a.sin_cos();
                let (h, l) = (tip.h * c + l * s, l * c - tip.h * s);
                let (length, radius) = (tip.length * k, tip.radius * opts.radius_scale);
                let start = tree.network.nodes[tip.node as usize].p;
                let node = tree.add(start + h * length, Some(tip.node), radius);
                next.push(Tip {
                    node,
                    h,
                    l,
                    u,
                    length,
                    radius,
                });
            }
        }
        tips = next;
    }
    Ok(tree)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fixed_fork_is_symmetric_and_counts_its_branches() -> Result<(), BifurcationError> {
        for depth in [0, 1, 2, 6] {
            let t = bifurcate(
                &BifurcationOptions {
                    depth,
                    ..Default::default()
                },
                1,
            )?;
            assert_eq!(t.network.edges.len(), (1 << (depth + 1)) - 1);
            assert!(t.is_consistent());
        }
        let t = bifurcate(&BifurcationOptions::default(), 1)?;
        // The two children of a fork mirror each other about their parent.
        let n = &t.network.nodes;
        let (trunk, left, right) = (n[1].p, n[2].p - n[1].p, n[3].p - n[1].p);
        assert!((left.x + right.x).abs() < 1e-9 && (left.y - right.y).abs() < 1e-9);
        assert!((left.angle_between(trunk).to_degrees() - 25.0).abs() < 1e-9);
        assert!((left.length() - 1500.0).abs() < 1e-9);
        assert!(n.iter().all(|n| n.p.z == 0.0), "flat without roll");
        Ok(())
    }

    #[test]
    fn ranges_draw_per_branch_and_repeat_by_seed() -> Result<(), BifurcationError> {
        let opts = BifurcationOptions {
            angle: Span {
                min: 15.0,
                max: 40.0,
            },
            scale: Span { min: 0.6, max: 0.8 },
            ..Default::default()
        };
        let a = bifurcate(&opts, 5)?;
        assert_eq!(a, bifurcate(&opts, 5)?);
        assert_ne!(a, bifurcate(&opts, 6)?);
        let net = &a.network;
        for e in net.edges.iter().skip(1) {
            let parent = a.parent[e.a as usize].expect("branches have parents");
            let (pa, pb, c) = (
                net.nodes[parent as usize].p,
                net.nodes[e.a as usize].p,
                net.nodes[e.b as usize].p,
            );
            let turn = (pb - pa).angle_between(c - pb).to_degrees();
            let k = (c - pb).length() / (pb - pa).length();
            assert!((15.0 - 1e-9..=40.0 + 1e-9).contains(&turn), "{turn}");
            assert!((0.6 - 1e-12..=0.8 + 1e-12).contains(&k), "{k}");
        }
        Ok(())
    }

    #[test]
    fn a_rolled_tree_is_three_dimensional() -> Result<(), BifurcationError> {
        let t = bifurcate(
            &BifurcationOptions {
                roll: Some(90.0),
                ..Default::default()
            },
            1,
        )?;
        assert!(t.network.nodes.iter().any(|n| n.p.z.abs() > 100.0));
        assert_eq!(
            bifurcate(
                &BifurcationOptions {
                    depth: 21,
                    ..Default::default()
                },
                1
            ),
            Err(BifurcationError::TooDeep(21))
        );
        Ok(())
    }
}
