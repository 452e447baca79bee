//! `coiffure`: the command line of the Coiffure hair simulator.

mod carried;
mod delivery;
mod demo;
mod device_sim_cmd;
mod files_cmd;
mod fit_cmd;
mod outbox;
mod protocol;
mod run_cmd;
mod serve;
mod strand_cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Coiffure: a visuo-haptic hair simulator (local Super-Helix strands, global lattice layer).
#[derive(Debug, Parser)]
#[command(name = "coiffure", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The visuo-haptic app: serve the browser viewer and the live session (http://127.0.0.1:8080).
    Serve(serve::ServeArgs),
    /// A simulated haptic device and hand streaming a scenario's tool path to `serve --device` (UDP).
    DeviceSim(device_sim_cmd::DeviceSimArgs),
    /// Headless run of the built-in default scene: a few strands hanging from a moving root.
    Demo(demo::DemoArgs),
    /// Simulate or solve the statics of one strand described by a TOML spec file.
    Strand(strand_cmd::StrandArgs),
    /// Run a scenario (TOML: a patch, global tools, or the live session headless): trace and summary.
    Run(run_cmd::RunArgs),
    /// Replay a `coiffure serve --record` file headless into the outputs of a live scenario.
    Replay(run_cmd::ReplayArgs),
    /// Convert a hair file between formats (.hair, .data, .tfx, .usda), chosen by extension.
    Convert(files_cmd::ConvertArgs),
    /// Print a hair file's strand and point counts and bounds.
    Info(files_cmd::InfoArgs),
    /// Place a hairstyle from another tool on the built-in head (units, axes, fit to the scalp) and write it.
    Fit(fit_cmd::FitArgs),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Serve(args) => serve::run(&args),
        Command::DeviceSim(args) => device_sim_cmd::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Strand(args) => strand_cmd::run(&args),
        Command::Run(args) => run_cmd::run(&args),
        Command::Replay(args) => run_cmd::replay(&args),
        Command::Convert(args) => files_cmd::convert(&args),
        Command::Info(args) => files_cmd::show_info(&args),
        Command::Fit(args) => fit_cmd::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Creates the parent folder of `path` if needed.
pub(crate) fn ensure_parent(path: &std::path::Path) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| anyhow::anyhow!("cannot create folder {}: {e}", dir.display()))?;
    }
    Ok(())
}
