//! `lamina sl1 check`: an SL1 archive read back and checked (ours or PrusaSlicer's).

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args as ClapArgs, Subcommand};

use lamina::fabricate::sl1::{check, Sl1Check};

#[derive(ClapArgs)]
pub struct Args {
    #[command(subcommand)]
    pub command: Sl1Command,
}

#[derive(Subcommand)]
pub enum Sl1Command {
    /// Check an SL1 archive: config.ini and prusaslicer.ini keys, the layer count and height
    /// against the images, image sizes against the display, islands per layer, resin from the
    /// pixels against usedMaterial. Exit 0 clean, 1 problems, 2 not an SL1.
    Check {
        /// The archive (.sl1)
        archive: PathBuf,
        /// Print the whole check as JSON on stdout
        #[arg(long)]
        json: bool,
    },
}

/// Ok(true) when the archive has no problem.
pub fn run(args: Args) -> Result<bool> {
    match args.command {
        Sl1Command::Check { archive, json } => {
            let c = check(&archive)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&c)?);
            } else {
                print_check(&c);
            }
            Ok(c.problems.is_empty())
        }
    }
}

fn print_check(c: &Sl1Check) {
    outln!(
        "{}: {} layers of {} mm, {} × {} pixels of {:.4} mm; resin {:.4} mL from the images \
         (usedMaterial {:.4} mL); {} islands; {} empty layers",
        c.archive,
        c.layers,
        c.layer_mm,
        c.pixels[0],
        c.pixels[1],
        c.pixel_mm,
        c.volume_ml,
        c.used_ml,
        c.island_count,
        c.empty_layers
    );
    for i in c.islands.iter().take(10) {
        outln!(
            "  island at layer {} (z {:.3} mm): ({:.3}, {:.3}) mm, {:.4} mm², {} pixels",
            i.layer,
            i.z_mm,
            i.x_mm,
            i.y_mm,
            i.area_mm2,
            i.pixels
        );
    }
    if c.island_count > 10 {
        outln!("  … {} more", c.island_count - 10);
    }
    for p in &c.problems {
        outln!("problem: {p}");
    }
}
