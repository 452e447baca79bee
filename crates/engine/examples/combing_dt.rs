//! Time-step convergence of the combing force's statistics (issue 29): runs the comb-h1 tress (24 wisps, 4.75 g,
//! 20 cm, combed at 0.25 m/s, as `combing_suite`'s standard case) of every preset, dry and wet, at several time
//! steps, and prints for each the stroke's force statistics (peak, 99th, 95th and 90th percentiles, median, mean,
//! over the steps from the first to the last contact) and their change from one step size to the next; and
//! the combing curve by fifths of the tress length (the layouts' mean force by comb position over each fifth, as
//! `combing_suite` reads issue 29's curve-shape criteria: the largest fifth, the largest later fifth over the first).
//! Each figure is the mean over `seeds` tress layouts (`[patch] seed`: the wisps' roots and tilts), beside the
//! layouts' spread (sample standard deviation over the mean), so that a change with the step size can be told
//! from the sensitivity of one layout's trajectory.
//! Run from the repository root:
//! `cargo run --release -p coiffure-engine --example combing_dt [-- dt=0.001,0.0005,0.00025] [seeds=1,2,3,4] [hair=H1,african] [treatments] [light] [threads=2]`
//! `treatments` adds caucasian conditioned (dry and wet), bleached and bleached twice (wet); `light` the 2.75 g
//! caucasian tress, dry and wet. With every preset, `treatments` and `light`, the last table is issue 29's 51
//! criteria as `combing_suite::the_combing_law_meets_the_measured_anchors` reads them (at each time step), and
//! the count met: the suite's table from a release build, for trying a change of the law.

use engine::scenario::criteria::{self, LayoutFigures, LIGHT_MASS as LIGHT, MASS};
use engine::scenario::{run, ScenarioFile, ScenarioSummary};

/// The tress's roots' height and its length, m (the comb's position along it is `ROOT_Z - z`).
const ROOT_Z: f64 = 0.3;
const LENGTH: f64 = 0.2;

/// One tress and stroke (as `crates/engine/tests/combing_suite.rs`'s `Case::toml`).
fn toml(hair: &str, wetness: f64, treatment: &str, mass: f64, dt: f64, seed: u64) -> String {
    let (length, speed) = (LENGTH, 0.25);
    let (z0, z1) = (0.29, ROOT_Z - length - 0.02);
    let t1 = (z0 - z1) / speed;
    format!(
        r#"
        name = "dt"
        dt = {dt}
        settle = 0.5
        [patch]
        hair_type = "{hair}"
        strands = 24
        length = {length}
        segments = 12
        root = [0.0, 0.0, {ROOT_Z}]
        extent = [0.012, 0.004]
        tilt = 0.05
        seed = {seed}
        tress_mass = {mass}
        wetness = {wetness}
        treatment = "{treatment}"
        [tool]
        shape = "comb"
        path = [
          {{ t = 0.0, position = [0.0004, -0.012, {z0}], rotation = [1.5707963, 0.0, 0.0] }},
          {{ t = {t1}, position = [0.0004, -0.012, {z1}], rotation = [1.5707963, 0.0, 0.0] }},
        ]
        "#
    )
}

