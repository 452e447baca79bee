//! Stage 6: the constraints of all strands in one projected Gauss-Seidel solve ([`strand::constraint::solve`]), the
//! hair-hair contacts linking the two strands' rows (both strands' responses in each, no lag of a step).

use super::frame::StepFrame;
use super::LocalInteraction;
use strand::constraint::{solve, ConstraintLink, ConstraintOptions, ConstraintRows};

impl LocalInteraction {
    /// Stage 6: solves the rows `frame.rows[..frame.used]` together with the solver `options`; the impulses stay in
    /// the rows for the commit.
    pub(super) fn solve_rows(&self, frame: &mut StepFrame, options: &ConstraintOptions) {
        let t_solve = frame.clock.elapsed().as_secs_f64();
        // A pair whose other strand failed to build its rows is no link: the strand that built its rows
        // solves that contact alone, against a still strand.
        let links: Vec<ConstraintLink> = frame.hair_slots
            .iter()
            .filter_map(|pair| match pair {
                [Some(first), Some(second)] => Some(ConstraintLink { first: *first, second: *second }),
                _ => None,
            })
            .collect();
        // A linked contact's second row starts from minus its first's (warm starts).
        for link in &links {
            let p = frame.rows[link.first.0].impulses[link.first.1];
            frame.rows[link.second.0].impulses[link.second.1] = -p;
        }
        let t_sweeps = frame.clock.elapsed().as_secs_f64();
        frame.timings.sweeps = solve(&mut frame.rows[..frame.used], &links, options);
        frame.timings.solve = frame.clock.elapsed().as_secs_f64() - t_sweeps;
        frame.timings.rows = frame.rows[..frame.used].iter().map(ConstraintRows::len).sum();
        frame.timings.strand_rows = frame.rows[..frame.used].iter().map(ConstraintRows::len).max().unwrap_or(0);
        frame.timings.links = links.len();
        frame.timings.constrained += frame.clock.elapsed().as_secs_f64() - t_solve;
    }
}
