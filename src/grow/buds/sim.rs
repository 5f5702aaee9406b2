//! Buds and their scheduler. Each live bud in turn runs its program up to its next division
//! (or sleeps a turn), so every bud gets an equal share of the growth; buds made during a
//! round start in the next one.
//!
//! A division by a bud gives both children the bud's colour, texture and size; a bud in the
//! dividing cell follows the child furthest along its heading (or a random one). After the
//! division the two children and their ring are relaxed; every [`WIDE_EVERY`] divisions of a
//! bud its neighbourhood is relaxed more widely, and the whole form whenever it has grown by
//! a quarter. Every move is checked so that no triangle passes through another.
//!
//! A bud freezes when a cell it moved comes within the clearance of a part of the form more
//! than [`COLLIDE_HOPS`] + 1 hops from the divided cell, or when [`STUCK_LIMIT`] divisions in
//! a row were undone because no placement of the children was clear of the form.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::embed::Embedding;
#[cfg(doc)]
use super::embed::COLLIDE_HOPS;
use super::graph::{CellGraph, Split};
use super::hole::{self, HoleOutcome};
use super::program::{Command, Program, Texture, SIZE_RANGE};
use super::BudError;

/// Divisions of one bud between wider relaxations of its neighbourhood.
pub const WIDE_EVERY: u32 = 8;

/// No division raises a neighbour's degree past this while another choice exists (the
/// paper's forms keep degrees "approximately balanced"; the bound).
pub const MAX_DEGREE: usize = 12;

/// Blocked divisions in a row after which a bud freezes.
pub const STUCK_LIMIT: u32 = 16;

/// The whole form is relaxed once each time it has grown by 1/GLOBAL_EVERY of its cells.
pub const GLOBAL_EVERY: usize = 4;

#[derive(Clone, Debug)]
pub struct GrowthOptions {
    /// Cells at which growth stops (default 10,000).
    pub max_cells: usize,
    /// Distance, in cell sizes, within which two parts of the form collide (default 0.9).
    pub clearance: f64,
    /// Local relaxation sweeps after each division (default 2).
    pub sweeps: u32,
    /// Run `CellGraph::check()` after every operation (slow: for tests).
    pub verify: bool,
}

impl Default for GrowthOptions {
    fn default() -> Self {
        GrowthOptions {
            max_cells: 10_000,
            clearance: 0.9,
            sweeps: 1,
            verify: false,
        }
    }
}

/// Bud counts at one moment of growth.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Sample {
    pub round: u64,
    pub cells: usize,
    pub live: usize,
    pub frozen: usize,
    pub dead: usize,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct GrowthReport {
    pub cells: usize,
    pub divisions: u64,
    pub rounds: u64,
    pub genus: usize,
    pub holes: usize,
    /// `hole` commands that found no clear way through the form.
    pub holes_refused: usize,
    /// Divisions undone because no placement of the children was clear of the form (tried
    /// again elsewhere).
    pub divisions_blocked: usize,
    pub buds_made: usize,
    pub buds_dead: usize,
    pub buds_frozen: usize,
    pub buds_live: usize,
    /// Buds made per type, in program order.
    pub buds_by_type: Vec<(String, usize)>,
    /// `cap` (the cell cap was reached) or `buds` (no bud could go on).
    pub stopped_by: String,
    /// Cells by degree: (degree, count).
    pub degrees: Vec<(usize, usize)>,
    pub timeline: Vec<Sample>,
}

/// Where a bud ended: its type (index in the program), its cell, and whether it died.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BudAt {
    pub kind: usize,
    pub cell: u32,
    pub dead: bool,
}

