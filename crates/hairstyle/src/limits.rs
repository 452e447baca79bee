//! Bounds on a loaded hairstyle file (issue 16).

use crate::formats::HairCurves;

/// Bounds on a loaded hairstyle (issue 16), checked before anything is built, so that a malformed or hostile
/// file cannot make the server parse, fit or build without limit. `engine::scene::SceneOptions::load` (the live LOAD and `Scene::from_curves`); [`crate::fit::read_and_fit`]
/// checks the size before reading and the counts before fitting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadLimits {
    /// Largest file, bytes. Default 64 MiB (also the WebSocket message limit; the built-in 100,000-strand
    /// hairstyle saves to 14 MB as `.hair`, 33 MB as `.usda`).
    pub max_file_bytes: usize,
    /// Most strands. Default 200,000 (twice the built-in hairstyle; each becomes a render strand of the SCENE).
    pub max_strands: usize,
    /// Most points over all strands, as read (before resampling). Default 10,000,000.
    pub max_points: usize,
    /// Lower corner of the box around the head every point must lie in, head frame (x right, y towards the
    /// face, z up, origin at the head's centre), m. Default (-0.55, -0.55, -0.85): hair to the waist.
    pub box_min: [f64; 3],
    /// Upper corner of that box, m. Default (0.55, 0.55, 0.45).
    pub box_max: [f64; 3],
    /// Time budget of one LOAD (read, fit, build the scene), wall-clock s, checked after each stage; a LOAD
    /// over it is refused and the live hairstyle stays. Default 30 s (the largest file the other bounds allow,
    /// 200,000 strands in 60 MiB, loads in about 3 s on a 2-core machine).
    pub max_seconds: f64,
}

impl Default for LoadLimits {
    fn default() -> Self {
        Self { max_file_bytes: 64 << 20, max_strands: 200_000, max_points: 10_000_000, box_min: [-0.55, -0.55, -0.85], box_max: [0.55, 0.55, 0.45], max_seconds: 30.0 }
    }
}

impl LoadLimits {
    /// A file of `bytes` bytes may be read; the error names the bound.
    pub fn check_size(&self, bytes: usize) -> Result<(), String> {
        if bytes > self.max_file_bytes {
            return Err(format!("the file has {bytes} bytes; at most {} bytes ({} MiB) may be loaded", self.max_file_bytes, self.max_file_bytes >> 20));
        }
        Ok(())
    }

    /// Strand and point counts (any units: checked right after reading, before fitting); the error names the bound.
    pub fn check_counts(&self, curves: &HairCurves) -> Result<(), String> {
        let n = curves.strands.len();
        if n == 0 || n > self.max_strands {
            return Err(format!("a hairstyle needs 1 to {} strands, got {n}", self.max_strands));
        }
        let points = curves.num_points();
        if points > self.max_points {
            return Err(format!("the hairstyle has {points} points; at most {} may be loaded", self.max_points));
        }
        if let Some(i) = curves.strands.iter().position(|s| s.is_empty()) {
            return Err(format!("strand {i} has no point"));
        }
        Ok(())
    }

    /// The LOAD started at `start` is still within [`LoadLimits::max_seconds`] after `stage`; the error names
    /// the stage, the time taken and the budget.
    pub fn check_time(&self, start: std::time::Instant, stage: &str) -> Result<(), String> {
        let t = start.elapsed().as_secs_f64();
        if !(t <= self.max_seconds) {
            return Err(format!("the load took {t:.2} s up to {stage}, over its time budget of {} s", self.max_seconds));
        }
        Ok(())
    }

    /// Every point finite and inside the box around the head (head frame, m); the error names the first
    /// point outside and the box.
    pub fn check_box(&self, curves: &HairCurves) -> Result<(), String> {
        for (i, st) in curves.strands.iter().enumerate() {
            // Compared in f32, the files' precision (the corners themselves are inside).
            let outside = |p: &[f32; 3]| !(0..3).all(|a| p[a] >= self.box_min[a] as f32 && p[a] <= self.box_max[a] as f32);
            if let Some(j) = st.iter().position(outside) {
                return Err(format!(
                    "strand {i} point {j} at {:?} m is outside the box around the head, x {:?} y {:?} z {:?} m (head frame; non-finite points are outside too)",
                    st[j],
                    [self.box_min[0], self.box_max[0]],
                    [self.box_min[1], self.box_max[1]],
                    [self.box_min[2], self.box_max[2]]
                ));
            }
        }
        Ok(())
    }
}
