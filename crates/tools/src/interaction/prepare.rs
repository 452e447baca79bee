//! Stage 2 (constraint model): every strand's free step prepared ([`strand::Strand::prepare_step`]), the reduced
//! strands of equal size four at a time ([`strand::StrandBatch`], SIMD lanes).

use super::frame::StepFrame;
use super::LocalInteraction;
use strand::{ModelKind, PointForce, Strand, StrandBatch};

impl LocalInteraction {
    /// Stage 2: prepares every strand's step of `frame.dt` s (constraint model only; batched first with
    /// `use_batches`); a strand that cannot prepare (another integrator, bad input) takes its whole step in
    /// stage 5 instead, which reports its error.
    pub(super) fn prepare_strands(&mut self, frame: &mut StepFrame) {
        self.ws.prepared.iter_mut().for_each(|p| *p = false);
        if frame.constraint {
            if self.params.use_batches {
                self.prepare_batched(frame.dt);
            }
            for (k, strand) in self.strands.iter_mut().enumerate() {
                if self.ws.prepared[k] {
                    continue;
                }
                if strand.integrator == strand::Integrator::LinearlyImplicitEuler && strand.prepare_step(frame.dt, &self.surface_torques[k]).is_ok() {
                    self.ws.prepared[k] = true;
                    self.surface_torques[k].clear();
                }
            }
        }
        frame.timings.dynamics = frame.clock.elapsed().as_secs_f64();
    }

    /// Prepares the steps of the reduced, linearly implicit strands in batches of four strands of equal size
    /// ([`StrandBatch::prepare`]); marks them prepared and remembers their lanes. Strands left out (another
    /// model or integrator, a lane that failed) are prepared one by one afterwards.
    fn prepare_batched(&mut self, dt: f64) {
        self.ws.lane_of.clear();
        self.ws.lane_of.resize(self.strands.len(), None);
        let mut groups: Vec<((usize, usize), Vec<usize>)> = Vec::new();
        for (k, s) in self.strands.iter().enumerate() {
            if s.model.kind != ModelKind::Reduced || s.integrator != strand::Integrator::LinearlyImplicitEuler {
                continue;
            }
            let key = (s.model.segments, s.dynamics.quadrature_nodes().len());
            match groups.iter_mut().find(|g| g.0 == key) {
                Some(g) => g.1.push(k),
                None => groups.push((key, vec![k])),
            }
        }
        let mut b = 0;
        for (key, members) in groups {
            for chunk in members.chunks(strand::batch::LANES) {
                if self.ws.batches.len() <= b {
                    self.ws.batches.push(StrandBatch::new(key.0, key.1));
                } else if !self.ws.batches[b].accepts(&self.strands[chunk[0]]) {
                    self.ws.batches[b] = StrandBatch::new(key.0, key.1);
                }
                let ext: Vec<&[PointForce]> = chunk.iter().map(|&k| self.surface_torques[k].as_slice()).collect();
                let mut refs: Vec<&mut Strand> = self.strands.iter_mut().enumerate().filter(|(k, _)| chunk.contains(k)).map(|(_, s)| s).collect();
                // A lane that fails is left unprepared; its strand's own step reports the error below.
                let _ = self.ws.batches[b].prepare(dt, &mut refs, &ext);
                for (j, &k) in chunk.iter().enumerate() {
                    if self.strands[k].has_prepared_step() {
                        self.ws.prepared[k] = true;
                        self.ws.lane_of[k] = Some((b, j));
                        self.surface_torques[k].clear();
                    }
                }
                b += 1;
            }
        }
    }
}
