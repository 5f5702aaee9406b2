//! The readers a fuzzer drives, by name: each reads a file the way its command does and then
//! checks what it read (a network validated, a mesh's topology counted, a grammar built), so a
//! mutated file goes as deep as a real one. Used by `examples/fuzz.rs` (the mutation harness)
//! and by `tests/suite/fuzz_replay.rs` (every seed and every input the harness kept, replayed).
//!
//! Seeds are the repository's fixtures (`fixtures/…`) and the small corpus in `fuzz/corpus/`.

use std::path::Path;

/// One reader under test.
pub struct Target {
    pub name: &'static str,
    /// Extension of the file it reads (it picks the format).
    pub ext: &'static str,
    /// Seed files, relative to the repository root; folders take every file in them.
    pub seeds: &'static [&'static str],
    pub run: fn(&Path) -> Result<(), String>,
}

fn network(path: &Path) -> Result<(), String> {
    network_with(path, &Default::default())
}

/// A DXF network with its HATCH boundaries read too (the flag that reaches the most code).
fn dxf_network(path: &Path) -> Result<(), String> {
    let opts = crate::network::io::ReadOptions {
        hatch_boundaries: true,
        ..Default::default()
    };
    network_with(path, &opts)
}

fn network_with(path: &Path, opts: &crate::network::io::ReadOptions) -> Result<(), String> {
    let imported = crate::network::io::read_network(path, opts).map_err(|e| e.to_string())?;
    let _ = imported.network.validate();
    let tol = imported.point_tolerance();
    let _ = crate::network::arrangement::defects(&imported.network, tol, 1000);
    Ok(())
}

fn mesh(path: &Path) -> Result<(), String> {
    let mut m = crate::mesh::io::read_mesh(path).map_err(|e| e.to_string())?;
    let _ = m.check_manifold();
    m.drop_degenerate();
    let tol = 1e-6 * m.bbox().diagonal();
    let _ = m.weld(tol);
    Ok(())
}

