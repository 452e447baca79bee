//! The tangles a comb pushes ahead along a wisp, and where it counts them from ([`Pile`]); the box its parting
//! teeth fill ([`Teeth`]), through which a wisp carries its pile between two teeth.

use crate::bvh::Piece;
use crate::contact::ToolPose;
use crate::geometry::Aabb;
use crate::shape::Capsule;

/// The tangles a comb pushes ahead along one wisp ([`crate::entanglement::Entanglement::pile_factor`]): the arc
/// length (m) the comb's travel along the wisp is counted from and the stretch of the wisp (m) its teeth have
/// dragged through since. The crossings a tooth meets with its path between two fibres are caught on it and move
/// down with the comb: they stay on the comb, not on one tooth, as long as the wisp passes through the comb.
/// - A wisp out of every tooth's reach (waiting between two teeth, as a wavy wisp does) keeps its pile while its
///   centreline passes through the box the parting teeth fill ([`Teeth`]), whatever the number of steps (so the
///   travel does not depend on the time step); it drops it when it leaves that box (the comb out of the hair, or
///   the wisp past the teeth's open ends).
/// - Met again within a span (the crossings' spacing) of the stretch dragged through: the same pile.
/// - Met again further on, having passed between the teeth: the same pile, counted on from the travel it had (no
///   crossing is gathered while no tooth reaches the wisp, and the pile factor is continuous at the re-entry).
/// - Met more than a span behind the stretch (a stroke coming from above): dropped, counted afresh from there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pile {
    /// Arc length the comb's travel along the wisp is counted from, m (where the comb entered it, moved on by the
    /// stretches it passed between the teeth).
    entry: f64,
    /// The stretch a tooth has dragged through since the last (re-)entry, lowest and highest arc length, m.
    lo: f64,
    hi: f64,
}

impl Pile {
    /// The entry to count this step's travel from, given the pile `slot` of the wisp, the arc lengths `contacts`
    /// (m) of this step's tool contacts with it, the entanglement `span` (m) and `threaded`, whether the wisp's
    /// centreline passes through the parting teeth's box (asked only on a step without contacts): see [`Pile`].
    /// Without a pile: the shallowest contact.
    pub(crate) fn entry(slot: &mut Option<Pile>, contacts: impl Iterator<Item = f64> + Clone, span: f64, threaded: impl FnOnce() -> bool) -> f64 {
        let shallowest = contacts.clone().fold(f64::INFINITY, f64::min);
        if let Some(p) = *slot {
            if shallowest == f64::INFINITY {
                if !threaded() {
                    *slot = None;
                }
                return p.entry;
            }
            if contacts.clone().any(|s| s >= p.lo - span && s <= p.hi + span) {
                return p.entry;
            }
            if shallowest > p.hi + span {
                let entry = shallowest - (p.hi - p.entry);
                *slot = Some(Pile { entry, lo: shallowest, hi: shallowest });
                return entry;
            }
            *slot = None;
        }
        shallowest
    }

    /// Records a tooth dragging through the wisp at arc length `s` (m), counting from `entry` (from
    /// [`Pile::entry`]): the stretch dragged through grows to hold it.
    pub(crate) fn reach(slot: &mut Option<Pile>, entry: f64, s: f64) {
        match slot {
            Some(p) if p.entry == entry => {
                p.lo = p.lo.min(s);
                p.hi = p.hi.max(s);
            }
            _ => *slot = Some(Pile { entry, lo: entry.min(s), hi: entry.max(s) }),
        }
    }
}

/// The box (tool frame, m) the parting teeth fill, grown by the wisp's reach: a wisp whose centreline passes
/// through it is threaded through the comb (between two teeth when no tooth reaches it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Teeth(Aabb);

impl Teeth {
    /// The box of `teeth` (the capsules that part a wisp) grown by `reach` (m); None without teeth.
    pub(crate) fn new<'a>(teeth: impl Iterator<Item = &'a Capsule>, reach: f64) -> Option<Self> {
        let b = teeth.fold(Aabb::empty(), |b, c| b.merge(&Aabb::of_segment(&c.a.into(), &c.b.into(), c.radius + reach)));
        (b.min.x <= b.max.x).then_some(Teeth(b))
    }

    /// Whether any of `pieces` (world frame, m) passes through the box with the tool at `pose`.
    pub(crate) fn thread(&self, pose: &ToolPose, pieces: &[Piece]) -> bool {
        let local = |x| pose.rotation.transpose() * (x - pose.position);
        pieces.iter().any(|p| self.0.meets_segment(&local(p.a), &local(p.b)))
    }
}

#[cfg(test)]
mod tests {
    use super::Pile;

    /// One step: the entry for the contacts `s`, then a drag at each of them, as `rows` does.
    fn step(slot: &mut Option<Pile>, s: &[f64], span: f64) -> f64 {
        threaded_step(slot, s, span, true)
    }

    /// The same with the wisp through the teeth's box or not.
    fn threaded_step(slot: &mut Option<Pile>, s: &[f64], span: f64, threaded: bool) -> f64 {
        let entry = Pile::entry(slot, s.iter().copied(), span, || threaded);
        for &x in s {
            Pile::reach(slot, entry, x);
        }
        entry
    }

