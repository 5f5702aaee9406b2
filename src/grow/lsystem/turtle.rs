//! The turtle that draws a derived word (Prusinkiewicz and Lindenmayer 1990, ch. 1), in 2D and
//! 3D with one frame: heading H, left L, up U; it starts at the origin heading +Y with U = +Z,
//! so a word that only turns with `+ -` draws in the XY plane.
//!
//! | symbol | action |
//! | --- | --- |
//! | `F` | move forward one step, drawing |
//! | `f` | move forward one step without drawing |
//! | `+` `-` | turn left / right about U (counter-clockwise seen from +Z) |
//! | `&` `^` | pitch down / up about L |
//! | `\` `/` | roll left / right about H |
//! | `|` | turn around |
//! | `[` `]` | push / pop the state (position, frame, depth, width, node) |
//! | `!` | multiply the width by the decay factor |
//!
//! Every other symbol (`X`, …) only carries the grammar and does nothing. Each turn draws a
//! fresh angle from the angle range (Hanafin et al.'s "new turtle"); a fixed angle draws
//! nothing. The step is scaled by `length_scale` and the radius by `radius_scale` per bracket
//! depth.
//!
//! Simplification (Hanafin et al. §5.3): consecutive `F`s, with no symbol between them that
//! changes the turtle, are one segment: a straight member, not a row of collinear pieces.

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::super::tree::{Span, Tree};

/// A turn angle in degrees: fixed, or drawn afresh from `min..=max` at every turn.
pub type Angle = Span;

/// How the turtle draws. Lengths in mm.
#[derive(Clone, Debug, PartialEq)]
pub struct TurtleOptions {
    /// Length of one `F`. Default 500 (the paper's façade).
    pub step: f64,
    /// Turn angle. Default 22° (the paper's).
    pub angle: Angle,
    /// Step factor per bracket depth. Default 1.
    pub length_scale: f64,
    /// Merge runs of `F` into one segment. Default true.
    pub simplify: bool,
    /// Member radius at depth 0. Default 40.
    pub radius: f64,
    /// Radius factor per bracket depth. Default 0.8.
    pub radius_scale: f64,
    /// Radius factor of `!`. Default 0.7.
    pub decay: f64,
}

impl Default for TurtleOptions {
    fn default() -> Self {
        TurtleOptions {
            step: 500.0,
            angle: Angle::fixed(22.0),
            length_scale: 1.0,
            simplify: true,
            radius: 40.0,
            radius_scale: 0.8,
            decay: 0.7,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TurtleError {
    #[error("--{0} must be a positive number, got {1}")]
    NotPositive(&'static str, f64),
    #[error("angle= must lie in 0..360 degrees, got {0}..{1}")]
    Angle(f64, f64),
}

impl TurtleOptions {
    pub fn check(&self) -> Result<(), TurtleError> {
        for (name, v) in [
            ("step", self.step),
            ("length-scale", self.length_scale),
            ("radius", self.radius),
            ("radius-scale", self.radius_scale),
            ("decay", self.decay),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(TurtleError::NotPositive(name, v));
            }
        }
        let a = self.angle;
        if !(0.0..=360.0).contains(&a.min) || !(0.0..=360.0).contains(&a.max) {
            return Err(TurtleError::Angle(a.min, a.max));
        }
        Ok(())
    }
}

/// What a symbol does to the turtle.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Draw,
    Move,
    /// Rotation about U (0), L (1) or H (2), by +1 or −1 times the angle.
    Turn(u8, f64),
    TurnAround,
    Push,
    Pop,
    Decay,
    Nothing,
}

fn role(c: u8) -> Role {
    match c {
        b'F' => Role::Draw,
        b'f' => Role::Move,
        b'+' => Role::Turn(0, 1.0),
        b'-' => Role::Turn(0, -1.0),
        b'&' => Role::Turn(1, 1.0),
        b'^' => Role::Turn(1, -1.0),
        b'\\' => Role::Turn(2, 1.0),
        b'/' => Role::Turn(2, -1.0),
        b'|' => Role::TurnAround,
        b'[' => Role::Push,
        b']' => Role::Pop,
        b'!' => Role::Decay,
        _ => Role::Nothing,
    }
}

/// The counts the paper reports, from the word alone (no geometry).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Counts {
    /// Symbols in the word.
    pub symbols: u64,
    /// `F`s: segments the plain turtle draws.
    pub segments: u64,
    /// Segments after merging runs of `F`.
    pub simplified_segments: u64,
    #[serde(skip)]
    in_run: bool,
}

impl Counts {
    #[inline]
    pub fn feed(&mut self, c: u8) {
        self.symbols += 1;
        match role(c) {
            Role::Draw => {
                self.segments += 1;
                if !self.in_run {
                    self.simplified_segments += 1;
                    self.in_run = true;
                }
            }
            Role::Nothing => {}
            _ => self.in_run = false,
        }
    }
}

/// What the turtle did besides drawing.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TurtleStats {
    #[serde(flatten)]
    pub counts: Counts,
    /// Turns made (`+ - & ^ \ /`).
    pub turns: u64,
    /// Smallest and largest turn angle drawn, degrees (None without turns).
    pub turn_min_deg: Option<f64>,
    pub turn_max_deg: Option<f64>,
    /// Deepest bracket nesting.
    pub max_depth: u32,
}