fn axes(path: &Path) -> Result<(), String> {
    crate::rationalize::axes::read_axes(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn plates(path: &Path) -> Result<(), String> {
    crate::fabricate::plates_file::read_plates(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn panels(path: &Path) -> Result<(), String> {
    let read = crate::rationalize::audit::read_panels(path).map_err(|e| e.to_string())?;
    let _ = crate::rationalize::audit::audit(&read.panels);
    Ok(())
}

fn tolerance_rules(path: &Path) -> Result<(), String> {
    crate::rationalize::tolerance::Rules::read(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn sl1(path: &Path) -> Result<(), String> {
    crate::fabricate::sl1::check(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn outline(path: &Path) -> Result<(), String> {
    crate::grow::outline_file::read_outline(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn density(path: &Path) -> Result<(), String> {
    crate::grow::density::DensityMap::read(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn buds(path: &Path) -> Result<(), String> {
    crate::grow::buds::program::read_program(path)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn grammar(path: &Path) -> Result<(), String> {
    let file = crate::grow::lsystem::read_grammar_file(path).map_err(|e| e.to_string())?;
    let rules = file.rules.into_iter().map(|(r, _)| r).collect();
    crate::grow::lsystem::Grammar::new(file.axiom.as_deref().unwrap_or(""), rules)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn printer(path: &Path) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    // The profile is read by the CLI, which prints serde's message through `printable`.
    let p: crate::fabricate::slice::Printer = serde_json::from_str(&text)
        .map_err(|e| crate::text::printable(&e.to_string()).into_owned())?;
    p.check().map_err(|e| e.to_string())
}

/// Every reader, in a fixed order.
pub const TARGETS: &[Target] = &[
    Target {
        name: "dxf",
        ext: "dxf",
        seeds: &[
            "fixtures/networks/ezdxf_veins.dxf",
            "fixtures/networks/ezdxf_curves_in.dxf",
            "fixtures/networks/ezdxf_crossings.dxf",
            "fixtures/networks/ezdxf_round_holes.dxf",
            "fixtures/networks/ezdxf_overlaps.dxf",
            "fixtures/networks/ezdxf_unread_entities.dxf",
            "fixtures/networks/ezdxf_hatches.dxf",
            "fixtures/networks/ezdxf_hatch_curves.dxf",
            "fixtures/outlines/oak.dxf",
            "fixtures/fuzz/P7_dxf_julian_date/in.dxf",
        ],
        run: dxf_network,
    },
    Target {
        name: "obj_network",
        ext: "obj",
        seeds: &[
            "fixtures/networks/rhino_curves.obj",
            "fixtures/networks/blender_loose_edges.obj",
        ],
        run: network,
    },
    Target {
        name: "obj_mesh",
        ext: "obj",
        seeds: &[
            "fixtures/surfaces/rhino_box.obj",
            "fixtures/surfaces/colored_patch.obj",
        ],
        run: mesh,
    },
    Target {
        name: "stl_binary",
        ext: "stl",
        seeds: &["fixtures/surfaces/openscad_part.stl"],
        run: mesh,
    },
    Target {
        name: "stl_ascii",
        ext: "stl",
        seeds: &[
            "fixtures/surfaces/two_bodies.stl",
            "fixtures/surfaces/cad_jitter.stl",
        ],
        run: mesh,
    },
    Target {
        name: "json_network",
        ext: "json",
        seeds: &["fixtures/networks/small_loop.json", "fuzz/corpus/network"],
        run: network,
    },
    Target {
        name: "axes",
        ext: "json",
        seeds: &["fuzz/corpus/axes"],
        run: axes,
    },
    Target {
        name: "plates",
        ext: "json",
        seeds: &["fuzz/corpus/plates"],
        run: plates,
    },
    Target {
        name: "panels_dxf",
        ext: "dxf",
        seeds: &[
            "fixtures/panels/ezdxf_panels.dxf",
            "fixtures/panels/ezdxf_polyface_block.dxf",
        ],
        run: panels,
    },
    Target {
        name: "panels_obj",
        ext: "obj",
        seeds: &["fixtures/panels/rhino_ngons.obj"],
        run: panels,
    },
    Target {
        name: "tolerance_rules",
        ext: "json",
        seeds: &["fixtures/panels/glass_rules.json"],
        run: tolerance_rules,
    },
    Target {
        name: "sl1",
        ext: "sl1",
        seeds: &["fixtures/print/prusaslicer_bridge.sl1"],
        run: sl1,
    },
    Target {
        name: "svg_outline",
        ext: "svg",
        seeds: &[
            "fixtures/outlines/maple.svg",
            "fixtures/fuzz/P1_outline_translate/in.svg",
        ],
        run: outline,
    },
    Target {
        name: "png_density",
        ext: "png",
        seeds: &["fuzz/corpus/png"],
        run: density,
    },
    Target {
        name: "bud_program",
        ext: "bud",
        seeds: &["fixtures/buds"],
        run: buds,
    },
    Target {
        name: "grammar_text",
        ext: "txt",
        seeds: &["fuzz/corpus/grammar_text"],
        run: grammar,
    },
    Target {
        name: "grammar_json",
        ext: "json",
        seeds: &["fuzz/corpus/grammar_json"],
        run: grammar,
    },
    Target {
        name: "printer",
        ext: "json",
        seeds: &["fuzz/corpus/printer"],
        run: printer,
    },
];

/// The seed files of a target and the inputs the harness kept for it (`fuzz/crashes/NAME/`),
/// under `root`, sorted.
pub fn seed_files(root: &Path, target: &Target) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let kept = format!("fuzz/crashes/{}", target.name);
    for rel in target
        .seeds
        .iter()
        .copied()
        .chain(std::iter::once(kept.as_str()))
    {
        let p = root.join(rel);
        if p.is_dir() {
            if let Ok(dir) = std::fs::read_dir(&p) {
                out.extend(
                    dir.filter_map(|e| e.ok())
                        .map(|e| e.path())
                        .filter(|p| p.is_file()),
                );
            }
        } else if p.is_file() {
            out.push(p);
        }
    }
    out.sort();
    out
}
