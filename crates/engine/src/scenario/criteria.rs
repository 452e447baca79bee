//! Issue 29's combing criteria: the measured anchors a combing law is held to (figures and sources in
//! docs/combing.md, "Anchors now"), each a bound on a figure of comb strokes through tresses run over several
//! tress layouts. One list for the validation suite (`tests/combing_suite.rs`, which asserts them) and the
//! `combing_dt` example (which prints them at each time step of a release build).

/// The straight and wavy presets the criteria name (besides `african`).
pub const STRAIGHT: [&str; 6] = ["H1", "H2", "GA1", "GC3", "asian", "caucasian"];
/// The standard tress mass and the light one, kg (Newman et al. 1973's 4.75 g and 2.75 g tresses).
pub const MASS: f64 = 4.75e-3;
/// The light tress's mass, kg.
pub const LIGHT_MASS: f64 = 2.75e-3;

/// One case's figures over the tress layouts, in the layouts' order: peak and median force of the stroke (N) and
/// its combing curve by fifths of the tress length (mean force by comb position over each fifth, roots first, N:
/// [`super::fifths`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LayoutFigures {
    /// Each layout's peak force, N.
    pub peak: Vec<f64>,
    /// Each layout's median force over the stroke, N.
    pub median: Vec<f64>,
    /// Each layout's fifths, N.
    pub fifths: Vec<[f64; 5]>,
}

impl LayoutFigures {
    /// The layouts' mean fifths, N.
    pub fn mean_fifths(&self) -> [f64; 5] {
        std::array::from_fn(|k| self.fifths.iter().map(|f| f[k]).sum::<f64>() / self.fifths.len() as f64)
    }
}

/// A criterion: what it reads, its value (the layouts' mean; a ratio: the ratio of the means), each layout's own
/// value (a ratio's: of the same layout's two figures) and its closed bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Criterion {
    /// What it reads (its unit, if any, in the name).
    pub what: String,
    /// The layouts' mean (a ratio: the ratio of the means).
    pub value: f64,
    /// Each layout's own value.
    pub layouts: Vec<f64>,
    /// Closed bounds (lowest, highest).
    pub bounds: (f64, f64),
}

impl Criterion {
    /// Whether the value lies within the bounds.
    pub fn met(&self) -> bool {
        (self.bounds.0..=self.bounds.1).contains(&self.value)
    }
}

/// The cases the criteria read, as (hair preset, wetness, tress mass in kg, treatment): every preset dry and wet
/// at [`MASS`], caucasian dry and wet at [`LIGHT_MASS`], and caucasian's treatments.
pub fn cases() -> Vec<(&'static str, f64, f64, &'static str)> {
    let mut c: Vec<(&'static str, f64, f64, &'static str)> = Vec::new();
    for h in STRAIGHT.iter().chain(["african"].iter()) {
        c.push((h, 0.0, MASS, "virgin"));
        c.push((h, 1.0, MASS, "virgin"));
    }
    c.push(("caucasian", 1.0, LIGHT_MASS, "virgin"));
    c.push(("caucasian", 0.0, LIGHT_MASS, "virgin"));
    for (t, w) in [("conditioned", 0.0), ("conditioned", 1.0), ("bleached", 1.0), ("bleached-twice", 1.0)] {
        c.push(("caucasian", w, MASS, t));
    }
    c
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// The index of the largest of `f` (0: roots .. 4: tips).
fn largest(f: &[f64; 5]) -> f64 {
    (0..5).max_by(|&a, &b| f[a].total_cmp(&f[b])).unwrap() as f64
}

/// Issue 29's criteria, from the figures `figures(hair, wetness, mass, treatment)` of each of [`cases`].
pub fn criteria<'a>(figures: impl Fn(&str, f64, f64, &str) -> &'a LayoutFigures) -> Vec<Criterion> {
    let std = |h: &str, w: f64| figures(h, w, MASS, "virgin");
    let mut checks = Vec::new();
    let mut check = |what: String, value: f64, layouts: Vec<f64>, lo: f64, hi: f64| checks.push(Criterion { what, value, layouts, bounds: (lo, hi) });
    let ratio = |a: &[f64], b: &[f64]| (mean(a) / mean(b), a.iter().zip(b).map(|(x, y)| x / y).collect::<Vec<f64>>());
    for h in STRAIGHT {
        let (d, w) = (std(h, 0.0), std(h, 1.0));
        check(format!("{h} dry peak, N"), mean(&d.peak), d.peak.clone(), 0.06, 0.24);
        let (v, l) = ratio(&w.peak, &d.peak);
        check(format!("{h} wet/dry peak"), v, l, 4.0, 10.0);
        let (v, l) = ratio(&d.median, &d.peak);
        check(format!("{h} dry median / peak"), v, l, 0.4, 1.0);
        let (v, l) = ratio(&w.median, &w.peak);
        check(format!("{h} wet median / peak"), v, l, 0.4, 1.0);
        // Curve shape by fifths of the length (the layouts' mean curve): dry, the largest fifth is one of the two at
        // the tips; wet, the force rises from the roots (a later fifth above the first) and the largest fifth is not
        // the tips'.
        check(format!("{h} dry: largest fifth (0 roots .. 4 tips)"), largest(&d.mean_fifths()), d.fifths.iter().map(largest).collect(), 3.0, 4.0);
        check(format!("{h} wet: largest fifth (0 roots .. 4 tips)"), largest(&w.mean_fifths()), w.fifths.iter().map(largest).collect(), 0.0, 3.0);
        let rise = |f: &[f64; 5]| f[1..].iter().copied().fold(0.0, f64::max) / f[0];
        check(format!("{h} wet: largest later fifth / first"), rise(&w.mean_fifths()), w.fifths.iter().map(rise).collect(), 1.0, f64::INFINITY);
    }
    let light = figures("caucasian", 1.0, LIGHT_MASS, "virgin");
    check("caucasian 2.75 g wet peak, N".into(), mean(&light.peak), light.peak.clone(), 0.25, 1.0);
    for w in [0.0, 1.0] {
        let (a, b) = (figures("caucasian", w, LIGHT_MASS, "virgin"), std("caucasian", w));
        let (v, l) = ratio(&a.peak, &b.peak);
        check(format!("caucasian {} peak per gram, 2.75 g / 4.75 g", if w > 0.0 { "wet" } else { "dry" }), v * 4.75 / 2.75, l.iter().map(|x| x * 4.75 / 2.75).collect(), 0.65, 1.35);
    }
    let (v, l) = ratio(&std("african", 0.0).peak, &std("H1", 0.0).peak);
    check("african dry peak / H1 dry peak".into(), v, l, 2.0, f64::INFINITY);
    let (v, l) = ratio(&std("african", 1.0).peak, &std("african", 0.0).peak);
    check("african wet peak / dry peak".into(), v, l, 0.0, 1.0);
    for (t, w, what, lo, hi) in [
        ("conditioned", 0.0, "caucasian conditioned / virgin, dry", 0.6, 0.95),
        ("conditioned", 1.0, "caucasian conditioned / virgin, wet", 0.3, 0.6),
        ("bleached", 1.0, "caucasian bleached / virgin, wet", 2.0, 4.0),
        ("bleached-twice", 1.0, "caucasian bleached twice / virgin, wet", 3.0, 6.0),
    ] {
        let (v, l) = ratio(&figures("caucasian", w, MASS, t).peak, &std("caucasian", w).peak);
        check(what.into(), v, l, lo, hi);
    }
    checks
}
