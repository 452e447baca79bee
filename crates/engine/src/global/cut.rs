//! Scissors cuts of the render strands on the global layer: a cut job (computed here or on a worker
//! thread), its result applied to the kept lengths, and the pieces turned into falling clusters.

use super::GlobalCore;
use crate::scene::{GuideDisplacements, Scene};
use hairstyle::cut::{cut_polylines, polyline_length, Blade};
use lattice::cluster::{ClusterSet, CutPiece};
use nalgebra::{Isometry3, Point3, Vector3};
use std::sync::Arc;
use std::time::Instant;


/// What one scissors cut of the render strands did (masses in kg, by the render hair's linear density).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CutReport {
    /// Render strands cut.
    pub strands: usize,
    /// Mass of those strands before the cut (their hair on the head), kg.
    pub mass_before: f64,
    /// Mass they keep on the head, kg (from the kept lengths the session stores).
    pub mass_kept: f64,
    /// Mass of the pieces cut off, kg.
    pub mass_pieces: f64,
    /// Mass handed to the falling clusters (all pieces, or a sample scaled to the same total), kg.
    pub mass_clusters: f64,
    /// Pieces turned into falling chains (at most `GlobalParams::max_pieces_per_cut`).
    pub pieces: usize,
    /// Wall time of the cut, s (information).
    pub seconds: f64,
}

impl GlobalCore {
    /// Cuts the render strands crossing `blade` (their current shape: rest positions through the lattice)
    /// and turns the pieces into falling clusters, at once (`self.cut_job(blade).run()` then
    /// [`GlobalCore::apply_cut`]).
    pub fn cut(&mut self, blade: &Blade) -> CutReport {
        let job = self.cut_job(blade);
        let r = job.run();
        self.apply_cut(r).unwrap_or_default()
    }

    /// What a cut needs of the current state, copied so that another thread can compute it
    /// ([`CutJob::run`]) while this core keeps stepping.
    pub fn cut_job(&self, blade: &Blade) -> CutJob {
        CutJob { scene: self.scene.clone(), nodes: self.state.positions.clone(), head: self.head, kept_len: self.kept_len.clone(), kept_version: self.kept_version, lambda: self.lambda, blade: *blade, max_pieces: self.params.max_pieces_per_cut }
    }

    /// Applies a computed cut: shortens the strands and adds the falling clusters. None (and nothing done)
    /// if the strands changed since the job was taken (a reset meanwhile).
    pub fn apply_cut(&mut self, r: CutResult) -> Option<CutReport> {
        if r.kept_version != self.kept_version {
            return None;
        }
        let t0 = Instant::now();
        let mut rep = r.report;
        let v = self.scene.render.vertices_per_strand;
        let mut kept = (*self.kept).clone();
        for &(i, k) in &r.changes {
            self.kept_len[i] = k;
            kept[i] = ((k + 0.5).floor() as usize + 1).min(v) as u16;
        }
        self.kept = Arc::new(kept);
        self.kept_version += 1;
        if !r.pieces.is_empty() {
            match ClusterSet::new(&r.pieces, &self.cluster_params) {
                Ok(set) => {
                    rep.mass_clusters = set.total_mass();
                    rep.pieces = r.pieces.len();
                    if self.clusters.len() >= self.params.max_cluster_sets {
                        self.clusters.remove(0);
                    }
                    self.clusters.push(set);
                }
                Err(_) => self.failed += 1,
            }
        }
        rep.seconds += t0.elapsed().as_secs_f64();
        self.last_cut = Some(rep);
        Some(rep)
    }

    /// Cuts the global steps were asked for but left to the caller (see [`GlobalCore::defer_cuts`]).
    pub fn take_pending_cut(&mut self) -> Option<Blade> {
        if self.pending.is_empty() { None } else { Some(self.pending.remove(0)) }
    }

    /// With `true`, [`GlobalCore::step`] queues the scissors' cuts ([`GlobalCore::take_pending_cut`]) instead
    /// of making them: the live session computes them on a worker thread and applies them when done.
    pub fn defer_cuts(&mut self, on: bool) {
        self.deferred = on;
    }

    /// Version of the kept points (changes with every cut and reset).
    pub fn kept_version(&self) -> u64 {
        self.kept_version
    }
}

/// The inputs of one scissors cut of the render strands (see [`GlobalCore::cut_job`]).
pub struct CutJob {
    scene: Arc<Scene>,
    nodes: Vec<Point3<f64>>,
    head: Isometry3<f64>,
    kept_len: Vec<f64>,
    kept_version: u64,
    lambda: f64,
    blade: Blade,
    max_pieces: usize,
}

/// A computed cut, to apply with [`GlobalCore::apply_cut`].
pub struct CutResult {
    kept_version: u64,
    /// New kept length (vertex units) of each strand cut.
    changes: Vec<(usize, f64)>,
    /// The pieces for the falling clusters (at most `GlobalParams::max_pieces_per_cut`).
    pieces: Vec<CutPiece>,
    report: CutReport,
}

