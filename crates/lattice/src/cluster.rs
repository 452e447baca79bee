//! Falling clusters of cut hair.
//!
//! Pieces cut off by the scissors (polylines with their masses) are grouped into clusters by where they were
//! cut (a grid of cell size [`ClusterParams::cluster_radius`]). Each cluster falls as a few **guide chains**
//! (mass-spring chains: stretch springs between neighbouring nodes, bending springs to second neighbours,
//! damping, air drag, gravity); every piece of the cluster is drawn **interpolated** from its guides (weights by
//! inverse distance of the cut points, plus a fixed offset that reproduces the piece's shape at the cut and a
//! little random noise). Guides collide with the body (a [`MetaballSet`]: a node where the field exceeds the
//! threshold is projected back onto the surface) and with a floor (a plane z = `floor`), with Coulomb friction,
//! and come to rest.
//!
//! Integration: semi-implicit (symplectic) Euler in sub-steps of at most [`ClusterParams::substep`]; spring
//! stiffnesses are given as natural frequencies of the lighter node (`k = m (2 pi f)^2`), which keeps the
//! sub-step stable whatever the hair mass. Internal forces cancel in pairs, so the chain's centre of mass
//! falls exactly at g (without drag) until it touches something.
//!
//! Mass: the cluster's mass (the sum of its pieces' masses) is spread over its guides' nodes as fractions that
//! sum to one; nothing is created or lost ([`ClusterSet::total_mass`]).

use crate::metaball::MetaballSet;
use nalgebra::{Point3, Vector3};
use std::collections::BTreeMap;

/// Parameters of the falling clusters (immutable).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClusterParams {
    /// Cut pieces whose cut points fall in the same cubic cell of this size form a cluster, m. Default 0.02.
    pub cluster_radius: f64,
    /// Guide chains per cluster (at most the number of its pieces), >= 1. Default 3.
    pub guides_per_cluster: usize,
    /// Nodes per guide chain, >= 2. Default 8.
    pub nodes_per_guide: usize,
    /// Natural frequency of a stretch spring with the lighter node, Hz. Default 60.
    pub stretch_frequency: f64,
    /// Natural frequency of a bending spring (to the second neighbour), Hz. Default 6.
    pub bending_frequency: f64,
    /// Damping ratio of every spring (relative velocity along it), dimensionless. Default 0.5.
    pub damping_ratio: f64,
    /// Air drag per unit mass, 1/s (terminal velocity g / drag). Default 3 (loose hair falls at about 3 m/s).
    pub air_drag: f64,
    /// Coulomb friction coefficient against the body and the floor, dimensionless. Default 0.6.
    pub friction: f64,
    /// Gravity, m/s^2. Default (0, 0, -9.81).
    pub gravity: Vector3<f64>,
    /// Height of the floor plane z = floor, m. Default -1.2 (head frame, head centre at the origin).
    pub floor: f64,
    /// Metaball surface threshold T, dimensionless. Default 0.25 (as [`crate::metaball::MetaballParams`]).
    pub threshold: f64,
    /// Largest integration sub-step, s. Default 5e-4.
    pub substep: f64,
    /// Amplitude of the random offset of an interpolated piece, m (grows from 0 at the cut to this at the
    /// tip). Default 0.002.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for ClusterParams {
    fn default() -> Self {
        Self {
            cluster_radius: 0.02,
            guides_per_cluster: 3,
            nodes_per_guide: 8,
            stretch_frequency: 60.0,
            bending_frequency: 6.0,
            damping_ratio: 0.5,
            air_drag: 3.0,
            friction: 0.6,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            floor: -1.2,
            threshold: 0.25,
            substep: 5e-4,
            noise: 0.002,
            seed: 1,
        }
    }
}

/// What is wrong with the clusters' input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClusterError {
    /// A parameter or input out of range.
    #[error("clusters: {field}: {reason}")]
    Invalid {
        /// The parameter or input.
        field: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The simulation produced a non-finite state; the step was undone.
    #[error("clusters: non-finite state at t = {time} s; step rejected")]
    NonFinite {
        /// Time of the rejected step, s.
        time: f64,
    },
}

fn invalid(field: &'static str, reason: String) -> ClusterError {
    ClusterError::Invalid { field, reason }
}

