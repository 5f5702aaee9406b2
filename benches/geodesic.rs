//! Geodesic veins (Bachman) with 2,000 sources on a 100,000-vertex torus: our incremental
//! labelling against two baselines in the same run: a fresh multi-source Dijkstra from the
//! whole tree every iteration, and Bachman's own step, a Dijkstra from each source every
//! iteration (timed on every `GEODESIC_BACHMAN_EVERY`-th iteration, default 10; set it to 1 to
//! time all of them, about half an hour). All three again on a 10,000-vertex torus, where
//! Bachman's step runs whole. Then surface venation with at least 20,000 sources on a
//! 50,000-triangle torus. Both large meshes go to `target/bench-data` for the whole-process
//! runs in `scripts/bench geodesic`. `harness = false`: `cargo bench --bench geodesic [--
//! --quick]`.

use lamina::grow::geodesic::{grow_veins, Incremental, Labels, MeshGraph, Relabel, VeinTree};
use lamina::grow::surface::{self, grow_on_surface, SurfaceOptions};
use lamina::grow::venation::{Mode, VenationOptions};
use lamina::mesh::io::write_mesh;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[path = "common/meshes.rs"]
mod meshes;
#[path = "common/timing.rs"]
mod timing;
use timing::best_of;

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::Instant;

/// The first baseline: every iteration forgets the labels and runs a multi-source Dijkstra
/// from every tree vertex.
struct Recompute {
    tree: Vec<u32>,
}

impl Relabel for Recompute {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], labels: &mut Labels) {
        self.tree.extend_from_slice(added);
        labels.recompute(g, in_tree, &self.tree);
    }
}

/// One Dijkstra from a source until it reaches the tree (Bachman's step 1 for one source),
/// with its scratch space kept between calls.
struct SourcePath {
    dist: Vec<f64>,
    pred: Vec<u32>,
    touched: Vec<u32>,
    heap: BinaryHeap<Reverse<(Key, u32)>>,
}

impl SourcePath {
    fn new(n: usize) -> Self {
        SourcePath {
            dist: vec![f64::INFINITY; n],
            pred: vec![u32::MAX; n],
            touched: Vec::new(),
            heap: BinaryHeap::new(),
        }
    }

    /// (tree vertex at the path's end, the path's last vertex off the tree, its length), and
    /// the vertices the search labelled go to `self.touched`.
    fn find(&mut self, g: &MeshGraph, in_tree: &[bool], s: u32) -> Option<(u32, u32, f64)> {
        for &v in &self.touched {
            self.dist[v as usize] = f64::INFINITY;
            self.pred[v as usize] = u32::MAX;
        }
        self.touched.clear();
        self.heap.clear();
        self.dist[s as usize] = 0.0;
        self.touched.push(s);
        self.heap.push(Reverse((Key(0.0), s)));
        while let Some(Reverse((Key(d), x))) = self.heap.pop() {
            if d > self.dist[x as usize] {
                continue;
            }
            if in_tree[x as usize] {
                // The path's last vertex off the tree is the one we came from.
                return Some((x, self.pred[x as usize], d));
            }
            for (y, len) in g.neighbours(x) {
                let nd = d + len;
                if nd < self.dist[y as usize] {
                    self.dist[y as usize] = nd;
                    self.pred[y as usize] = x;
                    self.touched.push(y);
                    self.heap.push(Reverse((Key(nd), y)));
                }
            }
        }
        None
    }
}

/// Bachman's step 1 as written: every iteration, a Dijkstra from each live source until it
/// reaches the tree; only the sources get labels.
struct PerSource {
    sources: Vec<u32>,
    search: SourcePath,
}

impl Relabel for PerSource {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], _added: &[u32], labels: &mut Labels) {
        labels.changed = 0;
        for &s in &self.sources {
            if in_tree[s as usize] {
                continue;
            }
            if let Some((site, first, d)) = self.search.find(g, in_tree, s) {
                labels.site[s as usize] = site;
                labels.first[s as usize] = first;
                labels.dist[s as usize] = d;
            }
            labels.changed += self.search.touched.len();
        }
    }
}