/// A grown form: the cell graph and each cell's position and properties.
#[derive(Clone, Debug)]
pub struct Form {
    pub graph: CellGraph,
    pub pos: Vec<DVec3>,
    pub size: Vec<f64>,
    pub colour: Vec<[f32; 3]>,
    pub texture: Vec<Texture>,
    pub buds: Vec<BudAt>,
    pub report: GrowthReport,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    Live,
    Frozen,
    Dead,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Task {
    None,
    Grow,
    Blob,
}

#[derive(Clone, Debug)]
struct Bud {
    kind: usize,
    pc: usize,
    cell: u32,
    state: State,
    colour: [f32; 3],
    texture: Texture,
    size: f64,
    fat: u32,
    heading: Option<DVec3>,
    line: bool,
    task: Task,
    remaining: u32,
    sleeping: u32,
    /// The cells a `blob` grows among: its start and every cell it made.
    blob: Vec<u32>,
    divisions: u32,
    /// Divisions blocked in a row.
    stuck: u32,
}

/// A growth in progress: call [`Growth::round`] until it returns false.
pub struct Growth<'p> {
    program: &'p Program,
    options: GrowthOptions,
    graph: CellGraph,
    embed: Embedding,
    colour: Vec<[f32; 3]>,
    texture: Vec<Texture>,
    buds: Vec<Bud>,
    bud_at: Vec<Option<u32>>,
    rng: ChaCha8Rng,
    rounds: u64,
    divisions: u64,
    holes: usize,
    holes_refused: usize,
    blocked: usize,
    last_global: usize,
    timeline: Vec<Sample>,
    stopped_by: Option<String>,
    /// Rounds in a row in which the form did not change (no division, hole or split) and no
    /// bud slept.
    idle: u64,
    /// Commands run in those rounds.
    idle_commands: u64,
    /// Commands run since the start.
    commands: u64,
}

/// Rounds without a change to the form (and nobody asleep) after which a program is taken to
/// never grow: buds that only create buds, forever.
pub const MAX_IDLE_ROUNDS: u64 = 10_000;

/// Commands run without a change to the form after which a program is taken to never grow
/// (long chains of `create` make each idle round long).
pub const MAX_IDLE_COMMANDS: u64 = 10_000_000;

const START_COLOUR: [f32; 3] = [0.85, 0.82, 0.76];

/// Whether any bud type the first one can lead to (through `create`) divides a cell: a
/// program without one would run until the idle limits refuse it.
fn grows(program: &Program) -> bool {
    let mut seen = vec![false; program.types.len()];
    let mut stack = vec![0usize];
    seen[0] = true;
    while let Some(k) = stack.pop() {
        for c in &program.types[k].commands {
            match *c {
                Command::Grow(n) | Command::Blob(n) if n > 0 => return true,
                Command::Split => return true,
                Command::Create { bud, .. } if bud < seen.len() && !seen[bud] => {
                    seen[bud] = true;
                    stack.push(bud);
                }
                _ => {}
            }
        }
    }
    false
}