    #[test]
    fn the_pile_is_kept_while_the_wisp_passes_through_the_comb_and_dropped_when_it_leaves() {
        let span = 6.6e-3;
        let mut p = None;
        // A down stroke: the entry is the first contact, the stretch follows the comb.
        assert_eq!(step(&mut p, &[0.010, 0.011], span), 0.010);
        for k in 1..=9 {
            assert_eq!(step(&mut p, &[0.011 + 1e-3 * k as f64], span), 0.010);
        }
        assert_eq!(p, Some(Pile { entry: 0.010, lo: 0.010, hi: 0.020 }));
        // Steps without any contact, the wisp between two teeth, keep it, whatever their number: the travel does
        // not depend on how many steps the wisp was away.
        for _ in 0..7 {
            assert_eq!(step(&mut p, &[], span), 0.010);
        }
        // Met again within a span of the stretch (ahead of it, or swung back): kept, the stretch grows.
        assert_eq!(step(&mut p, &[0.020 + 0.9 * span], span), 0.010);
        assert_eq!(step(&mut p, &[0.012], span), 0.010);
        assert_eq!(p, Some(Pile { entry: 0.010, lo: 0.010, hi: 0.020 + 0.9 * span }));
        // The comb turning back up through the stretch (the live session's up-and-down strokes): kept; the travel
        // |s - entry| falls back as the comb returns towards the entry.
        assert_eq!(step(&mut p, &[0.011, 0.010 - 0.5 * span], span), 0.010);
        // Met again further on, having passed between the teeth: the same pile, counted on from the travel it had
        // (0.010 + 0.9 span behind the new stretch): the travel at the re-entry is the travel before it.
        let had = 0.020 + 0.9 * span - 0.010;
        let entry = step(&mut p, &[0.1, 0.09], span);
        assert!((0.09 - entry - had).abs() < 1e-15, "{entry}");
        assert_eq!(p, Some(Pile { entry, lo: 0.09, hi: 0.1 }));
        // Behind the stretch by more than a span (a stroke starting above it): dropped, counted from there.
        assert_eq!(step(&mut p, &[0.09 - 1.1 * span], span), 0.09 - 1.1 * span);
        assert_eq!(p, Some(Pile { entry: 0.09 - 1.1 * span, lo: 0.09 - 1.1 * span, hi: 0.09 - 1.1 * span }));
        // The wisp out of the teeth's box (the comb out of the hair, or past the teeth's open ends): dropped, and
        // the comb meeting it again starts a new pile there.
        assert_eq!(threaded_step(&mut p, &[], span, false), 0.09 - 1.1 * span);
        assert_eq!(p, None);
        assert_eq!(step(&mut p, &[0.2], span), 0.2);
        assert_eq!(p, Some(Pile { entry: 0.2, lo: 0.2, hi: 0.2 }));
    }

    #[test]
    fn a_wisp_is_threaded_while_its_centreline_passes_between_the_teeth() {
        use super::Teeth;
        use crate::bvh::Piece;
        use crate::contact::ToolPose;
        use crate::shape::Capsule;
        use nalgebra::{Matrix3, Vector3};
        // Two teeth along the tool's y, 5 mm apart along x, 0.3 mm thick; the reach 1 mm. The tool turned a
        // quarter turn about z and moved: the box is in the tool's frame.
        let teeth = [Capsule { a: [0.0, 0.0, 0.0], b: [0.0, 0.02, 0.0], radius: 3e-4 }, Capsule { a: [5e-3, 0.0, 0.0], b: [5e-3, 0.02, 0.0], radius: 3e-4 }];
        let box_ = Teeth::new(teeth.iter(), 1e-3).unwrap();
        assert!(Teeth::new([].iter(), 1e-3).is_none());
        let pose = ToolPose { position: Vector3::new(0.1, 0.2, 0.3), rotation: Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0) };
        let wisp = |x: f64, y: f64| {
            // A vertical wisp (along the tool's z) at tool-frame (x, y), 4 cm long in two pieces.
            let at = |z: f64| pose.position + pose.rotation * Vector3::new(x, y, z);
            [Piece { strand: 0, s: 0.0, length: 0.02, a: at(0.02), b: at(0.0) }, Piece { strand: 0, s: 0.02, length: 0.02, a: at(0.0), b: at(-0.02) }]
        };
        assert!(box_.thread(&pose, &wisp(2.5e-3, 0.01)), "between the two teeth");
        assert!(box_.thread(&pose, &wisp(-1.2e-3, 0.01)), "within the reach outside the first tooth");
        assert!(!box_.thread(&pose, &wisp(-1.5e-3, 0.01)), "beyond the reach of the outer tooth");
        assert!(!box_.thread(&pose, &wisp(2.5e-3, 0.0225)), "past the teeth's open ends");
        assert!(!box_.thread(&pose, &wisp(2.5e-3, 0.01)[..1].iter().map(|p| Piece { a: p.a + pose.rotation * Vector3::new(0.0, 0.0, 0.0035), b: p.b + pose.rotation * Vector3::new(0.0, 0.0, 0.0035), ..*p }).collect::<Vec<_>>()), "above the comb");
    }
}