impl ClusterParams {
    /// Checks every field, naming the first bad one.
    pub fn validate(&self) -> Result<(), ClusterError> {
        let pos = |field: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(invalid(field, format!("must be > 0, got {v}")))
            }
        };
        let nonneg = |field: &'static str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(invalid(field, format!("must be >= 0, got {v}")))
            }
        };
        pos("cluster_radius", self.cluster_radius)?;
        pos("stretch_frequency", self.stretch_frequency)?;
        nonneg("bending_frequency", self.bending_frequency)?;
        nonneg("damping_ratio", self.damping_ratio)?;
        nonneg("air_drag", self.air_drag)?;
        nonneg("friction", self.friction)?;
        pos("substep", self.substep)?;
        nonneg("noise", self.noise)?;
        pos("threshold", self.threshold)?;
        if self.guides_per_cluster == 0 {
            return Err(invalid("guides_per_cluster", "must be >= 1".into()));
        }
        if self.nodes_per_guide < 2 {
            return Err(invalid(
                "nodes_per_guide",
                format!("must be >= 2, got {}", self.nodes_per_guide),
            ));
        }
        if !(self.gravity.iter().all(|x| x.is_finite()) && self.floor.is_finite()) {
            return Err(invalid("gravity/floor", "must be finite".into()));
        }
        Ok(())
    }
}

/// A cut piece as the clusters take it: a polyline (cut point first, m) and its mass (kg).
#[derive(Debug, Clone, PartialEq)]
pub struct CutPiece {
    /// Points, m.
    pub points: Vec<Point3<f64>>,
    /// Mass, kg (> 0 or 0).
    pub mass: f64,
}

/// A spring between two nodes of a chain.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Spring {
    i: usize,
    j: usize,
    rest: f64,
    k: f64,
    c: f64,
}

/// A guide chain (mass-spring), state and springs.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    /// Node positions, m.
    pub positions: Vec<Point3<f64>>,
    /// Node velocities, m/s.
    pub velocities: Vec<Vector3<f64>>,
    /// Node masses, kg.
    pub masses: Vec<f64>,
    springs: Vec<Spring>,
}

/// A piece drawn from its cluster's guides.
#[derive(Debug, Clone, PartialEq)]
struct Member {
    /// (guide index in the cluster, weight); weights sum to 1.
    weights: Vec<(usize, f64)>,
    /// Normalized arc length of each point along the piece, in [0, 1].
    u: Vec<f64>,
    /// Offset of each point from the weighted guide point, m.
    offsets: Vec<Vector3<f64>>,
}

/// One falling cluster.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    /// Its guide chains.
    pub guides: Vec<Chain>,
    members: Vec<Member>,
    /// Total mass of its pieces, kg.
    pub mass: f64,
}

/// Every falling cluster (state), with the step time.
#[derive(Debug, Clone, PartialEq)]
pub struct ClusterSet {
    /// The clusters.
    pub clusters: Vec<Cluster>,
    /// Time simulated, s.
    pub time: f64,
}

fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E3779B97F4A7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Cumulative normalized arc length of a polyline (all zeros if it has no length).
fn arc_params(points: &[Point3<f64>]) -> Vec<f64> {
    let mut s = vec![0.0];
    for w in points.windows(2) {
        s.push(s.last().unwrap() + (w[1] - w[0]).norm());
    }
    let total = *s.last().unwrap();
    if total > 0.0 {
        s.iter().map(|x| x / total).collect()
    } else {
        (0..points.len())
            .map(|i| {
                if points.len() > 1 {
                    i as f64 / (points.len() - 1) as f64
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// Point at normalized arc parameter u of a polyline with parameters `params`.
fn at_param(points: &[Point3<f64>], params: &[f64], u: f64) -> Point3<f64> {
    if points.len() == 1 {
        return points[0];
    }
    let k = params.partition_point(|&p| p <= u).clamp(1, points.len() - 1);
    let (a, b) = (params[k - 1], params[k]);
    let t = if b > a {
        ((u - a) / (b - a)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    points[k - 1] + (points[k] - points[k - 1]) * t
}

/// Node parameters of a chain of n nodes: evenly spaced in [0, 1].
fn chain_params(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64 / (n - 1) as f64).collect()
}

impl ClusterSet {
    /// Groups `pieces` into clusters and builds their guide chains, at rest.
    pub fn new(pieces: &[CutPiece], params: &ClusterParams) -> Result<Self, ClusterError> {
        params.validate()?;
        for (i, p) in pieces.iter().enumerate() {
            if p.points.is_empty() || !p.points.iter().all(|x| x.iter().all(|c| c.is_finite())) {
                return Err(invalid(
                    "pieces",
                    format!("piece {i} is empty or has a non-finite point"),
                ));
            }
            if !(p.mass.is_finite() && p.mass >= 0.0) {
                return Err(invalid("pieces", format!("piece {i} has mass {}", p.mass)));
            }
        }
        let mut cells: BTreeMap<[i64; 3], Vec<usize>> = BTreeMap::new();
        for (i, p) in pieces.iter().enumerate() {
            let key = [0, 1, 2].map(|k| (p.points[0][k] / params.cluster_radius).floor() as i64);
            cells.entry(key).or_default().push(i);
        }
        let mut rng = params.seed;
        let n = params.nodes_per_guide;
        let np = chain_params(n);
        let mut clusters = vec![];
        for idx in cells.into_values() {
            let mass: f64 = idx.iter().map(|&i| pieces[i].mass).sum();
            // Guides: the longest pieces (ties by index).
            let len = |i: usize| pieces[i].points.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>();
            let mut order = idx.clone();
            order.sort_by(|&a, &b| len(b).total_cmp(&len(a)).then(a.cmp(&b)));
            order.truncate(params.guides_per_cluster.min(idx.len()));
            let g = order.len();
            let mut guides = vec![];
            for &gi in &order {
                let pts = &pieces[gi].points;
                let pp = arc_params(pts);
                let positions: Vec<Point3<f64>> = np.iter().map(|&u| at_param(pts, &pp, u)).collect();
                // Lumped masses: each node carries half its neighbouring intervals, as fractions summing to 1.
                let frac: Vec<f64> = (0..n)
                    .map(|k| {
                        if k == 0 || k == n - 1 {
                            0.5 / (n - 1) as f64
                        } else {
                            1.0 / (n - 1) as f64
                        }
                    })
                    .collect();
                let masses: Vec<f64> = frac.iter().map(|f| f * mass / g as f64).collect();
                let mut springs = vec![];
                for (step, f) in [(1usize, params.stretch_frequency), (2, params.bending_frequency)] {
                    if f <= 0.0 {
                        continue;
                    }
                    let w = 2.0 * std::f64::consts::PI * f;
                    for i in 0..n.saturating_sub(step) {
                        let j = i + step;
                        let m = masses[i].min(masses[j]);
                        springs.push(Spring {
                            i,
                            j,
                            rest: (positions[j] - positions[i]).norm(),
                            k: m * w * w,
                            c: 2.0 * params.damping_ratio * m * w,
                        });
                    }
                }
                guides.push(Chain {
                    velocities: vec![Vector3::zeros(); n],
                    positions,
                    masses,
                    springs,
                });
            }
            // Members: every piece, interpolated from the guides.
            let mut members = vec![];
            for &i in &idx {
                let pts = &pieces[i].points;
                let mut weights: Vec<(usize, f64)> = order
                    .iter()
                    .enumerate()
                    .map(|(k, &gi)| (k, 1.0 / ((pieces[gi].points[0] - pts[0]).norm() + 1e-4)))
                    .collect();
                let sum: f64 = weights.iter().map(|w| w.1).sum();
                weights.iter_mut().for_each(|w| w.1 /= sum);
                let u = arc_params(pts);
                let dir = Vector3::new(
                    splitmix(&mut rng) - 0.5,
                    splitmix(&mut rng) - 0.5,
                    splitmix(&mut rng) - 0.5,
                );
                let dir = dir.try_normalize(1e-12).unwrap_or(Vector3::x());
                let offsets = pts
                    .iter()
                    .zip(&u)
                    .map(|(p, &uk)| {
                        let base = weights.iter().fold(Vector3::zeros(), |acc, &(k, w)| {
                            acc + at_param(&guides[k].positions, &np, uk).coords * w
                        });
                        p.coords - base + dir * (params.noise * uk)
                    })
                    .collect();
                members.push(Member { weights, u, offsets });
            }
            clusters.push(Cluster { guides, members, mass });
        }
        Ok(Self { clusters, time: 0.0 })
    }

    /// Total mass carried by the guide nodes, kg (equals the pieces' mass).
    pub fn total_mass(&self) -> f64 {
        self.clusters
            .iter()
            .flat_map(|c| &c.guides)
            .flat_map(|g| &g.masses)
            .sum()
    }

    /// Kinetic energy of the guide nodes, J.
    pub fn kinetic_energy(&self) -> f64 {
        self.clusters
            .iter()
            .flat_map(|c| &c.guides)
            .map(|g| {
                g.masses
                    .iter()
                    .zip(&g.velocities)
                    .map(|(m, v)| 0.5 * m * v.norm_squared())
                    .sum::<f64>()
            })
            .sum()
    }

    /// Advances every cluster by `dt` seconds (sub-stepped) against the `body` and the floor. A step that
    /// would give a non-finite state is rejected and the state kept.
    pub fn step(&mut self, params: &ClusterParams, body: &MetaballSet, dt: f64) -> Result<(), ClusterError> {
        params.validate()?;
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(invalid("dt", format!("must be >= 0 s, got {dt}")));
        }
        let subs = (dt / params.substep).ceil().max(1.0) as usize;
        let h = dt / subs as f64;
        let saved = self.clusters.clone();
        for _ in 0..subs {
            for c in &mut self.clusters {
                for g in &mut c.guides {
                    substep(g, params, body, h);
                }
            }
        }
        let finite = self.clusters.iter().flat_map(|c| &c.guides).all(|g| {
            g.positions.iter().all(|p| p.iter().all(|x| x.is_finite()))
                && g.velocities.iter().all(|v| v.iter().all(|x| x.is_finite()))
        });
        if !finite {
            self.clusters = saved;
            return Err(ClusterError::NonFinite { time: self.time });
        }
        self.time += dt;
        Ok(())
    }

    /// Every piece's points now, m: interpolated from its guides, then pushed out of the body and above the
    /// floor (so no drawn point is inside).
    pub fn piece_points(&self, params: &ClusterParams, body: &MetaballSet) -> Vec<Vec<Point3<f64>>> {
        let np = chain_params(params.nodes_per_guide);
        let mut out = vec![];
        for c in &self.clusters {
            for m in &c.members {
                let pts =
                    m.u.iter()
                        .zip(&m.offsets)
                        .map(|(&u, off)| {
                            let base = m.weights.iter().fold(Vector3::zeros(), |acc, &(k, w)| {
                                acc + at_param(&c.guides[k].positions, &np, u).coords * w
                            });
                            let mut x = Point3::from(base + off);
                            project_out(body, params, &mut x);
                            x
                        })
                        .collect();
                out.push(pts);
            }
        }
        out
    }
}

/// Moves `x` out of the body (onto the threshold surface, Newton steps along the field's gradient) and above
/// the floor. Returns the outward normal if it moved or if it lies within [`CONTACT_BAND`] of a surface (a
/// resting contact: the caller then removes the inward velocity).
fn project_out(body: &MetaballSet, params: &ClusterParams, x: &mut Point3<f64>) -> Option<Vector3<f64>> {
    let mut normal = None;
    for _ in 0..20 {
        let (f, g) = body.field_and_gradient(x);
        let gg = g.norm_squared();
        if f <= params.threshold {
            if f > 0.0 && gg > 1e-24 && (params.threshold - f) / gg.sqrt() < CONTACT_BAND {
                normal = normal.or(Some(-g / gg.sqrt()));
            }
            break;
        }
        if gg < 1e-24 {
            *x += Vector3::z() * 1e-4; // at a ball's exact centre: nudge and retry
            continue;
        }
        // Newton on F(x) = T along -grad F.
        *x -= g * ((f - params.threshold) / gg);
        normal = Some(-g / gg.sqrt());
    }
    if x.z < params.floor + CONTACT_BAND {
        x.z = x.z.max(params.floor);
        normal = Some(Vector3::z());
    }
    normal
}

/// Distance from a surface within which a node counts as touching it, m.
pub const CONTACT_BAND: f64 = 1e-4;

fn substep(g: &mut Chain, params: &ClusterParams, body: &MetaballSet, h: f64) {
    let n = g.positions.len();
    let mut force: Vec<Vector3<f64>> = g
        .masses
        .iter()
        .zip(&g.velocities)
        .map(|(m, v)| (params.gravity - v * params.air_drag) * *m)
        .collect();
    for s in &g.springs {
        let d = g.positions[s.j] - g.positions[s.i];
        let len = d.norm();
        if len < 1e-15 {
            continue;
        }
        let e = d / len;
        let vrel = (g.velocities[s.j] - g.velocities[s.i]).dot(&e);
        let f = e * (s.k * (len - s.rest) + s.c * vrel);
        force[s.i] += f;
        force[s.j] -= f;
    }
    for k in 0..n {
        if g.masses[k] > 0.0 {
            g.velocities[k] += force[k] * (h / g.masses[k]);
        }
        g.positions[k] += g.velocities[k] * h;
        if let Some(normal) = project_out(body, params, &mut g.positions[k]) {
            let v = g.velocities[k];
            let vn = v.dot(&normal);
            if vn < 0.0 {
                // Inelastic contact: remove the inward normal velocity; Coulomb friction takes up to mu |vn|
                // off the tangential velocity.
                let vt = v - normal * vn;
                let vt_norm = vt.norm();
                let cut = params.friction * (-vn);
                g.velocities[k] = if vt_norm <= cut {
                    Vector3::zeros()
                } else {
                    vt * (1.0 - cut / vt_norm)
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hanging(x: f64, y: f64, z: f64, len: f64, n: usize, mass: f64) -> CutPiece {
        CutPiece {
            points: (0..n)
                .map(|k| Point3::new(x + 0.002 * (k as f64).sin(), y, z - len * k as f64 / (n - 1) as f64))
                .collect(),
            mass,
        }
    }

    #[test]
    fn a_free_chain_falls_at_g() {
        // No drag, nothing to touch: the centre of mass follows semi-implicit Euler of free fall exactly,
        // v = g t (1e-12 relative) and z drop g h^2 n (n + 1) / 2 = g t^2 / 2 + g h t / 2 (1e-12 relative),
        // i.e. g t^2 / 2 within the method's O(h) term g h t / 2.
        let params = ClusterParams {
            air_drag: 0.0,
            floor: -100.0,
            ..Default::default()
        };
        let body = MetaballSet::new(vec![]);
        let pieces = vec![hanging(0.0, 0.0, 0.0, 0.05, 10, 3e-6)];
        let mut set = ClusterSet::new(&pieces, &params).unwrap();
        let com = |s: &ClusterSet| {
            let g = &s.clusters[0].guides[0];
            let m: f64 = g.masses.iter().sum();
            let x = g
                .positions
                .iter()
                .zip(&g.masses)
                .fold(Vector3::zeros(), |a, (p, m)| a + p.coords * *m)
                / m;
            let v = g
                .velocities
                .iter()
                .zip(&g.masses)
                .fold(Vector3::zeros(), |a, (v, m)| a + v * *m)
                / m;
            (x, v)
        };
        let (x0, _) = com(&set);
        for _ in 0..50 {
            set.step(&params, &body, 0.01).unwrap();
        }
        let (x, v) = com(&set);
        let (t, h, g) = (0.5, params.substep, 9.81);
        assert!((v.z + g * t).abs() < 1e-12 * g * t, "v = {v:?}");
        assert!(v.x.abs() < 1e-12 && v.y.abs() < 1e-12);
        let n = (t / h).round();
        let drop = x0.z - x.z;
        assert!((drop - g * h * h * n * (n + 1.0) / 2.0).abs() < 1e-12 * drop);
        assert!((drop - g * t * t / 2.0).abs() <= g * h * t / 2.0 * (1.0 + 1e-9));
    }

    #[test]
    fn with_air_drag_the_fall_tends_to_terminal_velocity() {
        // COM velocity: v = g/c (1 - exp(-c t)); semi-implicit Euler with h = 0.5 ms is first order: 1e-3 relative.
        let params = ClusterParams {
            air_drag: 3.0,
            floor: -100.0,
            ..Default::default()
        };
        let mut set = ClusterSet::new(&[hanging(0.0, 0.0, 0.0, 0.05, 10, 3e-6)], &params).unwrap();
        for _ in 0..100 {
            set.step(&params, &MetaballSet::new(vec![]), 0.01).unwrap();
        }
        let g = &set.clusters[0].guides[0];
        let m: f64 = g.masses.iter().sum();
        let v = g
            .velocities
            .iter()
            .zip(&g.masses)
            .fold(Vector3::zeros(), |a, (v, m)| a + v * *m)
            / m;
        let exact = 9.81 / 3.0 * (1.0 - (-3.0f64).exp());
        assert!((-v.z - exact).abs() < 1e-3 * exact, "{} vs {exact}", -v.z);
    }

    #[test]
    fn a_cluster_dropped_on_the_shoulders_comes_to_rest_outside_with_its_mass() {
        // Cut pieces 5 cm long above the left shoulder of the rough body (head radius 0.1 m), some above the
        // right one; 4 s of fall. At rest: kinetic energy below 1e-12 J (the pieces weigh m g = 1.6e-4 N, so
        // that is the energy of a 6 nm drop; measured 1.9e-14 J); no guide node and no drawn point inside the
        // body (field at most T (1 + 1e-6)) or under the floor; mass conserved to 1e-12.
        let body = MetaballSet::head_neck_shoulders(0.1);
        let params = ClusterParams {
            floor: -0.6,
            ..Default::default()
        };
        let mut pieces = vec![];
        for i in 0..12 {
            let x = if i % 3 == 0 { 0.11 } else { -0.11 };
            pieces.push(hanging(
                x + 0.001 * i as f64,
                -0.01 + 0.001 * i as f64,
                -0.02,
                0.05,
                12,
                1e-6 * (1.0 + 0.1 * i as f64),
            ));
        }
        let m0: f64 = pieces.iter().map(|p| p.mass).sum();
        let mut set = ClusterSet::new(&pieces, &params).unwrap();
        assert!(set.clusters.len() >= 2);
        assert!(((set.total_mass() - m0) / m0).abs() < 1e-12);
        let mut landed_on_body = false;
        for _ in 0..400 {
            set.step(&params, &body, 0.01).unwrap();
            landed_on_body |= set
                .clusters
                .iter()
                .flat_map(|c| &c.guides)
                .flat_map(|g| &g.positions)
                .any(|p| body.field(p) > 0.2);
        }
        assert!(landed_on_body, "the pieces touched the shoulders");
        let ke = set.kinetic_energy();
        let on_floor = set
            .clusters
            .iter()
            .flat_map(|c| &c.guides)
            .flat_map(|g| &g.positions)
            .filter(|p| p.z < params.floor + 1e-9)
            .count();
        println!("kinetic energy at rest {ke:e} J, {on_floor} guide nodes on the floor");
        assert!(ke < 1e-12, "kinetic energy {ke} J");
        for p in set.clusters.iter().flat_map(|c| &c.guides).flat_map(|g| &g.positions) {
            assert!(
                body.field(p) <= params.threshold * (1.0 + 1e-6) && p.z >= params.floor,
                "{p:?}"
            );
        }
        let drawn = set.piece_points(&params, &body);
        assert_eq!(drawn.len(), 12);
        for p in drawn.iter().flatten() {
            assert!(
                body.field(p) <= params.threshold * (1.0 + 1e-6) && p.z >= params.floor,
                "{p:?}"
            );
        }
        assert!(((set.total_mass() - m0) / m0).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_named() {
        let p = ClusterParams {
            substep: 0.0,
            ..Default::default()
        };
        assert!(ClusterSet::new(&[], &p).unwrap_err().to_string().contains("substep"));
        let bad = CutPiece {
            points: vec![Point3::new(f64::NAN, 0.0, 0.0)],
            mass: 1.0,
        };
        assert!(ClusterSet::new(&[bad], &ClusterParams::default())
            .unwrap_err()
            .to_string()
            .contains("piece 0"));
    }
}