impl<'p> Growth<'p> {
    pub fn new(
        program: &'p Program,
        options: GrowthOptions,
        seed: u64,
    ) -> Result<Growth<'p>, BudError> {
        if program.types.is_empty() {
            return Err(BudError::Options("the program has no bud type".into()));
        }
        if !(options.clearance > 0.0 && options.clearance < 3.0) {
            return Err(BudError::Options(format!(
                "clearance {} is outside (0, 3) cell sizes",
                options.clearance
            )));
        }
        if !grows(program) {
            return Err(BudError::Options(format!(
                "no bud type that {} can lead to divides a cell (grow, blob or split): the \
                 program never grows",
                program.types[0].name
            )));
        }
        if options.max_cells < 4 {
            return Err(BudError::Options(format!(
                "a cap of {} cells is below the tetrahedron's 4",
                options.max_cells
            )));
        }
        let largest = program
            .types
            .iter()
            .flat_map(|t| &t.commands)
            .filter_map(|c| match c {
                Command::Size(s) => Some(*s),
                _ => None,
            })
            .fold(1.0f64, f64::max)
            .min(SIZE_RANGE.1);
        let (graph, corners) = CellGraph::tetrahedron();
        let embed = Embedding::new(corners.to_vec(), vec![1.0; 4], options.clearance, largest);
        let mut g = Growth {
            program,
            options,
            graph,
            embed,
            colour: vec![START_COLOUR; 4],
            texture: vec![Texture::Flat; 4],
            buds: Vec::new(),
            bud_at: vec![None; 4],
            rng: ChaCha8Rng::seed_from_u64(seed),
            rounds: 0,
            divisions: 0,
            holes: 0,
            holes_refused: 0,
            blocked: 0,
            last_global: 4,
            timeline: Vec::new(),
            stopped_by: None,
            idle: 0,
            idle_commands: 0,
            commands: 0,
        };
        g.add_bud(0, 0, None);
        g.sample();
        Ok(g)
    }

    pub fn cells(&self) -> usize {
        self.graph.len()
    }

    pub fn graph(&self) -> &CellGraph {
        &self.graph
    }

    pub fn positions(&self) -> &[DVec3] {
        &self.embed.pos
    }

    pub fn colours(&self) -> &[[f32; 3]] {
        &self.colour
    }

    pub fn holes(&self) -> usize {
        self.holes
    }

    pub fn live_buds(&self) -> usize {
        self.buds.iter().filter(|b| b.state == State::Live).count()
    }

    /// One round: every live bud takes its turn. False once growth has stopped.
    pub fn round(&mut self) -> Result<bool, BudError> {
        if self.stopped_by.is_some() {
            return Ok(false);
        }
        let n = self.buds.len();
        let before = (self.graph.len(), self.divisions, self.holes);
        let commands = self.commands;
        let mut slept = false;
        for b in 0..n {
            if self.graph.len() >= self.options.max_cells {
                break;
            }
            if self.buds[b].state == State::Live {
                slept |= self.buds[b].sleeping > 0;
                self.turn(b)?;
            }
        }
        self.rounds += 1;
        if (self.graph.len(), self.divisions, self.holes) == before && !slept {
            self.idle += 1;
            self.idle_commands += self.commands - commands;
            // One idle round can be the one in which every bud is between its creates and
            // the buds it made have yet to grow: the command limit needs two in a row.
            let busy = self.idle >= 2 && self.idle_commands >= MAX_IDLE_COMMANDS;
            if self.idle >= MAX_IDLE_ROUNDS || busy {
                return Err(BudError::Options(format!(
                    "{} live buds ran {} rounds ({} commands) without dividing a cell: the \
                     program never grows (a bud that only creates buds?)",
                    self.live_buds(),
                    self.idle,
                    self.idle_commands
                )));
            }
        } else {
            self.idle = 0;
            self.idle_commands = 0;
        }
        if self.graph.len() >= self.last_global + self.last_global / GLOBAL_EVERY {
            self.relax_all(1);
            self.last_global = self.graph.len();
        }
        let live = self.live_buds();
        if live != self.timeline.last().map_or(usize::MAX, |s| s.live)
            || self.rounds.is_multiple_of(25)
        {
            self.sample();
        }
        if self.graph.len() >= self.options.max_cells {
            self.stopped_by = Some("cap".into());
        } else if live == 0 {
            self.stopped_by = Some("buds".into());
        }
        Ok(self.stopped_by.is_none())
    }

    /// Relaxes the whole form once more and hands it over.
    pub fn finish(mut self) -> Form {
        self.relax_all(1);
        self.sample();
        let census = self
            .graph
            .check()
            .expect("growth keeps the cell graph a closed manifold");
        let mut degrees = std::collections::BTreeMap::new();
        for v in 0..self.graph.len() as u32 {
            *degrees.entry(self.graph.degree(v)).or_insert(0) += 1;
        }
        let count = |s: State| self.buds.iter().filter(|b| b.state == s).count();
        let by_type = self
            .program
            .types
            .iter()
            .enumerate()
            .map(|(k, t)| {
                (
                    t.name.clone(),
                    self.buds.iter().filter(|b| b.kind == k).count(),
                )
            })
            .collect();
        let report = GrowthReport {
            cells: census.cells,
            divisions: self.divisions,
            rounds: self.rounds,
            genus: census.genus,
            holes: self.holes,
            holes_refused: self.holes_refused,
            divisions_blocked: self.blocked,
            buds_made: self.buds.len(),
            buds_dead: count(State::Dead),
            buds_frozen: count(State::Frozen),
            buds_live: count(State::Live),
            buds_by_type: by_type,
            stopped_by: self.stopped_by.clone().unwrap_or_else(|| "buds".into()),
            degrees: degrees.into_iter().collect(),
            timeline: self.timeline,
        };
        let buds = self
            .buds
            .iter()
            .map(|b| BudAt {
                kind: b.kind,
                cell: b.cell,
                dead: b.state == State::Dead,
            })
            .collect();
        Form {
            buds,
            graph: self.graph,
            pos: self.embed.pos,
            size: self.embed.size,
            colour: self.colour,
            texture: self.texture,
            report,
        }
    }

    fn sample(&mut self) {
        let count = |s: State| self.buds.iter().filter(|b| b.state == s).count();
        let s = Sample {
            round: self.rounds,
            cells: self.graph.len(),
            live: count(State::Live),
            frozen: count(State::Frozen),
            dead: count(State::Dead),
        };
        self.timeline.push(s);
    }

    fn add_bud(&mut self, kind: usize, cell: u32, parent: Option<&Bud>) {
        let bud = Bud {
            kind,
            pc: 0,
            cell,
            state: State::Live,
            colour: parent.map_or(START_COLOUR, |p| p.colour),
            texture: parent.map_or(Texture::Flat, |p| p.texture),
            size: parent.map_or(1.0, |p| p.size),
            fat: parent.map_or(1, |p| p.fat),
            heading: parent.and_then(|p| p.heading),
            line: false,
            task: Task::None,
            remaining: 0,
            sleeping: 0,
            blob: Vec::new(),
            divisions: 0,
            stuck: 0,
        };
        self.bud_at[cell as usize] = Some(self.buds.len() as u32);
        self.buds.push(bud);
    }

    /// Bud `b` runs until it divides, sleeps, freezes or dies.
    fn turn(&mut self, b: usize) -> Result<(), BudError> {
        loop {
            let bud = &mut self.buds[b];
            if bud.sleeping > 0 {
                bud.sleeping -= 1;
                return Ok(());
            }
            if bud.remaining > 0 {
                bud.remaining -= 1;
                let cell = self.pick_cell(b);
                if self.divide_by(b, cell)?.is_none() {
                    // Blocked: the division is owed, and tried elsewhere next turn.
                    self.buds[b].remaining += 1;
                }
                return Ok(());
            }
            let Some(command) = self.program.types[bud.kind].commands.get(bud.pc).cloned() else {
                self.retire(b, State::Dead);
                return Ok(());
            };
            bud.pc += 1;
            self.commands += 1;
            match command {
                Command::Colour(c) => bud.colour = c,
                Command::Texture(t) => bud.texture = t,
                Command::Size(s) => bud.size = s,
                Command::Fat(r) => bud.fat = r,
                Command::Head(h) => bud.heading = h,
                Command::Line => bud.line = true,
                Command::Sleep(n) => bud.sleeping = n,
                Command::Grow(n) => {
                    bud.task = Task::Grow;
                    bud.remaining = n;
                }
                Command::Blob(n) => {
                    bud.task = Task::Blob;
                    bud.remaining = n;
                    let start = bud.cell;
                    let mut region = vec![start];
                    region.extend_from_slice(self.graph.neighbours(start));
                    self.buds[b].blob = region;
                }
                Command::Create { bud: kind, count } => self.create(b, kind, count),
                Command::Split => {
                    self.split(b)?;
                    return Ok(());
                }
                Command::Hole => {
                    self.hole(b)?;
                    return Ok(());
                }
            }
        }
    }

    fn retire(&mut self, b: usize, state: State) {
        let bud = &mut self.buds[b];
        if bud.state == State::Live {
            bud.state = state;
            if self.bud_at[bud.cell as usize] == Some(b as u32) {
                self.bud_at[bud.cell as usize] = None;
            }
        }
    }

    /// The cell a bud's current growth command divides next.
    fn pick_cell(&mut self, b: usize) -> u32 {
        let bud = &self.buds[b];
        match bud.task {
            Task::Blob if !bud.blob.is_empty() => {
                bud.blob[self.rng.random_range(0..bud.blob.len())]
            }
            _ => {
                // The hormone reaches at least the adjacent cells ("diffuses either to only the
                // adjacent cells or more widely"): `fat R` reaches R + 1 hops.
                let around = self
                    .embed
                    .within(&self.graph, bud.cell, (bud.fat + 1).min(255) as u8);
                around[self.rng.random_range(0..around.len())].0
            }
        }
    }

    /// Divides `cell` on behalf of bud `b` (Figure 2), moves any bud in it, keeps line buds
    /// joined, relaxes, and freezes `b` if the form came too close to itself.
    fn divide_by(&mut self, b: usize, cell: u32) -> Result<Option<Split>, BudError> {
        let ring = self.graph.neighbours(cell).to_vec();
        let n = ring.len();
        let i = self.lowest_degree(&ring);
        let j = if n.is_multiple_of(2) {
            (i + n / 2) % n
        } else {
            let (lo, hi) = ((i + n / 2) % n, (i + n / 2 + 1) % n);
            let (dl, dh) = (self.graph.degree(ring[lo]), self.graph.degree(ring[hi]));
            match dl.cmp(&dh) {
                std::cmp::Ordering::Less => lo,
                std::cmp::Ordering::Greater => hi,
                std::cmp::Ordering::Equal => {
                    if self.rng.random_bool(0.5) {
                        lo
                    } else {
                        hi
                    }
                }
            }
        };
        // The paper's opposite neighbour, unless that would take it past MAX_DEGREE: then the
        // nearest ring position to it that stays within (the balance the rule is for).
        let j = if self.graph.degree(ring[j]) < MAX_DEGREE {
            j
        } else {
            (1..n / 2)
                .flat_map(|d| [(j + d) % n, (j + n - d) % n])
                .find(|&k| k != i && self.graph.degree(ring[k]) < MAX_DEGREE)
                .unwrap_or(j)
        };
        let resident = self.bud_at[cell as usize];
        // Line buds next to the dividing cell's bud, of its type.
        let joined: Vec<u32> = match resident {
            Some(r) if self.buds[r as usize].line => ring
                .iter()
                .copied()
                .filter(|&u| {
                    self.bud_at[u as usize].is_some_and(|o| {
                        let o = &self.buds[o as usize];
                        o.line && o.kind == self.buds[r as usize].kind
                    })
                })
                .collect(),
            _ => Vec::new(),
        };
        let x = self.embed.pos[cell as usize];
        let old_size = self.embed.size[cell as usize];
        let normal = self.embed.normal(&self.graph, cell);
        let mut touched = ring.clone();
        touched.push(cell);
        let saved = self.graph.save(&touched);
        let split = self.graph.divide(cell, i, j);
        let (kept, new) = (split.kept, split.new);
        let bud = &self.buds[b];
        let (size, colour, texture) = (bud.size, bud.colour, bud.texture);
        let mean = |v: u32, g: &CellGraph, pos: &[DVec3]| {
            let ns = g.neighbours(v);
            ns.iter()
                .filter(|&&u| u != kept && u != new)
                .map(|&u| pos[u as usize])
                .sum::<DVec3>()
                / (ns.len() - 1) as f64
        };
        let dk = mean(kept, &self.graph, &self.embed.pos) - x;
        let dn = mean(new, &self.graph, &self.embed.pos) - x;
        // The children start towards their arcs, the surface bumped out a little; nearer the
        // old cell if that would make triangles meet. If no placement is clear the form is too
        // crowded here: the division is undone and the bud freezes.
        let placed = [(0.3, 0.1), (0.15, 0.0), (0.05, 0.0)]
            .iter()
            .any(|&(reach, bump)| {
                self.embed
                    .place(kept, x + reach * dk + bump * size * normal, size);
                self.embed
                    .place(new, x + reach * dn + bump * size * normal, size);
                let (pk, pn) = (self.embed.pos[kept as usize], self.embed.pos[new as usize]);
                self.embed.star_clear(&self.graph, kept, pk)
                    && self.embed.star_clear(&self.graph, new, pn)
            });
        if !placed {
            self.graph.restore(saved);
            self.embed.truncate(self.graph.len());
            self.embed.place(cell, x, old_size);
            self.blocked += 1;
            self.buds[b].stuck += 1;
            if self.buds[b].stuck >= STUCK_LIMIT {
                self.retire(b, State::Frozen);
            }
            return Ok(None);
        }
        self.buds[b].stuck = 0;
        self.embed.measure(&self.graph, kept);
        self.embed.measure(&self.graph, new);
        self.colour[kept as usize] = colour;
        self.colour.push(colour);
        self.texture[kept as usize] = texture;
        self.texture.push(texture);
        self.bud_at.push(None);
        if self.buds[b].task == Task::Blob {
            self.buds[b].blob.push(new);
        }
        self.divisions += 1;
        self.buds[b].divisions += 1;

        let mut moved = vec![kept, new];
        moved.extend_from_slice(&ring);
        for _ in 0..self.options.sweeps {
            for &v in &moved {
                self.embed.relax(&self.graph, v);
            }
        }
        if self.buds[b].divisions.is_multiple_of(WIDE_EVERY) {
            let around = self.buds[b].fat.saturating_add(3).min(12) as u8;
            let cells = self.embed.within(&self.graph, self.buds[b].cell, around);
            for (v, _) in cells {
                self.embed.relax(&self.graph, v);
            }
        }
        // The bud in the divided cell follows its heading.
        if let Some(r) = resident {
            let r = r as usize;
            let to = match self.buds[r].heading {
                Some(h) => {
                    let (a, c) = (self.embed.pos[kept as usize], self.embed.pos[new as usize]);
                    if c.dot(h) > a.dot(h) {
                        new
                    } else {
                        kept
                    }
                }
                None => {
                    if self.rng.random_bool(0.5) {
                        new
                    } else {
                        kept
                    }
                }
            };
            self.bud_at[cell as usize] = None;
            self.buds[r].cell = to;
            self.bud_at[to as usize] = Some(r as u32);
            // A line bud that lost a neighbour of its kind puts a new one between them.
            let other = if to == kept { new } else { kept };
            for &u in &joined {
                if !self.graph.adjacent(to, u) && self.bud_at[other as usize].is_none() {
                    let parent = self.buds[r].clone();
                    self.add_bud(parent.kind, other, Some(&parent));
                    let last = self.buds.len() - 1;
                    self.buds[last].pc = parent.pc;
                    self.buds[last].line = true;
                    self.buds[last].task = parent.task;
                    self.buds[last].remaining = parent.remaining;
                    self.buds[last].blob = parent.blob.clone();
                }
            }
        }
        // A blob's region is the blob itself, whose lumps may touch in its creases; a bud that
        // grows a limb freezes when the limb reaches another part of the form.
        if self.buds[b].task != Task::Blob
            && self.embed.crowded(&self.graph, kept, &moved).is_some()
        {
            self.retire(b, State::Frozen);
        }
        self.verify("a division")?;
        Ok(Some(split))
    }

    fn lowest_degree(&mut self, ring: &[u32]) -> usize {
        let low = ring
            .iter()
            .map(|&u| self.graph.degree(u))
            .min()
            .unwrap_or(0);
        let ties: Vec<usize> = (0..ring.len())
            .filter(|&k| self.graph.degree(ring[k]) == low)
            .collect();
        ties[self.rng.random_range(0..ties.len())]
    }

    /// `create TYPE K`: K buds in free cells round this one (its ring first, in ring order from
    /// a random start, so created buds are neighbours; then two hops out).
    fn create(&mut self, b: usize, kind: usize, count: u32) {
        let cell = self.buds[b].cell;
        let ring = self.graph.neighbours(cell).to_vec();
        let start = self.rng.random_range(0..ring.len());
        let mut candidates: Vec<u32> = (0..ring.len())
            .map(|k| ring[(start + k) % ring.len()])
            .collect();
        for (v, h) in self.embed.within(&self.graph, cell, 2) {
            if h == 2 {
                candidates.push(v);
            }
        }
        let parent = self.buds[b].clone();
        let mut made = 0;
        for v in candidates {
            if made == count {
                break;
            }
            if self.bud_at[v as usize].is_none() {
                self.add_bud(kind, v, Some(&parent));
                made += 1;
            }
        }
    }

    /// `split`: the bud's cell divides and each child holds one of the two buds.
    fn split(&mut self, b: usize) -> Result<(), BudError> {
        let cell = self.buds[b].cell;
        let Some(s) = self.divide_by(b, cell)? else {
            // Blocked: try the split again next turn.
            self.buds[b].pc -= 1;
            return Ok(());
        };
        if self.buds[b].state != State::Live {
            return Ok(());
        }
        let at = self.buds[b].cell;
        let other = if at == s.kept { s.new } else { s.kept };
        if self.bud_at[other as usize].is_none() {
            let parent = self.buds[b].clone();
            self.add_bud(parent.kind, other, Some(&parent));
            let last = self.buds.len() - 1;
            let mut twin = parent;
            twin.cell = other;
            twin.blob.clear();
            twin.divisions = 0;
            self.buds[last] = twin;
        }
        Ok(())
    }

    /// `hole`: a tunnel from the bud's cell through the form to the wall opposite.
    fn hole(&mut self, b: usize) -> Result<(), BudError> {
        let cell = self.buds[b].cell;
        let size = self.buds[b].size;
        let outcome =
            hole::grow(&mut self.graph, &mut self.embed, cell, size).map_err(|source| {
                BudError::Graph {
                    operation: "a hole".into(),
                    source,
                }
            })?;
        match outcome {
            HoleOutcome::Made { new_cells } => {
                self.holes += 1;
                for _ in 0..new_cells {
                    self.colour.push(self.buds[b].colour);
                    self.texture.push(Texture::Flat);
                    self.bud_at.push(None);
                }
            }
            HoleOutcome::Refused => self.holes_refused += 1,
        }
        self.verify("a hole")
    }

    /// Gauss-Seidel sweeps over every cell.
    fn relax_all(&mut self, sweeps: u32) {
        for _ in 0..sweeps {
            for v in 0..self.graph.len() as u32 {
                self.embed.relax(&self.graph, v);
            }
        }
        self.embed.remeasure(&self.graph);
    }

    fn verify(&self, operation: &str) -> Result<(), BudError> {
        if !self.options.verify {
            return Ok(());
        }
        let census = self.graph.check().map_err(|source| BudError::Graph {
            operation: operation.into(),
            source,
        })?;
        if census.genus != self.holes {
            return Err(BudError::Graph {
                operation: operation.into(),
                source: super::graph::GraphError::Euler {
                    euler: 2 - 2 * census.genus as i64,
                },
            });
        }
        Ok(())
    }
}

