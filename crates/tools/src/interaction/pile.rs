//! The tangles a comb pushes ahead along a wisp, and where it counts them from ([`Pile`]).

/// The tangles a comb pushes ahead along one wisp ([`crate::entanglement::Entanglement::pile_factor`]): the arc
/// length (m) at which the comb entered the wisp and the stretch of the wisp (m) its teeth have dragged through
/// since. The comb pushes the crossings it met since the entry; a tooth slipping out of the wisp for a while leaves
/// them where they are, ahead of it, and meets them again as it comes back: the pile is kept, whatever the number
/// of steps the wisp was away (so the travel does not depend on the time step). It is dropped when the comb meets
/// the wisp more than one span (the crossings' spacing) away from that stretch (elsewhere on the wisp): the travel
/// is then counted afresh from there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pile {
    /// Arc length at which the comb entered the wisp, m.
    entry: f64,
    /// The stretch a tooth has dragged through since, lowest and highest arc length, m.
    lo: f64,
    hi: f64,
}

impl Pile {
    /// The entry to count this step's travel from, given the pile `slot` of the wisp, the arc lengths `contacts`
    /// (m) of this step's tool contacts with it and the entanglement `span` (m): the kept pile's entry, unless every
    /// contact lies more than a span from the stretch dragged through (the pile is then dropped). Without a pile:
    /// the shallowest contact.
    pub(crate) fn entry(slot: &mut Option<Pile>, contacts: impl Iterator<Item = f64> + Clone, span: f64) -> f64 {
        if let Some(p) = *slot {
            let mut this_step = contacts.clone().peekable();
            if this_step.peek().is_none() || this_step.any(|s| s >= p.lo - span && s <= p.hi + span) {
                return p.entry;
            }
            *slot = None;
        }
        contacts.fold(f64::INFINITY, f64::min)
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

#[cfg(test)]
mod tests {
    use super::Pile;

    /// One step: the entry for the contacts `s`, then a drag at each of them, as `rows` does.
    fn step(slot: &mut Option<Pile>, s: &[f64], span: f64) -> f64 {
        let entry = Pile::entry(slot, s.iter().copied(), span);
        for &x in s {
            Pile::reach(slot, entry, x);
        }
        entry
    }

    #[test]
    fn the_pile_is_kept_while_the_comb_is_in_its_stretch_and_dropped_elsewhere() {
        let span = 6.6e-3;
        let mut p = None;
        // A down stroke: the entry is the first contact, the stretch follows the comb.
        assert_eq!(step(&mut p, &[0.010, 0.011], span), 0.010);
        for k in 1..=9 {
            assert_eq!(step(&mut p, &[0.011 + 1e-3 * k as f64], span), 0.010);
        }
        assert_eq!(p, Some(Pile { entry: 0.010, lo: 0.010, hi: 0.020 }));
        // Steps without any contact (the wisp slipped out of the teeth) keep it, whatever their number: the travel
        // does not depend on how many steps the wisp was away.
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
        // Met more than a span from it (elsewhere on the wisp): dropped, counted afresh from the shallowest contact.
        assert_eq!(step(&mut p, &[0.1, 0.09], span), 0.09);
        assert_eq!(p, Some(Pile { entry: 0.09, lo: 0.09, hi: 0.1 }));
        // Behind the entry by more than a span (a stroke starting above it): dropped too.
        assert_eq!(step(&mut p, &[0.09 - 1.1 * span], span), 0.09 - 1.1 * span);
    }
}
