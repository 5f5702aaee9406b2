//! The `lamina` command: parse, call the library, print. No algorithms here.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    // The DXF parser's and the PNG decoders' panics on values they cannot take are caught and
    // reported as the file's error; print nothing for them here. Every other panic is a bug and prints as usual.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let quiet = [
            lamina::network::io::dxf::PARSER_THREAD,
            lamina::files::DECODER_THREAD,
        ];
        if !quiet
            .iter()
            .any(|q| std::thread::current().name() == Some(q))
        {
            default_hook(info);
        }
    }));
    let cli = cli::Cli::parse();
    match cli::dispatch(cli.command) {
        Ok(true) => ExitCode::SUCCESS,
        // Outputs are written, but the tolerance was not met: 1, for scripts.
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("lamina: error: {}", cli::error_message(&e));
            // Bad input and failed writes alike: 2, as clap uses for bad arguments.
            ExitCode::from(2)
        }
    }
}
