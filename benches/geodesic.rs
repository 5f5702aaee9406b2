//! Geodesic veins (Bachman) with 2,000 sources on a 100,000-vertex torus: our incremental
//! labelling against the recompute-everything baseline (a fresh multi-source Dijkstra from the
//! whole tree every iteration, as the blog's method does), in the same run, and a check that
//! both grow the same tree. Then surface venation with about 20,000 sources on a
//! 50,000-triangle torus. Both meshes go to `target/bench-data` for the whole-process runs in
//! `scripts/bench geodesic`. `harness = false`: `cargo bench --bench geodesic [-- --quick]`.

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

/// The baseline: every iteration forgets the labels and runs Dijkstra from every tree vertex.
struct Recompute {
    tree: Vec<u32>,
}

impl Relabel for Recompute {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], added: &[u32], labels: &mut Labels) {
        self.tree.extend_from_slice(added);
        labels.clear();
        labels.relabel(g, in_tree, &self.tree);
    }
}

/// Bachman's step 1 as written: every iteration, a Dijkstra from each live source until it
/// reaches the tree; only the sources get labels.
struct PerSource {
    sources: Vec<u32>,
}

impl Relabel for PerSource {
    fn update(&mut self, g: &MeshGraph, in_tree: &[bool], _added: &[u32], labels: &mut Labels) {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let n = g.vertices();
        let mut dist = vec![f64::INFINITY; n];
        let mut pred = vec![u32::MAX; n];
        let mut touched: Vec<u32> = Vec::new();
        for &s in &self.sources {
            if in_tree[s as usize] {
                continue;
            }
            for &v in &touched {
                dist[v as usize] = f64::INFINITY;
                pred[v as usize] = u32::MAX;
            }
            touched.clear();
            let mut heap = BinaryHeap::new();
            dist[s as usize] = 0.0;
            touched.push(s);
            heap.push(Reverse((Key(0.0), s)));
            while let Some(Reverse((Key(d), x))) = heap.pop() {
                if d > dist[x as usize] {
                    continue;
                }
                if in_tree[x as usize] {
                    // The path's last vertex off the tree is the one we came from.
                    labels.site[s as usize] = x;
                    labels.first[s as usize] = pred[x as usize];
                    labels.dist[s as usize] = d;
                    break;
                }
                for (y, len) in g.neighbours(x) {
                    let nd = d + len;
                    if nd < dist[y as usize] {
                        dist[y as usize] = nd;
                        pred[y as usize] = x;
                        touched.push(y);
                        heap.push(Reverse((Key(nd), y)));
                    }
                }
            }
        }
        labels.changed = touched.len();
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
    let mut sources: Vec<u32> = (0..2000)
        .map(|_| rng.random_range(0..mesh.positions.len() as u32))
        .collect();
    sources.sort_unstable();
    sources.dedup();
    let root = 0;
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

    // Bachman's own step (a shortest path from each source, every iteration) cannot finish on
    // the large mesh in reasonable time; compare all three on a 10,000-vertex torus.
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
    let birth = surface::birth_for_count(&mesh, 20_000, None);
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
        seed: 1,
    };
    println!(
        "surface venation: torus of {} triangles, about 20,000 sources",
        mesh.triangles.len()
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
            grow_on_surface(&mesh, &[], &o).expect("grows")
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
