//! What the combing tests (`tress.rs`, `combing_suite.rs`) share: the anchor measure and a two-thread runner.
//!
//! The anchor measure (docs/combing.md, "Which figure is anchored"): a tress's combing force is the **mean over
//! [`LAYOUTS`] tress layouts** (`[patch] seed`: where the wisps are rooted and how they are tilted) of each
//! stroke's figure (peak, median, fifths), as the measured figures are means over repeated combings (Newman
//! 1973: 12 +- 3 gf, repeats spread up to 20 %). One layout's peak is one trajectory's largest step, which moves
//! by up to 60 % with the time step or the round-off of a path's end; the layout mean moves by at most about 10 %
//! from 1 to 0.5 ms (bench/RESULTS.md), within about twice its standard error.

#![allow(dead_code)]

/// The tress layouts (`[patch] seed`) the anchor figures are averaged over.
pub const LAYOUTS: [u64; 6] = [1, 2, 3, 4, 5, 6];

/// A figure over the layouts: mean, sample standard deviation, smallest and largest.
#[derive(Debug, Clone, Copy)]
pub struct OverLayouts {
    pub mean: f64,
    pub sd: f64,
    pub min: f64,
    pub max: f64,
}

impl OverLayouts {
    /// The figure over `values` (one per layout; at least two).
    pub fn of(values: &[f64]) -> Self {
        assert!(values.len() >= 2, "at least two layouts");
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self { mean, sd, min, max }
    }

    /// Standard error of the mean relative to it (dimensionless).
    pub fn rel_se(&self, layouts: usize) -> f64 {
        self.sd / self.mean / (layouts as f64).sqrt()
    }
}

impl std::fmt::Display for OverLayouts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.3} (sd {:.3}, {:.3}-{:.3})", self.mean, self.sd, self.min, self.max)
    }
}

/// `f` over `items` on two threads (the CI machine's cores), results in the items' order.
pub fn par_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results = std::sync::Mutex::new((0..items.len()).map(|_| None).collect::<Vec<Option<R>>>());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let r = f(item);
                results.lock().unwrap()[i] = Some(r);
            });
        }
    });
    results.into_inner().unwrap().into_iter().map(|r| r.unwrap()).collect()
}