#[derive(Clone, Copy)]
struct State {
    pos: DVec3,
    h: DVec3,
    l: DVec3,
    u: DVec3,
    /// The node at `pos`, if one was drawn there.
    node: Option<u32>,
    depth: u32,
    step: f64,
    radius: f64,
}

/// Draws a word fed to it symbol by symbol; `finish` gives the tree.
pub struct Turtle {
    opts: TurtleOptions,
    rng: ChaCha8Rng,
    state: State,
    stack: Vec<State>,
    /// `F`s read but not drawn yet (simplifying).
    run: u32,
    tree: Tree,
    stats: TurtleStats,
}

impl Turtle {
    /// A turtle at the origin heading +Y. `seed` draws the angles of a range.
    pub fn new(opts: &TurtleOptions, seed: u64) -> Turtle {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        // Angles on their own stream: the derivation's stochastic choices use stream 0.
        rng.set_stream(1);
        Turtle {
            opts: opts.clone(),
            rng,
            state: State {
                pos: DVec3::ZERO,
                h: DVec3::Y,
                l: DVec3::NEG_X,
                u: DVec3::Z,
                node: None,
                depth: 0,
                step: opts.step,
                radius: opts.radius,
            },
            stack: Vec::new(),
            run: 0,
            tree: Tree::default(),
            stats: TurtleStats {
                counts: Counts::default(),
                turns: 0,
                turn_min_deg: None,
                turn_max_deg: None,
                max_depth: 0,
            },
        }
    }

    #[inline]
    pub fn feed(&mut self, c: u8) {
        self.stats.counts.feed(c);
        let r = role(c);
        if r == Role::Draw {
            if self.opts.simplify {
                self.run += 1;
            } else {
                self.draw(1);
            }
            return;
        }
        if r == Role::Nothing {
            return;
        }
        if self.run > 0 {
            let k = std::mem::take(&mut self.run);
            self.draw(k);
        }
        let s = &mut self.state;
        match r {
            Role::Move => {
                s.pos += s.h * s.step;
                s.node = None;
            }
            Role::Turn(axis, sign) => {
                let a = self.angle() * sign;
                let (sin, cos) = a.sin_cos();
                let s = &mut self.state;
                // x turns towards y: (x cos + y sin, y cos − x sin).
                let rotate = |x: DVec3, y: DVec3| (x * cos + y * sin, y * cos - x * sin);
                match axis {
                    0 => (s.h, s.l) = rotate(s.h, s.l),
                    1 => (s.u, s.h) = rotate(s.u, s.h),
                    _ => (s.l, s.u) = rotate(s.l, s.u),
                }
            }
            Role::TurnAround => {
                s.h = -s.h;
                s.l = -s.l;
            }
            Role::Push => {
                self.stack.push(*s);
                s.depth += 1;
                s.step *= self.opts.length_scale;
                s.radius *= self.opts.radius_scale;
                self.stats.max_depth = self.stats.max_depth.max(s.depth);
            }
            Role::Pop => {
                // Grammars balance their brackets, so the stack is never empty here.
                if let Some(top) = self.stack.pop() {
                    *s = top;
                }
            }
            Role::Decay => s.radius *= self.opts.decay,
            Role::Draw | Role::Nothing => {}
        }
    }

    /// The next turn angle in radians.
    fn angle(&mut self) -> f64 {
        let deg = self.opts.angle.draw(&mut self.rng);
        let st = &mut self.stats;
        st.turns += 1;
        st.turn_min_deg = Some(st.turn_min_deg.map_or(deg, |m| m.min(deg)));
        st.turn_max_deg = Some(st.turn_max_deg.map_or(deg, |m| m.max(deg)));
        deg.to_radians()
    }

    /// A segment of `k` steps from the current position.
    fn draw(&mut self, k: u32) {
        let s = &mut self.state;
        let t = &mut self.tree;
        let start = match s.node {
            Some(n) => n,
            None => t.add(s.pos, None, s.radius),
        };
        s.pos += s.h * (k as f64 * s.step);
        s.node = Some(t.add(s.pos, Some(start), s.radius));
    }

    pub fn finish(mut self) -> (Tree, TurtleStats) {
        if self.run > 0 {
            let k = std::mem::take(&mut self.run);
            self.draw(k);
        }
        (self.tree, self.stats)
    }
}
