//! The push of a body too thick to part a wisp (a comb's spine, `crate::entanglement::Entanglement::parts`) on the
//! wisp: the wisp's fibres, compressed against it, push back as a cushion before the body meets its centreline.
//!
//! A simulated strand stands for a wisp of many fibres of radius `r_f` whose surfaces lie within the wisp's radius
//! `r_w` of its centreline, their centres spread uniformly over the disc of radius `R = r_w - r_f` (the wisp's
//! section, as `crate::entanglement::parted_share` spreads them). A body whose face lies `g` from the centreline
//! (flat over the wisp's width: a 3 mm spine against a wisp of at most a millimetre) reaches the fibres whose
//! centres lie beyond `a = g - r_f` towards it and pushes each back by `x - a` (its centre's distance beyond `a`).
//! Each is held sideways by its neighbours at the entanglement points about every span, and bends over one span as
//! a simply supported beam under a central load: its lateral stiffness is `k_f = 48 E I / span^3`
//! (`Entanglement::fibre_stiffness`, the same beam as the parting load's). The load per fibre of the wisp (the
//! simulated strand's own fibre stands for the wisp's mean one, as the parting drag's share does) is
//!
//! `F(g) = k_f <max(0, x - a)>` over the disc,  `<...> = ((2/3) (R^2 - a^2)^(3/2) - a A(a)) / (pi R^2)`
//!
//! with `A(a)` the disc's area beyond the chord at `a` ([`packed_deflection`]). It is 0 when the body reaches the
//! outer fibres (`g = r_w`), grows as `(r_w - g)^(5/2)` at first, and its stiffness `-dF/dg = k_f A(a) / (pi R^2)`
//! is `k_f` times the share of the wisp's fibres the body has reached: continuous in the depth, with its slope. When
//! the body reaches the centreline's fibre (`g = r_f`, half the fibres reached, each pushed `4 R / (3 pi)` on mean)
//! the wisp is packed against it and the contact also becomes the non-penetrating one at the fibre
//! (`strand::constraint::ConstraintKind::Cushion`), which takes over where it asks for more. The load is taken at
//! the step's end with its stiffness ([`cushion_stiffness`], an implicit spring): `k_f` on a few centimetres of one
//! fibre is too stiff for an explicit millisecond step. Before, the spine was
//! that non-penetrating contact alone: nothing until it touched the centreline's fibre, then the whole wisp pushed
//! as a solid in one step (docs/combing.md, "The spine's cushion").
//!
//! No new parameter: the span (`Entanglement::span`), the fibre's flexural rigidity and the wisp's radius
//! (`crate::hair_contact::HairContact`) set it. A model choice: the reached fibres are pushed straight back against
//! the body (not around it, which a body wider than the wisp does not let them), each against its own span's
//! bending alone (the packed fibres do not stiffen each other).

use crate::entanglement::Entanglement;

/// Mean over a wisp's fibres, their centres uniform over a disc of radius `radius` (m), of how far a flat face
/// pushes them back, m: the face holds every centre at most `a` (m, from the disc's centre, towards the face) from
/// the centre, so a fibre whose centre lies at `x > a` is pushed `x - a`. 0 for `a >= radius`, `-a` for
/// `a <= -radius` (every fibre pushed), `2 radius / (3 pi)` at `a = 0` (half the fibres, pushed `4 radius / (3 pi)` on
/// mean). Its derivative in `a` is minus
/// the share of the fibres reached (`x > a`).
pub fn packed_deflection(a: f64, radius: f64) -> f64 {
    let r = radius.max(0.0);
    if !(a < r) {
        return 0.0;
    }
    if a <= -r {
        return -a;
    }
    let root = (r * r - a * a).max(0.0).sqrt();
    (2.0 / 3.0 * root * root * root - a * area_beyond(a, r)) / (std::f64::consts::PI * r * r)
}

/// The load per fibre of a wisp pressed by a body too thick to part it, N (the module's law): fibres of flexural
/// rigidity `ei` (N m^2) and radius `fibre_radius` (m) within the wisp's radius `wisp_radius` (m) of its centreline,
/// the body's face `gap` (m) from the centreline, each reached fibre bending over the span of `entanglement`. 0 from
/// `gap >= wisp_radius` on; for a wisp no wider than its fibre (`wisp_radius <= fibre_radius`) the fibre's own
/// beam, `k_f max(0, r_f - gap)`.
pub fn cushion_load(entanglement: &Entanglement, ei: f64, fibre_radius: f64, wisp_radius: f64, gap: f64) -> f64 {
    let k = entanglement.fibre_stiffness(ei);
    let load = k * packed_deflection(gap - fibre_radius, wisp_radius - fibre_radius);
    if load.is_finite() { load.max(0.0) } else { 0.0 }
}

/// Share (0..1) of a wisp's fibres, their centres uniform over a disc of radius `radius` (m), that a flat face holding
/// every centre at most `a` (m) from the disc's centre has reached (centres beyond `a`): minus the slope of
/// [`packed_deflection`] in `a`.
pub fn reached_share(a: f64, radius: f64) -> f64 {
    let r = radius.max(0.0);
    if !(a < r) {
        return 0.0;
    }
    if a <= -r {
        return 1.0;
    }
    (area_beyond(a, r) / (std::f64::consts::PI * r * r)).clamp(0.0, 1.0)
}

/// Area of a disc of radius `r` (m) beyond the chord at `a` (m from its centre, `|a| < r`), m^2.
fn area_beyond(a: f64, r: f64) -> f64 {
    let root = (r * r - a * a).max(0.0).sqrt();
    r * r * (std::f64::consts::FRAC_PI_2 - (a / r).clamp(-1.0, 1.0).asin()) - a * root
}

