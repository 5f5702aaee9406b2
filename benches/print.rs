//! The print path in process: `solid` on a grown leaf (veins only and with lamina), and slicing
//! the solid for the DMP-SL printer with the images encoded but not written. The side-by-side
//! runs against manifold3d and PrusaSlicer on a 12,700-node leaf are whole-process, in
//! `scripts/bench print`. `harness = false`: `cargo bench --bench print`.

use lamina::fabricate::slice::{arrange, slice, Model, Printer};
use lamina::fabricate::solid::{solid, SolidOptions};
use lamina::grow::leaf::{grow_leaf, LeafOptions};
use lamina::grow::outline::{Outline, Shape};

#[path = "common/timing.rs"]
mod timing;
use timing::best_of;

fn main() {
    let outline = Outline::shape(Shape::Ovate);
    let opts = LeafOptions {
        birth: 4.0,
        tip_radius: 0.4,
        ..Default::default()
    };
    let leaf = grow_leaf(&outline, &[outline.default_root()], &opts, None).expect("leaf");
    let nodes = leaf.network.nodes.len();
    for (label, lamina, cell) in [
        ("veins", None, 0.035),
        ("veins + lamina 0.3 mm", Some(0.3), 0.035),
    ] {
        let o = SolidOptions {
            cell,
            lamina,
            fit: Some(30.0),
            ..Default::default()
        };
        let (secs, made) = best_of(3, || {
            solid(&leaf.network, &o, &lamina::stage::Quiet).expect("solid")
        });
        println!(
            "solid, {nodes}-node leaf at 30 mm, {label}, cell {cell} mm: {secs:.3} s best of 3, \
             {} triangles",
            made.report.triangles
        );
        if lamina.is_some() {
            let printer = Printer::default();
            let models = [Model {
                path: "leaf.stl".into(),
                mesh: made.mesh,
            }];
            let placed = arrange(&models, &printer, 1, 2.0, false).expect("fits");
            let (secs, layers) = best_of(3, || {
                slice(&models, &placed, &printer, |l| {
                    std::hint::black_box(l.png.len());
                    Ok::<(), ()>(())
                })
                .expect("slices")
            });
            println!(
                "slice that solid, 1920 x 1080 at 35 um, 50 um layers: {secs:.3} s best of 3, \
                 {layers} layers ({:.2} ms a layer)",
                secs * 1000.0 / layers as f64
            );
        }
    }
}