/// Grows a program to completion (or the cell cap).
pub fn grow(program: &Program, options: GrowthOptions, seed: u64) -> Result<Form, BudError> {
    let mut g = Growth::new(program, options, seed)?;
    while g.round()? {}
    Ok(g.finish())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grow::buds::{parse_program, ProgramError};

    #[test]
    fn a_program_grows_only_if_a_bud_it_can_reach_divides() -> Result<(), ProgramError> {
        let grows_ = |text: &str| parse_program(text, "t").map(|p| grows(&p));
        assert!(grows_(super::super::program::FIGURE_8)?);
        // Creates only, however many: refused before the first round.
        assert!(!grows_(&format!(
            "Base:\n{}",
            "create Base\n".repeat(1000)
        ))?);
        // A type that grows, but that nothing creates.
        assert!(!grows_("Base:\tNever:\ncreate Base\tgrow 5\n")?);
        // Reached through a chain of creates; grow 0 divides nothing.
        assert!(grows_("Base:\tA:\tB:\ncreate A\tcreate B\tsplit\n")?);
        assert!(!grows_("Base:\tA:\ncreate A\tgrow 0\n")?);
        let p = parse_program("Base:\ncreate Base\n", "t")?;
        let e = Growth::new(&p, GrowthOptions::default(), 1).err();
        assert!(
            e.is_some_and(|e| e.to_string().contains("no bud type that Base can lead to")),
            "refused up front"
        );
        Ok(())
    }
}