/// Bachman's step on the large mesh, where a whole run would take too long to repeat: ours
/// drives the growth, and every `every`-th iteration Bachman's step is timed on the same tree
/// and live sources (every = 1 times every iteration), and its paths' lengths are checked
/// against our labels.
struct BachmanSampled {
    sources: Vec<u32>,
    search: SourcePath,
    every: usize,
    iteration: usize,
    ours: f64,
    sampled: f64,
    samples: usize,
    worst: f64,
}

impl Relabel for BachmanSampled {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], labels: &mut Labels) {
        let t = Instant::now();
        Incremental.update(g, in_tree, added, labels);
        self.ours += t.elapsed().as_secs_f64();
        self.iteration += 1;
        if !(self.iteration - 1).is_multiple_of(self.every) {
            return;
        }
        let t = Instant::now();
        for &s in &self.sources {
            if in_tree[s as usize] {
                continue;
            }
            let (_, _, d) = self.search.find(g, in_tree, s).expect("reachable");
            let ours = labels.dist[s as usize];
            self.worst = self.worst.max((d - ours).abs() / ours);
        }
        self.sampled += t.elapsed().as_secs_f64();
        self.samples += 1;
    }
}

#[derive(PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

fn same_tree(a: &VeinTree, b: &VeinTree) -> bool {
    a.order == b.order && a.parent == b.parent
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let mesh = meshes::torus(300.0, 100.0, 400, 250);
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&data).expect("bench-data folder");
    write_mesh(&mesh, &data.join("torus-100k.obj"), 512).expect("mesh file");
    let g = MeshGraph::new(&mesh);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    // 2,000 distinct source vertices, none of them the root.
    let root = 0;
    let mut drawn = std::collections::BTreeSet::new();
    while drawn.len() < 2000 {
        let v = rng.random_range(0..mesh.positions.len() as u32);
        if v != root {
            drawn.insert(v);
        }
    }
    let sources: Vec<u32> = drawn.into_iter().collect();
    println!(
        "geodesic veins: torus of {} vertices, {} triangles, {} sources",
        mesh.positions.len(),
        mesh.triangles.len(),
        sources.len()
    );
    let (t_inc, inc) = best_of(if quick { 1 } else { 3 }, || {
        grow_veins(&g, &mesh.positions, root, &sources, &mut Incremental).expect("grows")
    });
    println!(
        "  incremental: {:.3} s, {} iterations, {} tree vertices, {} labels updated",
        t_inc,
        inc.iterations,
        inc.order.len(),
        inc.relabelled
    );
    let (t_full, full) = best_of(1, || {
        grow_veins(
            &g,
            &mesh.positions,
            root,
            &sources,
            &mut Recompute { tree: Vec::new() },
        )
        .expect("grows")
    });
    println!(
        "  recompute every iteration: {:.3} s, {} labels updated; same tree: {}",
        t_full,
        full.relabelled,
        same_tree(&inc, &full)
    );
    println!("  ratio: {:.1}x", t_full / t_inc);
    let every: usize = std::env::var("GEODESIC_BACHMAN_EVERY")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(if quick { 50 } else { 10 })
        .max(1);
    let mut bachman = BachmanSampled {
        sources: sources.clone(),
        search: SourcePath::new(g.vertices()),
        every,
        iteration: 0,
        ours: 0.0,
        sampled: 0.0,
        samples: 0,
        worst: 0.0,
    };
    let t = Instant::now();
    grow_veins(&g, &mesh.positions, root, &sources, &mut bachman).expect("grows");
    let rest = t.elapsed().as_secs_f64() - bachman.ours - bachman.sampled;
    let estimate = bachman.sampled * bachman.iteration as f64 / bachman.samples as f64 + rest;
    println!(
        "  a Dijkstra per source (Bachman), timed on {} of the {} labellings (every {}): {:.1} \
         s timed, {:.0} s for the run ({:.0}x ours); its path lengths agree with our labels \
         to {:.1e}",
        bachman.samples,
        bachman.iteration,
        every,
        bachman.sampled,
        estimate,
        estimate / t_inc,
        bachman.worst
    );

    // On a 10,000-vertex torus Bachman's step runs whole, growing its own tree.
    let mesh = meshes::torus(300.0, 100.0, 125, 80);
    let g = MeshGraph::new(&mesh);
    let mut sources: Vec<u32> = (0..200)
        .map(|_| rng.random_range(0..mesh.positions.len() as u32))
        .collect();
    sources.sort_unstable();
    sources.dedup();
    println!(
        "geodesic veins, small: torus of {} vertices, {} sources",
        mesh.positions.len(),
        sources.len()
    );
    let (t_inc, inc) = best_of(3, || {
        grow_veins(&g, &mesh.positions, 0, &sources, &mut Incremental).expect("grows")
    });
    let (t_full, _) = best_of(1, || {
        grow_veins(
            &g,
            &mesh.positions,
            0,
            &sources,
            &mut Recompute { tree: Vec::new() },
        )
        .expect("grows")
    });
    let (t_each, each) = best_of(1, || {
        grow_veins(
            &g,
            &mesh.positions,
            0,
            &sources,
            &mut PerSource {
                sources: sources.clone(),
                search: SourcePath::new(g.vertices()),
            },
        )
        .expect("grows")
    });
    println!(
        "  incremental {:.4} s ({} iterations); multi-source recompute {:.3} s ({:.1}x); a \
         Dijkstra per source {:.3} s ({:.0}x, same tree: {})",
        t_inc,
        inc.iterations,
        t_full,
        t_full / t_inc,
        t_each,
        t_each / t_inc,
        same_tree(&inc, &each)
    );

    let mesh = meshes::torus(300.0, 100.0, 250, 100);
    write_mesh(&mesh, &data.join("torus-50k-triangles.obj"), 512).expect("mesh file");
    // `birth_for_count` aims at a count; dart throwing places a few percent fewer, so the
    // radius shrinks until the growth's own sampling (same seed) places at least 20,000.
    let seed = 1;
    let mut birth = surface::birth_for_count(&mesh, 20_000, None);
    loop {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let placed = surface::poisson_points(&mesh, birth, birth, None, &mut rng)
            .expect("samples")
            .len();
        if placed >= 20_000 {
            break;
        }
        birth *= 0.998 * (placed as f64 / 20_000.0).sqrt();
    }
    let step = (0.5 * birth).min(0.9 * surface::mean_edge_length(&mesh));
    let opts = SurfaceOptions {
        growth: VenationOptions {
            mode: Mode::Closed,
            step,
            kill: 1.5 * step,
            ..Default::default()
        },
        birth_min: birth,
        birth_max: birth,
        density: None,
        reach: None,
        edge_tolerance: None,
        murray: 3.0,
        tip_radius: step / 7.5,
        seed,
    };
    println!(
        "surface venation: torus of {} triangles, at least 20,000 sources (birth {:.4} mm)",
        mesh.triangles.len(),
        birth
    );
    for mode in [Mode::Closed, Mode::Open] {
        let o = SurfaceOptions {
            growth: VenationOptions {
                mode,
                ..opts.growth
            },
            ..opts.clone()
        };
        let (t, v) = best_of(if quick { 1 } else { 3 }, || {
            grow_on_surface(&mesh, &[], &o, None).expect("grows")
        });
        println!(
            "  {:?}: {:.3} s, {} sources, {} nodes, {} left, {} steps",
            mode,
            t,
            v.growth.sources_placed,
            v.network.nodes.len(),
            v.growth.sources_left,
            v.growth.iterations
        );
    }
}