impl CutJob {
    /// Computes the cut: each kept strand (rest positions through the lattice) is cut at its first crossing
    /// of the blade's disk (`hairstyle::cut::cut_polylines`). Strands that cannot reach the blade are skipped
    /// without mapping them. At most `max_pieces` (`GlobalParams::max_pieces_per_cut`) pieces are kept for the clusters, sampled
    /// evenly, their masses scaled so that they carry all the mass cut off.
    pub fn run(&self) -> CutResult {
        let t0 = Instant::now();
        let mut rep = CutReport::default();
        let mut out = CutResult { kept_version: self.kept_version, changes: Vec::new(), pieces: Vec::new(), report: rep };
        let blade = &self.blade;
        if blade.validate().is_err() {
            return out;
        }
        let rh = &self.scene.render;
        let v = rh.vertices_per_strand;
        let nodes = &self.nodes;
        let c = Vector3::from(blade.point);
        let vert = |i: usize, j: usize| Vector3::from(rh.positions[i * v + j]).cast::<f64>();
        // Polyline of strand i as kept now, carried by the head and the lattice (`Scene::render_vertex`).
        let mapped = |i: usize, j: usize| self.scene.render_vertex(nodes, &self.head, &GuideDisplacements::default(), i, j);
        let line = |i: usize, k: f64| -> Vec<[f64; 3]> {
            let whole = (k.floor() as usize).min(v - 1);
            let mut out: Vec<[f64; 3]> = (0..=whole).map(|j| mapped(i, j).into()).collect();
            let frac = k - whole as f64;
            if frac > 0.0 && whole + 1 < v {
                // The cut end on the straight segment between the mapped vertices (where the cut was made).
                let (a, b) = (Vector3::from(out[whole]), mapped(i, whole + 1));
                out.push((a * (1.0 - frac) + b * frac).into());
            }
            out
        };
        let mut idx = Vec::new();
        let mut lines = Vec::new();
        // The FFD moves no point farther than the farthest node moved (its weights are a convex combination),
        // and the head's hold near the root only blends that motion towards the head's (`scene::carried`):
        // a strand whose rest vertices all stay farther than that from the blade's plane on one side, or from
        // the disk, cannot cross it, and is skipped without mapping it through the lattice.
        let reach = nodes.iter().zip(&self.scene.lattice.rest).map(|(x, r)| (x - self.head * r).norm()).fold(0.0, f64::max) + 1e-9;
        let n = Vector3::from(blade.normal).normalize();
        for i in 0..rh.strands() {
            let k = self.kept_len[i];
            if !(k > 0.0) {
                continue;
            }
            let last = (k.ceil() as usize).min(v - 1);
            let (mut above, mut below, mut near, mut seg) = (false, false, f64::INFINITY, 0.0f64);
            for j in 0..=last {
                let r = vert(i, j);
                let d = n.dot(&(r - c));
                above |= d > -reach;
                below |= d < reach;
                near = near.min((r - c).norm());
                if j > 0 {
                    seg = seg.max((r - vert(i, j - 1)).norm());
                }
            }
            if !(above && below) || near > blade.radius + reach + seg {
                continue;
            }
            let l = line(i, k);
            // A crossing at the very end (the strand's cut end lies on this blade) leaves nothing to cut.
            let rest = |(j, _, x): (usize, f64, Vector3<f64>)| (Vector3::from(l[j + 1]) - x).norm() + polyline_length(&l[j + 1..]);
            if blade.first_crossing(&l).is_some_and(|c| rest(c) > 1e-6) {
                idx.push(i);
                lines.push(l);
            }
        }
        let before: Vec<Vec<[f64; 3]>> = lines.clone();
        let Ok(pieces) = cut_polylines(&mut lines, self.lambda, blade) else { return out };
        for p in &pieces {
            let i = idx[p.source];
            let orig = &before[p.source];
            let Some((j, t, _)) = blade.first_crossing(orig) else { continue };
            // Segment j of the polyline is vertex segment j, except a partial last one (from an earlier cut).
            let k_old = self.kept_len[i];
            let whole = k_old.floor() as usize;
            let k_new = (if j >= whole { whole as f64 + (k_old - whole as f64) * t } else { j as f64 + t }).min(k_old);
            out.changes.push((i, k_new));
            rep.strands += 1;
            rep.mass_before += self.lambda * polyline_length(orig);
            rep.mass_kept += self.lambda * polyline_length(&line(i, k_new));
            rep.mass_pieces += p.mass;
        }
        // Falling clusters: at most max_pieces pieces, sampled evenly, masses scaled to the total.
        let every = pieces.len().div_ceil(self.max_pieces).max(1);
        let chosen: Vec<&hairstyle::cut::Piece> = pieces.iter().step_by(every).filter(|p| p.points.len() >= 2).collect();
        let chosen_mass: f64 = chosen.iter().map(|p| p.mass).sum();
        if chosen_mass > 0.0 {
            let scale = rep.mass_pieces / chosen_mass;
            out.pieces = chosen.iter().map(|p| CutPiece { points: p.points.iter().map(|x| Point3::from(*x)).collect(), mass: p.mass * scale }).collect();
        }
        rep.seconds = t0.elapsed().as_secs_f64();
        out.report = rep;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::SessionParams;
    use crate::testing::{small_scene, test_rot};
    use crate::tool::{Tool, ToolInput};

    #[test]
    fn scissors_shorten_the_render_strands_and_the_pieces_fall_to_rest() {
        // A horizontal cut through the hair at the back of the head. Mass: for the cut strands, the pieces'
        // mass plus the mass kept on the head (from the kept lengths the session stores) equals the mass
        // before, to 1e-9 relative; the falling clusters carry the pieces' mass (1e-9 relative). Then the
        // clusters fall: after 4 s they are at rest (kinetic energy < 1e-7 J) and above the floor.
        // The lattice is deformed first (the comb held in the hair for 0.2 s), so the cut is of the FFD's shape.
        let scene = small_scene();
        let mut g = GlobalCore::new(scene.clone(), &SessionParams::default());
        let comb = ToolInput { tool: Tool::Comb, present: true, position: Vector3::new(0.0, -0.13, 0.0), rotation: test_rot(), pressed: false, cuts: 0, ..ToolInput::default() };
        for _ in 0..20 {
            g.step(0.01, &comb);
        }
        let v = scene.render.vertices_per_strand;
        let blade = Blade { point: [0.0, -0.12, -0.05], normal: [0.0, 0.0, 1.0], radius: 0.08 };
        let rep = g.cut(&blade);
        eprintln!("{rep:?}");
        assert!(rep.strands > 50, "{} strands cut", rep.strands);
        assert!(((rep.mass_kept + rep.mass_pieces) - rep.mass_before).abs() <= 1e-9 * rep.mass_before, "{rep:?}");
        assert!((rep.mass_clusters - rep.mass_pieces).abs() <= 1e-9 * rep.mass_pieces, "{rep:?}");
        assert!(rep.pieces > 0 && rep.pieces <= crate::params::GlobalParams::default().max_pieces_per_cut);
        let snap = g.snapshot();
        assert_eq!(g.kept_lengths().iter().filter(|&&k| k < (v - 1) as f64).count(), rep.strands);
        assert!(snap.kept.iter().filter(|&&k| (k as usize) < v).count() > rep.strands / 2);
        assert!(g.kept_lengths().iter().all(|&k| k >= 0.0 && k <= (v - 1) as f64));
        assert!(!snap.chains.is_empty());
        // A second cut at the same place cuts nothing more; a cut higher up cuts the same strands again.
        assert_eq!(g.cut(&blade).strands, 0);
        let mass0 = g.cluster_mass();
        for _ in 0..400 {
            g.step(0.01, &ToolInput::default());
        }
        let e = g.cluster_energy();
        let low = g.snapshot().chains.iter().flatten().map(|p| p[2] as f64).fold(f64::INFINITY, f64::min);
        eprintln!("after 4 s: cluster energy {e} J, lowest point {low} m (floor {} m)", g.floor());
        assert!((g.cluster_mass() - mass0).abs() <= 1e-12 * mass0);
        assert!(e < 1e-7, "clusters at rest: {e} J");
        assert!(low >= g.floor() - 1e-6, "above the floor: {low}");
    }

    #[test]
    fn a_cut_on_a_worker_gives_the_same_strands_as_at_once() {
        // The live session defers cuts to a worker thread: the same blade gives the same kept lengths; a reset
        // between taking the job and applying it drops the result.
        let scene = small_scene();
        let p = SessionParams::default();
        let (mut now, mut later) = (GlobalCore::new(scene.clone(), &p), GlobalCore::new(scene.clone(), &p));
        later.defer_cuts(true);
        let input = ToolInput { tool: Tool::Scissors, present: true, position: Vector3::new(0.0, -0.12, -0.05), rotation: test_rot(), pressed: true, cuts: 1, ..ToolInput::default() };
        now.step(0.01, &ToolInput { cuts: 0, ..input });
        later.step(0.01, &input);
        let v0 = later.kept_version();
        let blade = later.take_pending_cut().expect("queued");
        now.cut(&blade);
        assert!(later.take_pending_cut().is_none());
        let job = later.cut_job(&blade);
        let r = std::thread::spawn(move || job.run()).join().unwrap();
        let rep = later.apply_cut(r).expect("applied");
        assert_eq!(later.kept_version(), v0 + 1);
        assert!(rep.strands > 50);
        assert!(now.kept_lengths() == later.kept_lengths(), "the same kept lengths");
        let job = later.cut_job(&Blade { point: [0.0, -0.12, -0.02], ..blade });
        later.reset();
        assert!(later.apply_cut(job.run()).is_none(), "a reset drops the pending cut");
    }
}
