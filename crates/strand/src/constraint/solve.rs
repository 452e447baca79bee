//! The projected Gauss-Seidel solve of one or several strands' rows together, strands linked by their contacts
//! with each other solved as one group.

use super::rows::{ConstraintRows, ContactFrame};
use super::{ConstraintKind, ConstraintOptions};
use nalgebra::Vector3;

/// Two strands' constraints that are one contact (two strands touching): the `first` row's constraint, a
/// [`ConstraintKind::Contact`] whose normal points from the second strand's point towards the first's, is
/// solved for both points (relative velocity, the sum of both mobilities), and the `second` row takes the
/// opposite impulse (its own kind is not used). Each index is (position of the strand's rows in the slice given
/// to [`solve`], constraint index in those rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConstraintLink {
    /// The first strand's rows and constraint.
    pub first: (usize, usize),
    /// The second strand's rows and constraint.
    pub second: (usize, usize),
}

/// Solves the constraints of one or several strands' prepared steps together by projected Gauss-Seidel sweeps
/// (at most `opts.iterations`, fewer once converged to `opts.tolerance`), the law of the module documentation;
/// `links` couple rows of different strands (their contacts with each other), so that both strands' responses
/// enter each such contact in the same sweep (implicitly, with no lag of a step). Each group of strands linked
/// directly or through others (an unlinked strand alone) is solved as it would be alone: its sweeps stop when
/// its own impulses converged. A link naming a
/// missing row, a row of its own strand, a row already linked or a first row that is not a contact is ignored.
/// The impulses are left in each [`ConstraintRows::impulses`]; the sweeps start from the impulses the rows hold
/// (zero, or a warm start: [`ConstraintRows::warm_start`]). Returns the number of sweeps run.
pub fn solve(rows: &mut [ConstraintRows], links: &[ConstraintLink], opts: &ConstraintOptions) -> usize {
    let Some(h) = rows.first().map(|r| r.h) else { return 0 };
    let beta = opts.error_reduction_rate(h);
    let v_max = opts.max_correction_speed;
    let mix = opts.force_mixing(h);
    // Each row's role: 0 its own, 1 + l the first row of link l, usize::MAX the second row of a link.
    const SECOND: usize = usize::MAX;
    let mut role: Vec<Vec<usize>> = rows.iter().map(|r| vec![0; r.len()]).collect();
    let mut frames: Vec<Option<ContactFrame>> = vec![None; links.len()];
    for (l, link) in links.iter().enumerate() {
        let ((a, i), (b, j)) = (link.first, link.second);
        let fits = |(s, c): (usize, usize)| s < rows.len() && c < rows[s].len() && role[s][c] == 0;
        if a == b || !fits(link.first) || !fits(link.second) {
            continue;
        }
        let ConstraintKind::Contact { normal, .. } = rows[a].constraints[i].kind else { continue };
        let w = rows[a].w[i * rows[a].len() + i] + rows[b].w[j * rows[b].len() + j];
        if !(rows[a].active[i] || rows[b].active[j]) || !(w.trace() > 0.0) {
            continue;
        }
        frames[l] = Some(ContactFrame::new(&normal, &w, mix));
        role[a][i] = 1 + l;
        role[b][j] = SECOND;
    }
    // Strands linked by contacts, directly or through others, form a group; each group stops sweeping once a
    // whole sweep changed none of its impulses by more than `tolerance` times its largest one (a strand without
    // links is a group of its own, and stops as it would alone).
    let group = groups(rows.len(), links.iter().enumerate().filter(|(l, _)| frames[*l].is_some()).map(|(_, k)| (k.first.0, k.second.0)));
    let mut done = vec![false; rows.len()];
    // Per group: the largest impulse and the largest change of one in this sweep, N s.
    let mut sizes = vec![(0.0f64, 0.0f64); rows.len()];
    let mut sweeps = 0;
    for _ in 0..opts.iterations.max(1) {
        sweeps += 1;
        sizes.fill((0.0, 0.0));
        for s in 0..rows.len() {
            if done[group[s]] {
                continue;
            }
            let (mut own_largest, mut own_change) = (0.0f64, 0.0f64);
            for c in 0..rows[s].len() {
                let before = rows[s].impulses[c];
                match role[s][c] {
                    0 if rows[s].active[c] => rows[s].update(c, beta, v_max, mix),
                    0 | SECOND => continue,
                    r => {
                        let l = r - 1;
                        let ((a, i), (b, j)) = (links[l].first, links[l].second);
                        let (Some(frame), ConstraintKind::Contact { normal, depth, friction }) = (frames[l], rows[a].constraints[i].kind) else { continue };
                        let rel = rows[a].velocity(i) - rows[b].velocity(j);
                        let p = frame.update(&normal, friction, (beta * depth).min(v_max), &rel, &rows[a].impulses[i], mix, 0.0);
                        let p = if p.iter().all(|x| x.is_finite()) { p } else { Vector3::zeros() };
                        rows[a].impulses[i] = p;
                        rows[b].impulses[j] = -p;
                    }
                }
                // Squared norms: the square root of the largest equals the largest square root.
                own_largest = own_largest.max(rows[s].impulses[c].norm_squared());
                own_change = own_change.max((rows[s].impulses[c] - before).norm_squared());
            }
            let size = &mut sizes[group[s]];
            *size = (size.0.max(own_largest), size.1.max(own_change));
        }
        let mut all = true;
        for g in 0..rows.len() {
            if group[g] == g && !done[g] {
                let (largest, change) = (sizes[g].0.sqrt(), sizes[g].1.sqrt());
                done[g] = change <= opts.tolerance * largest;
                all &= done[g];
            }
        }
        if all {
            break;
        }
    }
    sweeps
}

/// The group of each of `n` strands joined by the `pairs` (strand indices; out-of-range ones ignored): the
/// smallest strand index of its group, so a group's representative is the strand whose group is itself.
fn groups(n: usize, pairs: impl Iterator<Item = (usize, usize)>) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for (a, b) in pairs.filter(|&(a, b)| a < n && b < n) {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        parent[ra.max(rb)] = ra.min(rb);
    }
    (0..n).map(|x| find(&mut parent, x)).collect()
}

#[cfg(test)]
mod tests {
    use super::groups;

    #[test]
    fn strands_joined_directly_or_through_others_form_one_group() {
        // 0-3 and 3-5 join 0, 3, 5; 4-2 joins 2 and 4; 1 and 6 stay alone; an out-of-range pair is ignored.
        let pairs = [(0, 3), (4, 2), (5, 3), (7, 1), (2, 4)];
        assert_eq!(groups(7, pairs.into_iter()), vec![0, 1, 2, 0, 2, 0, 6]);
        assert_eq!(groups(3, std::iter::empty()), vec![0, 1, 2]);
    }
}
