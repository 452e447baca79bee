//! `coiffure fit IN OUT [--json]`: a hairstyle from another tool placed on the built-in head
//! (`hairstyle::fit`), written in metres in the head frame; prints the transform and the roots'
//! distances to the scalp.

use anyhow::{anyhow, Context, Result};
use clap::Args;
use hairstyle::fit::{fit_file, parse_units, Axis, Distances, FitOptions, FitParams, FitReport};
use hairstyle::formats::write_file;
use std::path::PathBuf;

/// Overrides of the fit (also used by `serve`'s load and scenarios' `[live] hairstyle`).
#[derive(Debug, Args, Clone, Default)]
pub struct FitFlags {
    /// The file's up axis (x, y, z, -x, -y, -z); default: the file's metadata, else detected.
    #[arg(long)]
    pub up: Option<String>,
    /// The direction the face looks in the file (x, y, z, -x, ...); default: detected.
    #[arg(long)]
    pub front: Option<String>,
    /// The file's units: m, cm, mm, in, ft or metres per unit; default: metadata, else from the size.
    #[arg(long)]
    pub units: Option<String>,
    /// Take the file as it is (metres, z up, facing +y, unless --units/--up/--front say otherwise):
    /// no detection, no fit to the scalp, no push-out.
    #[arg(long)]
    pub no_fit: bool,
}

impl FitFlags {
    /// The options, or an error naming the bad flag.
    pub fn options(&self) -> Result<FitOptions> {
        let axis = |s: &Option<String>, flag: &str| s.as_deref().map(Axis::parse).transpose().map_err(|e| anyhow!("--{flag}: {e}"));
        Ok(FitOptions {
            units: self.units.as_deref().map(parse_units).transpose().map_err(|e| anyhow!("--units: {e}"))?,
            up: axis(&self.up, "up")?,
            front: axis(&self.front, "front")?,
            fit: !self.no_fit,
        })
    }
}

/// Arguments of `coiffure fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Input hair file (.hair, .data, .tfx, .usda).
    input: PathBuf,
    /// Output file (metres, head frame); the format follows its extension.
    output: PathBuf,
    #[command(flatten)]
    flags: FitFlags,
    /// Print the report as JSON (one object) instead of text.
    #[arg(long)]
    json: bool,
    /// Follow strands written around each strand rooted on the scalp (`hairstyle::follow`, as the viewer's
    /// load draws them); default 0: the file's strands only.
    #[arg(long, default_value_t = 0)]
    follow_strands: usize,
}

fn distances(d: &Distances) -> serde_json::Value {
    serde_json::json!({ "median": d.median, "p95": d.p95, "max": d.max })
}

/// The report as a JSON value (lengths in m).
pub fn report_json(r: &FitReport) -> serde_json::Value {
    let t = &r.transform;
    let rows: Vec<Vec<f64>> = (0..3).map(|i| (0..3).map(|j| t.rotation[(i, j)]).collect()).collect();
    serde_json::json!({
        "meters_per_unit": r.meters_per_unit,
        "units_source": r.units_source.name(),
        "up": r.up.name(),
        "front": r.front.name(),
        "orientation_source": r.orientation_source.name(),
        "scale": t.scale,
        "rotation": rows,
        "translation": [t.translation.x, t.translation.y, t.translation.z],
        "rooted": r.rooted,
        "root_distance": distances(&r.root_distance),
        "rooted_distance": distances(&r.rooted_distance),
        "loose_distance": distances(&r.loose_distance),
        "pushed_out": r.pushed_out,
        "scores": r.scores.map(|(a, b)| [a, b]),
    })
}

/// The report as text lines.
pub fn report_text(r: &FitReport) -> String {
    let t = &r.transform;
    let m = |x: f64| format!("{:.2} mm", 1e3 * x);
    let mut s = format!(
        "units    {} per file unit ({})\naxes     up {} front {} ({})\nscale    {:.6} m per file unit\nrotation [{:.4} {:.4} {:.4}; {:.4} {:.4} {:.4}; {:.4} {:.4} {:.4}]\ntranslation [{:.5}, {:.5}, {:.5}] m\n",
        hairstyle::fit::units_name(r.meters_per_unit), r.units_source.name(), r.up.name(), r.front.name(), r.orientation_source.name(), t.scale,
        t.rotation[(0, 0)], t.rotation[(0, 1)], t.rotation[(0, 2)], t.rotation[(1, 0)], t.rotation[(1, 1)], t.rotation[(1, 2)], t.rotation[(2, 0)], t.rotation[(2, 1)], t.rotation[(2, 2)],
        t.translation.x, t.translation.y, t.translation.z,
    );
    let line = |d: &Distances| format!("median {}, 95th percentile {}, max {}", m(d.median), m(d.p95), m(d.max));
    s += &format!(
        "roots to the scalp: all {}\n  rooted on the scalp (within {}): {:.1} % of the strands, {}\n  loose: {:.1} %, {}\npushed out of the body: {} points\n",
        line(&r.root_distance), m(FitParams::default().inlier_distance), 100.0 * r.rooted, line(&r.rooted_distance), 100.0 * (1.0 - r.rooted), line(&r.loose_distance), r.pushed_out
    );
    s
}

pub fn run(args: &FitArgs) -> Result<()> {
    let opts = args.flags.options()?;
    let (mut curves, report) = fit_file(&args.input, &opts).with_context(|| format!("cannot fit {}", args.input.display()))?;
    if args.follow_strands > 0 {
        let head = hairstyle::Head::default();
        let scalp = hairstyle::fit::ScalpIndex::new(&head, FitParams::default().scalp_samples);
        let params = hairstyle::follow::FollowParams { per_strand: args.follow_strands, ..Default::default() };
        let more = hairstyle::follow::follow_strands(&curves.strands, &head, &scalp, FitParams::default().inlier_distance, &params);
        curves.strands.extend(more);
        curves.thickness = None;
    }
    if curves.thickness.is_none() {
        // widths from the default hair type (USD `widths`; ignored by formats without thickness)
        let d = strand::HairType::by_name("caucasian").map_or(7e-5, |h| h.major_diameter) as f32;
        curves.thickness = Some(vec![d; curves.num_points()]);
    }
    crate::ensure_parent(&args.output)?;
    write_file(&args.output, &curves).with_context(|| format!("cannot write {}", args.output.display()))?;
    if args.json {
        println!("{}", report_json(&report));
    } else {
        println!("{} -> {}: {} strands", args.input.display(), args.output.display(), curves.strands.len());
        print!("{}", report_text(&report));
    }
    Ok(())
}