/// How fast [`cushion_load`] grows as the body comes closer (`gap` falls), N/m: the fibre's lateral stiffness
/// `48 E I / span^3` times the share of the wisp's fibres reached ([`reached_share`]). The constraint takes the load
/// implicitly with it (`strand::constraint::ConstraintKind::Cushion::stiffness`): a fibre's stiffness on the mass of
/// a few centimetres of one fibre is too stiff for an explicit step of a millisecond. Same arguments.
pub fn cushion_stiffness(entanglement: &Entanglement, ei: f64, fibre_radius: f64, wisp_radius: f64, gap: f64) -> f64 {
    let k = entanglement.fibre_stiffness(ei) * reached_share(gap - fibre_radius, wisp_radius - fibre_radius);
    if k.is_finite() { k.max(0.0) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean push over the disc by a midpoint sum on a fine grid (independent of the closed form).
    fn by_grid(a: f64, r: f64) -> (f64, f64) {
        let n = 1500;
        let (mut sum, mut reached, mut total) = (0.0, 0usize, 0usize);
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (-r + 2.0 * r * (i as f64 + 0.5) / n as f64, -r + 2.0 * r * (j as f64 + 0.5) / n as f64);
                if x * x + y * y <= r * r {
                    total += 1;
                    if x > a {
                        sum += x - a;
                        reached += 1;
                    }
                }
            }
        }
        (sum / total as f64, reached as f64 / total as f64)
    }

    #[test]
    fn the_packed_deflection_is_the_mean_push_over_the_disc() {
        // Against a grid integration of the disc (1.5e-3 of the radius), and its slope against the share reached;
        // the limits: none beyond the disc, every fibre pushed past it, 2 R / (3 pi) at the centre.
        let r = 0.6e-3;
        for a in [0.59e-3, 0.45e-3, 0.2e-3, 0.0, -0.25e-3, -0.5e-3] {
            let (want, share) = by_grid(a, r);
            let got = packed_deflection(a, r);
            assert!((got - want).abs() < 1.5e-3 * r, "a = {a}: {got} vs {want}");
            let h = 1e-9;
            let slope = (packed_deflection(a + h, r) - packed_deflection(a - h, r)) / (2.0 * h);
            assert!((slope + share).abs() < 2e-3, "a = {a}: slope {slope} vs share {share}");
        }
        assert_eq!(packed_deflection(r, r), 0.0);
        assert_eq!(packed_deflection(2.0 * r, r), 0.0);
        assert_eq!(packed_deflection(-3.0 * r, r), 3.0 * r);
        assert!((packed_deflection(-r, r) - r).abs() < 1e-15);
        assert!((packed_deflection(0.0, r) - 2.0 * r / (3.0 * std::f64::consts::PI)).abs() < 1e-15);
    }

    #[test]
    fn the_cushion_comes_up_continuously_from_the_outer_fibres() {
        // H1 fibre (EI 7.59e-9 N m^2, r_f 46.55 um) in a 0.7 mm wisp, the default span: 0 at the wisp's edge and
        // beyond, then growing with the depth with no step anywhere (every step of 0.1 um changes the load by
        // less than k_f x 0.1 um: its slope is at most k_f), as (depth)^(5/2) at first; k_f x 2 R / (3 pi) when the
        // face reaches the centreline's fibre; a wisp of one fibre is the fibre's own beam.
        let e = Entanglement::default();
        let (ei, rf, rw) = (7.59e-9, 46.55e-6, 0.7e-3);
        let k = e.fibre_stiffness(ei);
        assert_eq!(cushion_load(&e, ei, rf, rw, rw), 0.0);
        assert_eq!(cushion_load(&e, ei, rf, rw, 2.0 * rw), 0.0);
        let dg = 1e-7;
        let mut last = 0.0;
        let mut g = rw;
        while g > 0.0 {
            let f = cushion_load(&e, ei, rf, rw, g);
            assert!(f >= last && f - last <= k * dg * (1.0 + 1e-9), "g = {g}: {last} -> {f}");
            last = f;
            g -= dg;
        }
        let (d1, d2) = (1e-6, 4e-6);
        let ratio = cushion_load(&e, ei, rf, rw, rw - d2) / cushion_load(&e, ei, rf, rw, rw - d1);
        assert!((ratio / 4f64.powf(2.5) - 1.0).abs() < 0.02, "{ratio}");
        // The stiffness is the load's slope (a central difference, 1e-6 relative), k_f at most.
        for g in [0.69e-3, 0.5e-3, 0.3e-3, rf, 0.0] {
            let slope = (cushion_load(&e, ei, rf, rw, g - 1e-9) - cushion_load(&e, ei, rf, rw, g + 1e-9)) / 2e-9;
            let got = cushion_stiffness(&e, ei, rf, rw, g);
            assert!((got - slope).abs() <= 1e-6 * k && got <= k, "g = {g}: {got} vs {slope}");
        }
        assert_eq!(cushion_stiffness(&e, ei, rf, rw, rw), 0.0);
        let packed = cushion_load(&e, ei, rf, rw, rf);
        assert!((packed - k * 2.0 * (rw - rf) / (3.0 * std::f64::consts::PI)).abs() < 1e-12 * packed);
        assert!((cushion_load(&e, ei, rf, rf, 0.5 * rf) - k * 0.5 * rf).abs() < 1e-18);
    }
}
