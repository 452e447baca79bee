//! `coiffure convert IN OUT` and `coiffure info FILE`: hair files (.hair, .data, .tfx, .usda) by extension.

use anyhow::{Context, Result};
use clap::Args;
use hairstyle::formats::{info, read_file, write_file};
use std::path::PathBuf;

/// Arguments of `coiffure convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input file (.hair, .data, .tfx or .usda).
    input: PathBuf,
    /// Output file; the format follows its extension.
    output: PathBuf,
}

/// Arguments of `coiffure info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// A hair file (.hair, .data, .tfx or .usda).
    file: PathBuf,
}

pub fn convert(args: &ConvertArgs) -> Result<()> {
    let curves = read_file(&args.input).with_context(|| format!("cannot read {}", args.input.display()))?;
    crate::ensure_parent(&args.output)?;
    write_file(&args.output, &curves).with_context(|| format!("cannot write {}", args.output.display()))?;
    let (s, p, _, _) = info(&curves);
    println!("{} -> {}: {s} strands, {p} points", args.input.display(), args.output.display());
    Ok(())
}

pub fn show_info(args: &InfoArgs) -> Result<()> {
    let curves = read_file(&args.file).with_context(|| format!("cannot read {}", args.file.display()))?;
    let (s, p, lo, hi) = info(&curves);
    println!("file     {}", args.file.display());
    println!("strands  {s}");
    println!("points   {p}");
    println!("bounds   min [{}, {}, {}]  max [{}, {}, {}]  (file units)", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    Ok(())
}