/// Statistics of the force magnitude over the stroke (first to last contact), N: peak, p99, p95, p90, median, mean;
/// the clamped strand-steps; and the combing curve by fifths of the tress length (mean force by comb position over
/// each fifth, roots first, N: `engine::scenario::fifths`, as `combing_suite` reads it).
fn stats(hair: &str, wetness: f64, treatment: &str, mass: f64, dt: f64, seed: u64) -> ([f64; 6], u64, [f64; 5]) {
    let out = run(&ScenarioFile::from_toml(&toml(hair, wetness, treatment, mass, dt, seed)).unwrap()).unwrap();
    let clamped = match &out.summary {
        ScenarioSummary::Patch(s) => s.strand_clamped_steps,
        _ => unreachable!(),
    };
    let f = &out.force;
    let position: Vec<f64> = f.tool_z.iter().map(|z| ROOT_Z - z).collect();
    let magnitude: Vec<f64> = (0..f.len()).map(|i| f.force(i).norm()).collect();
    let fifths = engine::scenario::fifths(&position, &magnitude, LENGTH).mean_force_n;
    let first = f.contacts.iter().position(|&c| c > 0).unwrap();
    let last = f.contacts.iter().rposition(|&c| c > 0).unwrap();
    let mut v: Vec<f64> = (first..=last).map(|i| f.force(i).norm()).collect();
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    v.sort_by(f64::total_cmp);
    let rank = |q: f64| v[((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    ([v[v.len() - 1], rank(0.99), rank(0.95), rank(0.9), rank(0.5), mean], clamped, fifths)
}

/// Mean and sample standard deviation of `x`.
fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = if x.len() > 1 { x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    (m, v.sqrt())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let get = |k: &str| args.iter().find_map(|a| a.strip_prefix(&format!("{k}=")).map(str::to_string));
    let list = |k: &str, d: &str| -> Vec<String> { get(k).unwrap_or(d.into()).split(',').map(String::from).collect() };
    let dts: Vec<f64> = list("dt", "0.001,0.0005,0.00025").iter().map(|s| s.parse().unwrap()).collect();
    let seeds: Vec<u64> = list("seeds", "1").iter().map(|s| s.parse().unwrap()).collect();
    let hairs = list("hair", "H1,H2,GA1,GC3,asian,caucasian,african");
    let threads: usize = get("threads").map(|s| s.parse().unwrap()).unwrap_or(2);
    let mut cases: Vec<(String, f64, &str, f64)> = Vec::new();
    for h in &hairs {
        cases.push((h.clone(), 0.0, "virgin", MASS));
        cases.push((h.clone(), 1.0, "virgin", MASS));
    }
    if args.iter().any(|a| a == "treatments") {
        for (t, w) in [("conditioned", 0.0), ("conditioned", 1.0), ("bleached", 1.0), ("bleached-twice", 1.0)] {
            cases.push(("caucasian".into(), w, t, MASS));
        }
    }
    if args.iter().any(|a| a == "light") {
        for w in [0.0, 1.0] {
            cases.push(("caucasian".into(), w, "virgin", LIGHT));
        }
    }
    let label = |c: usize| {
        let (h, w, t, m) = &cases[c];
        let grams = if *m == MASS { String::new() } else { format!(" {} g", m * 1e3) };
        format!("{h} {} {t}{grams}", if *w > 0.0 { "wet" } else { "dry" })
    };
    let (nc, nd, ns) = (cases.len(), dts.len(), seeds.len());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new(vec![None; nc * nd * ns]);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let j = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if j >= nc * nd * ns {
                    break;
                }
                let (c, d, k) = (j / (nd * ns), (j / ns) % nd, j % ns);
                let (h, w, t, m) = &cases[c];
                let r = stats(h, *w, t, *m, dts[d], seeds[k]);
                eprintln!("{} dt {} seed {}: {:?}", label(c), dts[d], seeds[k], r);
                results.lock().unwrap()[j] = Some(r);
            });
        }
    });
    let results: Vec<([f64; 6], u64, [f64; 5])> = results.into_inner().unwrap().into_iter().map(Option::unwrap).collect();
    let at = |c: usize, d: usize, k: usize| results[(c * nd + d) * ns + k];
    // The combing curve: the layouts' mean force by fifth of the length (roots to tips), the largest fifth, and the
    // largest later fifth over the first (issue 29's curve-shape criteria: dry, largest at 3 or 4; wet, a later one
    // above the first and the largest not 4).
    println!("| case | dt (ms) | mean fifths, roots to tips (N) | largest | largest later / first | layouts' largest |");
    println!("|---|---|---|---|---|---|");
    for c in 0..nc {
        for (d, dt) in dts.iter().enumerate() {
            let f: [f64; 5] = std::array::from_fn(|q| (0..ns).map(|k| at(c, d, k).2[q]).sum::<f64>() / ns as f64);
            let largest = |f: &[f64; 5]| (0..5).max_by(|&a, &b| f[a].total_cmp(&f[b])).unwrap();
            let rise = f[1..].iter().copied().fold(0.0, f64::max) / f[0];
            let each: Vec<usize> = (0..ns).map(|k| largest(&at(c, d, k).2)).collect();
            println!("| {} | {} | {} | {} | {rise:.3} | {each:?} |", label(c), dt * 1e3, f.map(|x| format!("{x:.4}")).join(" / "), largest(&f));
        }
    }
    println!();
    // Mean over the layouts and spread (sd / mean) of statistic `q` for case c at step d.
    let ms = |c: usize, d: usize, q: usize| {
        let (m, sd) = mean_sd(&(0..ns).map(|k| at(c, d, k).0[q]).collect::<Vec<_>>());
        (m, sd / m)
    };
    let names = ["peak", "p99", "p95", "p90", "median", "mean"];
    println!("seeds (tress layouts): {seeds:?}; each figure: mean over the layouts, N (spread sd/mean in brackets)");
    println!("| case | dt (ms) | {} | clamped strand-steps (all layouts) |", names.join(" | "));
    println!("|---|---|{}---|", "---|".repeat(names.len()));
    for c in 0..nc {
        for (d, dt) in dts.iter().enumerate() {
            let clamped: u64 = (0..ns).map(|k| at(c, d, k).1).sum();
            let cells: Vec<String> = (0..names.len()).map(|q| {
                let (m, rel) = ms(c, d, q);
                format!("{m:.4} ({:.0} %)", 100.0 * rel)
            }).collect();
            println!("| {} | {} | {} | {clamped} |", label(c), dt * 1e3, cells.join(" | "));
        }
    }
    // Change of each statistic's layout mean from one step size to the next (relative to the finer), the worst
    // case, and the layouts' spread of the mean (sd / mean / sqrt(layouts)) in that case at the finer step.
    for d in 1..nd {
        println!("\nchange of the layout mean from dt {} to {} ms (|a - b| / b): worst case, median over the cases; standard error of the finer mean there", dts[d - 1] * 1e3, dts[d] * 1e3);
        for (q, name) in names.iter().enumerate() {
            let mut ch: Vec<(f64, usize)> = (0..nc).map(|c| ((ms(c, d - 1, q).0 - ms(c, d, q).0).abs() / ms(c, d, q).0, c)).collect();
            ch.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (worst, c) = ch[nc - 1];
            println!("  {name}: worst {:.1} % ({}; standard error {:.1} %), median {:.1} %", 100.0 * worst, label(c), 100.0 * ms(c, d, q).1 / (ns as f64).sqrt(), 100.0 * ch[nc / 2].0);
        }
    }
    // Wet/dry ratios of each statistic's layout mean, per hair and step size.
    println!("\n| hair | dt (ms) | wet/dry {} |", names.join(" | wet/dry "));
    println!("|---|---|{}", "---|".repeat(names.len()));
    for h in &hairs {
        let find = |w: f64| cases.iter().position(|(hh, ww, t, m)| hh == h && *ww == w && *t == "virgin" && *m == MASS).unwrap();
        for (d, dt) in dts.iter().enumerate() {
            let cells: Vec<String> = (0..names.len()).map(|q| format!("{:.2}", ms(find(1.0), d, q).0 / ms(find(0.0), d, q).0)).collect();
            println!("| {h} | {} | {} |", dt * 1e3, cells.join(" | "));
        }
    }
    // Issue 29's criteria (engine::scenario::criteria, which combing_suite asserts), when every case they need was run.
    let find = |h: &str, w: f64, t: &str, m: f64| cases.iter().position(|(hh, ww, tt, mm)| hh == h && *ww == w && *tt == t && *mm == m);
    if !criteria::cases().iter().all(|&(h, w, m, t)| find(h, w, t, m).is_some()) {
        return;
    }
    for (d, dt) in dts.iter().enumerate() {
        // Each case's figures over the layouts at this step size (peak: statistic 0, median: statistic 4).
        let figures: Vec<LayoutFigures> = (0..nc).map(|c| LayoutFigures { peak: (0..ns).map(|k| at(c, d, k).0[0]).collect(), median: (0..ns).map(|k| at(c, d, k).0[4]).collect(), fifths: (0..ns).map(|k| at(c, d, k).2).collect() }).collect();
        let checks = criteria::criteria(|h, w, m, t| &figures[find(h, w, t, m).expect("every case was run")]);
        println!("\nissue 29's criteria at dt {} ms (layouts' means; a ratio of the means)", dt * 1e3);
        println!("| criterion | measured | bounds | met |");
        println!("|---|---|---|---|");
        for c in &checks {
            println!("| {} | {:.3} | [{}, {}] | {} |", c.what, c.value, c.bounds.0, c.bounds.1, if c.met() { "yes" } else { "**no**" });
        }
        println!("{} of {} criteria met", checks.iter().filter(|c| c.met()).count(), checks.len());
        // tests/tress.rs's H2 / GA1 dry comparison on the shipped tresses (comb-h2, comb-ga1).
        let peak = |h: &str| figures[find(h, 0.0, "virgin", MASS).unwrap()].peak.iter().sum::<f64>() / ns as f64;
        println!("H2 / GA1 dry peak: {:.4} / {:.4} N", peak("H2"), peak("GA1"));
    }
}
