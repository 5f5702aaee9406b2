//! Growth forms in the demo (Hart): the paper's Figure 8 program as printed, grown to 10,000
//! cells with its textures, and two smaller programs: bud splitting (his Figure 4) and holes
//! (his Figure 9).

use std::path::Path;

use anyhow::{Context, Result};
use clap::Parser;

use super::Entry;
use lamina::files::write_atomic;

const PROGRAMS: [(&str, &str); 3] = [
    (
        "figure8.bud",
        include_str!("../../../fixtures/buds/figure8.bud"),
    ),
    (
        "split.bud",
        include_str!("../../../fixtures/buds/split.bud"),
    ),
    (
        "holes.bud",
        include_str!("../../../fixtures/buds/holes.bud"),
    ),
];

#[derive(Parser)]
struct Buds {
    #[command(flatten)]
    args: crate::cli::buds::Args,
}

pub fn buds(out: &Path, size: u32) -> Result<Entry> {
    let dir = out.join("buds");
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("{}: cannot create folder", dir.display()))?;
    let p = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let px = size.to_string();
    let mut reports = Vec::new();
    for ((name, text), (cells, seed)) in
        PROGRAMS
            .iter()
            .zip([("10000", "1"), ("3000", "1"), ("3000", "2")])
    {
        write_atomic(&dir.join(name), |w| {
            std::io::Write::write_all(w, text.as_bytes())
        })?;
        let stem = name.trim_end_matches(".bud");
        let cmd = Buds::try_parse_from([
            "buds",
            &p(name),
            "--cells",
            cells,
            "--seed",
            seed,
            "-o",
            &p(&format!("{stem}.stl")),
            "--obj",
            &p(&format!("{stem}.obj")),
            "--png",
            &p(&format!("{stem}.png")),
            "--report",
            &p(&format!("{stem}.report.json")),
            "--size",
            &px,
        ])
        .context("the demo's buds arguments")?;
        reports.push(crate::cli::buds::execute(&cmd.args)?);
    }
    let g = |k: usize| &reports[k]["growth"];
    let by_type = |k: usize| {
        g(k)["buds_by_type"]
            .as_array()
            .map(|a| {
                a.iter()
                    .map(|t| format!("{} {}", t[1], t[0].as_str().unwrap_or("?")))
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .unwrap_or_default()
    };
    let mut outputs = Vec::new();
    for (name, _) in PROGRAMS {
        let stem = name.trim_end_matches(".bud");
        for ext in ["bud", "stl", "obj", "png", "report.json"] {
            outputs.push(format!("buds/{stem}.{ext}"));
        }
    }
    Ok(Entry {
        name: "growth forms (bud programs)".into(),
        about: "Hart's \"Growth Forms\": a triangulated cell surface grown from a tetrahedron by \
                buds running small programs. The paper's Figure 8 program (Base / Stem / Pod, \
                parsed as printed in three tab-separated columns) grown by `lamina buds` to \
                10,000 cells: a yellow blob base, a green bumpy stem that branches, red spiky \
                pods of larger cells; textures made geometry in the STL, colours in the OBJ. \
                Beside it: a bud that splits three times (Figure 4) and a blob with two holes \
                grown through it (Figure 9)."
            .into(),
        outputs,
        preview: "buds/figure8.png".into(),
        facts: format!(
            "Figure 8: {} cells, buds made: {}; {} froze on collision, {} live at the cap; \
             genus {}; {} triangles with textures, {} self-intersections. Split: {} buds. \
             Holes: genus {} from {} holes ({} refused).",
            g(0)["cells"],
            by_type(0),
            g(0)["buds_frozen"],
            g(0)["buds_live"],
            g(0)["genus"],
            reports[0]["mesh"]["triangles"],
            reports[0]["skin"]["self_intersections"],
            g(1)["buds_made"],
            g(2)["genus"],
            g(2)["holes"],
            g(2)["holes_refused"],
        ),
    })
}
