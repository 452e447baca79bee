//! High-accuracy reference solutions of stiff first-order ODE systems `y' = f(t, y)`.
//!
//! Tests use it to measure the error of the fast fixed-step strand integrator against an adaptive,
//! variable-order stiff solver (the BDF/NDF method of the `diffsol` crate), in the role DASPK
//! plays in the Super-Helix paper. The caller supplies only `f`; the Jacobian is built from
//! forward finite differences of `f`. Time is in seconds; `y` and `atol` share the caller's units.

use std::cell::{Cell, RefCell};

use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason, Vector};

/// Error from the reference solver.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The arguments are unusable (empty or non-finite state, unsorted times, bad tolerances...).
    #[error("bad input to the reference solver: {0}")]
    BadInput(String),
    /// The solver failed (step size underflow, Newton failure, non-finite derivative...).
    #[error("reference solver failed: {0}")]
    Solver(String),
}

/// Options of the reference solver.
#[derive(Debug, Clone)]
pub struct ReferenceOptions {
    /// Relative tolerance of the local error test (dimensionless, default 1e-8).
    pub rtol: f64,
    /// Absolute tolerance of the local error test, in the units of `y` (default 1e-10).
    pub atol: f64,
    /// Largest internal step in seconds, or `None` (default) for no limit.
    pub max_step: Option<f64>,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-8,
            atol: 1e-10,
            max_step: None,
        }
    }
}

/// Work space of the finite-difference Jacobian.
struct FdScratch {
    /// Typical magnitude of each component: the largest |y_j| met so far.
    typ: Vec<f64>,
    /// Time (s) and state of the cached base value `f`.
    t: f64,
    y: Vec<f64>,
    f: Vec<f64>,
    /// Perturbed state `y + h v` and `f` there.
    y_h: Vec<f64>,
    f_h: Vec<f64>,
}

/// Most internal steps the solver may take before giving up.
const MAX_STEPS: usize = 5_000_000;

/// Integrate y' = f(t, y) from t0 (s) with y(t0) = y0 and return y at each of `times` (s, sorted
/// ascending, all >= t0; repeats allowed).
///
/// `f(t, y, dydt)` writes the derivative into `dydt`. The Jacobian is obtained by finite
/// differences of `f`: column j is a forward difference with step `sqrt(eps) * typ_j`, where
/// `typ_j` is the largest `|y_j|` met so far (1 while it is still 0), so the caller gives only `f`.
/// Outputs between internal steps come from the solver's interpolant, accurate to the tolerances.
pub fn solve_reference<F>(
    f: F,
    t0: f64,
    y0: &[f64],
    times: &[f64],
    opts: &ReferenceOptions,
) -> Result<Vec<Vec<f64>>, ReferenceError>
where
    F: Fn(f64, &[f64], &mut [f64]),
{
    validate(&f, t0, y0, times, opts)?;
    let n = y0.len();
    // Outputs at t0 itself need no integration.
    let mut out: Vec<Vec<f64>> = times
        .iter()
        .take_while(|&&t| t == t0)
        .map(|_| y0.to_vec())
        .collect();
    let Some(&t_end) = times.last().filter(|_| out.len() < times.len()) else {
        return Ok(out);
    };

    // Time of the first non-finite value returned by `f`, reported if the solve then fails.
    let bad_f = Cell::new(None::<f64>);
    let rhs = |y: &[f64], _p: &[f64], t: f64, dydt: &mut [f64]| {
        f(t, y, dydt);
        if bad_f.get().is_none() && dydt.iter().any(|v| !v.is_finite()) {
            bad_f.set(Some(t));
        }
    };
    // Jacobian-vector product J v by a forward difference along v (diffsol assembles the dense
    // Jacobian from v = e_j); f(t, y) is cached across the columns.
    let fd = RefCell::new(FdScratch {
        typ: y0.iter().map(|v| v.abs()).collect(),
        t: f64::NAN,
        y: vec![0.0; n],
        f: vec![0.0; n],
        y_h: vec![0.0; n],
        f_h: vec![0.0; n],
    });
    let jac_mul = |y: &[f64], _p: &[f64], t: f64, v: &[f64], jv: &mut [f64]| {
        let fd = &mut *fd.borrow_mut();
        let (mut scale, mut vmax) = (0.0_f64, 0.0_f64);
        for ((ti, yi), vi) in fd.typ.iter_mut().zip(y).zip(v) {
            *ti = ti.max(yi.abs());
            if *vi != 0.0 {
                scale = scale.max(if *ti > 0.0 { *ti } else { 1.0 });
                vmax = vmax.max(vi.abs());
            }
        }
        if vmax == 0.0 {
            return jv.fill(0.0);
        }
        if fd.t != t || fd.y != y {
            fd.t = t;
            fd.y.copy_from_slice(y);
            f(t, y, &mut fd.f);
        }
        let h = f64::EPSILON.sqrt() * scale / vmax;
        for ((yh, yi), vi) in fd.y_h.iter_mut().zip(y).zip(v) {
            *yh = yi + h * vi;
        }
        f(t, &fd.y_h, &mut fd.f_h);
        for ((jv, fh), f0) in jv.iter_mut().zip(&fd.f_h).zip(&fd.f) {
            *jv = (fh - f0) / h;
        }
    };

    let fail = |what: String| {
        let note = bad_f.get().map_or(String::new(), |t| {
            format!("; f returned a non-finite value at t = {t} s")
        });
        ReferenceError::Solver(what + &note)
    };
    let problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .t0(t0)
        .rtol(opts.rtol)
        .atol([opts.atol])
        .rhs_implicit(rhs, jac_mul)
        .init(|_p, _t, y: &mut [f64]| y.copy_from_slice(y0), n)
        .build()
        .map_err(|e| fail(format!("building the problem: {e}")))?;
    let mut solver = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| fail(format!("creating the BDF solver: {e}")))?;

    // March in equal chunks no longer than max_step (the solver cannot step over a chunk's end),
    // the last one ending exactly on t_end.
    let mut steps = 0;
    while out.len() < times.len() {
        let t_now = solver.state().t;
        let chunk_end = match opts.max_step {
            Some(h) if t_end - t_now > h * (1.0 + 1e-9) => {
                t_now + (t_end - t_now) / ((t_end - t_now) / h).ceil()
            }
            _ => t_end,
        };
        solver
            .set_stop_time(chunk_end)
            .map_err(|e| fail(format!("setting the stop time: {e}")))?;
        loop {
            let reason = solver
                .step()
                .map_err(|e| fail(format!("step from t = {} s: {e}", solver.state().t)))?;
            steps += 1;
            let state = solver.state();
            if state.y.clone_as_vec().iter().any(|v| !v.is_finite()) {
                return Err(fail(format!(
                    "the state became non-finite at t = {} s",
                    state.t
                )));
            }
            // At a stop time the solver's t may differ from chunk_end by round-off.
            let stopped = matches!(reason, OdeSolverStopReason::TstopReached);
            let t_reached = if stopped { chunk_end } else { state.t };
            while out.len() < times.len() && times[out.len()] <= t_reached {
                let t_out = times[out.len()].min(state.t);
                let y = solver
                    .interpolate(t_out)
                    .map_err(|e| fail(format!("interpolating at t = {t_out} s: {e}")))?;
                out.push(y.clone_as_vec());
            }
            if stopped {
                break;
            }
            if steps >= MAX_STEPS {
                return Err(fail(format!(
                    "more than {MAX_STEPS} steps, stopped at t = {} s",
                    state.t
                )));
            }
        }
    }
    Ok(out)
}

/// Checks the arguments and that `f(t0, y0)` is finite, naming the first problem found.
fn validate<F>(
    f: &F,
    t0: f64,
    y0: &[f64],
    times: &[f64],
    opts: &ReferenceOptions,
) -> Result<(), ReferenceError>
where
    F: Fn(f64, &[f64], &mut [f64]),
{
    let bad = |msg: String| Err(ReferenceError::BadInput(msg));
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if y0.is_empty() {
        return bad("y0 is empty".into());
    }
    if let Some(i) = y0.iter().position(|v| !v.is_finite()) {
        return bad(format!("y0[{i}] = {} is not finite", y0[i]));
    }
    if !t0.is_finite() {
        return bad(format!("t0 = {t0} is not finite"));
    }
    if let Some(i) = times.iter().position(|t| !t.is_finite()) {
        return bad(format!("times[{i}] = {} is not finite", times[i]));
    }
    if let Some(i) = times.iter().position(|&t| t < t0) {
        return bad(format!("times[{i}] = {} s is before t0 = {t0} s", times[i]));
    }
    if let Some(i) = times.windows(2).position(|w| w[1] < w[0]) {
        return bad(format!(
            "times are not sorted: times[{}] = {} < {}",
            i + 1,
            times[i + 1],
            times[i]
        ));
    }
    if !(positive(opts.rtol) && positive(opts.atol)) {
        return bad(format!(
            "tolerances must be positive (rtol = {}, atol = {})",
            opts.rtol, opts.atol
        ));
    }
    if let Some(h) = opts.max_step.filter(|&h| !positive(h)) {
        return bad(format!("max_step = {h} s must be positive and finite"));
    }
    let mut dydt = vec![0.0; y0.len()];
    f(t0, y0, &mut dydt);
    if let Some(i) = dydt.iter().position(|v| !v.is_finite()) {
        return bad(format!("f(t0, y0)[{i}] = {} is not finite", dydt[i]));
    }
    Ok(())
}

/// Reference trajectory of a strand: the coordinates `q` at each of `times` (s, from `state.time`), from the
/// adaptive stiff solver applied to `qddot = M^-1 F` with the root held still and constant `external` forces.
/// Errors if the root is moving (its motion is not part of the ODE here).
pub fn strand_trajectory(
    model: &crate::model::StrandModel,
    state: &crate::state::StrandState,
    external: &[crate::dynamics::PointForce],
    times: &[f64],
    opts: &ReferenceOptions,
) -> Result<Vec<nalgebra::DVector<f64>>, ReferenceError> {
    let root = &state.root;
    if [root.velocity, root.angular_velocity, root.acceleration, root.angular_acceleration].iter().any(|v| v.norm() != 0.0) {
        return Err(ReferenceError::BadInput("the root must be at rest for the reference trajectory".into()));
    }
    let n = model.dofs();
    let dynamics = RefCell::new(crate::dynamics::Dynamics::new(model));
    let scratch = RefCell::new(state.clone());
    let f = |_t: f64, y: &[f64], dy: &mut [f64]| {
        let mut st = scratch.borrow_mut();
        st.q.copy_from_slice(&y[..n]);
        st.qdot.copy_from_slice(&y[n..]);
        let mut dy_state = dynamics.borrow_mut();
        dy_state.evaluate(model, &st, external, true);
        let acc = dy_state.mass.clone().cholesky().map(|c| c.solve(&dy_state.forces));
        dy[..n].copy_from_slice(&y[n..]);
        match acc {
            Some(a) => dy[n..].copy_from_slice(a.as_slice()),
            None => dy[n..].iter_mut().for_each(|x| *x = f64::NAN),
        }
    };
    let y0: Vec<f64> = state.q.iter().chain(state.qdot.iter()).copied().collect();
    let ys = solve_reference(f, state.time, &y0, times, opts)?;
    Ok(ys.into_iter().map(|y| nalgebra::DVector::from_column_slice(&y[..n])).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn linear_stiff_system_matches_analytic_solution() {
        // y1' = -1000 (y1 - cos t), y2' = y1, y(0) = 0: stiffness ratio 1000.
        let calls = Cell::new(0usize);
        let f = |t: f64, y: &[f64], d: &mut [f64]| {
            calls.set(calls.get() + 1);
            d[0] = -1000.0 * (y[0] - t.cos());
            d[1] = y[0];
        };
        let (a, b) = (1e6 / (1e6 + 1.0), 1e3 / (1e6 + 1.0));
        let exact = |t: f64| {
            let e = (-1000.0 * t).exp();
            [
                a * t.cos() + b * t.sin() - a * e,
                a * t.sin() + b * (1.0 - t.cos()) - a / 1e3 * (1.0 - e),
            ]
        };
        let times = [0.0, 1e-4, 1e-3, 5e-3, 0.1, 1.0, 2.5, 5.0, 10.0];
        let ys = solve_reference(f, 0.0, &[0.0, 0.0], &times, &Default::default()).unwrap();
        assert_eq!(ys.len(), times.len());
        for (t, y) in times.iter().zip(&ys) {
            // Tolerance: 1e-6 absolute on each component (solution is O(1)).
            let e = exact(*t);
            assert!(
                (y[0] - e[0]).abs() < 1e-6 && (y[1] - e[1]).abs() < 1e-6,
                "t = {t}: {y:?} vs {e:?}"
            );
        }
        // An explicit method's stability limit h < ~3e-3 s would cost > 3000 steps (> 10^4 calls
        // at 4 or more stages) over 10 s; the stiff solver must stay below that.
        assert!(calls.get() < 10_000, "{} f calls", calls.get());
    }

    #[test]
    fn harmonic_oscillator_over_ten_periods() {
        // x'' = -w^2 x, x(0) = 1 m, x'(0) = 0, w = 2 pi * 3 rad/s, over 10 periods (3.33 s).
        let w = 2.0 * PI * 3.0;
        let f = |_t: f64, y: &[f64], d: &mut [f64]| {
            d[0] = y[1];
            d[1] = -w * w * y[0];
        };
        let period = 2.0 * PI / w;
        let times: Vec<f64> = (0..=200).map(|k| k as f64 * period / 20.0).collect();
        let limited = ReferenceOptions {
            max_step: Some(period / 20.0),
            ..Default::default()
        };
        for opts in [ReferenceOptions::default(), limited] {
            let ys = solve_reference(f, 0.0, &[1.0, 0.0], &times, &opts).unwrap();
            for (t, y) in times.iter().zip(&ys) {
                // Tolerance: 1e-5 m on x and 1e-5 * w m/s on x' (BDF error grows with periods).
                let (ex, ev) = (
                    (y[0] - (w * t).cos()).abs(),
                    (y[1] + w * (w * t).sin()).abs(),
                );
                assert!(ex < 1e-5 && ev < 1e-5 * w, "{opts:?} t = {t}: {y:?}");
            }
        }
    }

    #[test]
    fn robertson_kinetics() {
        let f = |_t: f64, y: &[f64], d: &mut [f64]| {
            d[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
            d[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1];
            d[2] = 3e7 * y[1] * y[1];
        };
        let ys =
            solve_reference(f, 0.0, &[1.0, 0.0, 0.0], &[40.0, 4e10], &Default::default()).unwrap();
        // Values at t = 40 s to 10 digits (SUNDIALS' cvRoberts_dns prints 7.1583e-01, 9.1855e-06,
        // 2.8416e-01). Tolerance: 1e-6 relative per component, the tiny y2 included.
        let known = [0.71582706872, 9.1855347646e-06, 0.28416374575];
        for (yi, ki) in ys[0].iter().zip(&known) {
            assert!((yi - ki).abs() < 1e-6 * ki, "{:?} vs {known:?}", ys[0]);
        }
        // At late times y1 decays like 2.08e3 / t (published tables: 5.20e-5 at t = 4e7, 5.20e-6
        // at 4e8), so y1(4e10) = 5.20e-8; tolerance 2 %. Fails with a badly scaled FD Jacobian.
        assert!(
            (ys[1][0] / 5.20e-8 - 1.0).abs() < 0.02,
            "y1(4e10) = {:e}",
            ys[1][0]
        );
        for y in &ys {
            // The kinetics conserve y1 + y2 + y3 = 1; tolerance 1e-8.
            let sum: f64 = y.iter().sum();
            assert!((sum - 1.0).abs() < 1e-8, "sum {sum}");
        }
    }

    #[test]
    fn bad_input_is_an_error_naming_the_problem() {
        let f = |_t: f64, y: &[f64], d: &mut [f64]| d[0] = -y[0];
        let o = ReferenceOptions::default();
        let neg_rtol = ReferenceOptions {
            rtol: -1.0,
            ..o.clone()
        };
        let nan_f = |_t: f64, _y: &[f64], d: &mut [f64]| d[0] = f64::NAN;
        let cases = [
            ("y0 is empty", solve_reference(f, 0.0, &[], &[1.0], &o)),
            (
                "not sorted",
                solve_reference(f, 0.0, &[1.0], &[2.0, 1.0], &o),
            ),
            (
                "before t0",
                solve_reference(f, 1.0, &[1.0], &[0.5, 2.0], &o),
            ),
            (
                "y0[0] = NaN is not finite",
                solve_reference(f, 0.0, &[f64::NAN], &[1.0], &o),
            ),
            (
                "tolerances",
                solve_reference(f, 0.0, &[1.0], &[1.0], &neg_rtol),
            ),
            ("f(t0, y0)", solve_reference(nan_f, 0.0, &[1.0], &[1.0], &o)),
        ];
        for (needle, result) in cases {
            match result {
                Err(e @ ReferenceError::BadInput(_)) => {
                    assert!(e.to_string().contains(needle), "{e}")
                }
                other => panic!("{needle}: expected BadInput, got {other:?}"),
            }
        }
    }

    #[test]
    fn non_finite_derivative_during_the_run_is_a_solver_error() {
        // f turns NaN from t = 0.5 s on: the solve must return an error, not panic or hang.
        let f = |t: f64, y: &[f64], d: &mut [f64]| d[0] = if t < 0.5 { -y[0] } else { f64::NAN };
        match solve_reference(f, 0.0, &[1.0], &[1.0], &Default::default()) {
            Err(e @ ReferenceError::Solver(_)) => {
                assert!(e.to_string().contains("non-finite"), "{e}")
            }
            other => panic!("expected a Solver error, got {other:?}"),
        }
    }

    #[test]
    fn outputs_at_t0_repeated_times_and_nonzero_t0() {
        // y' = -2 y from t0 = 3 s: y = exp(-2 (t - 3)); tolerance 1e-8 absolute.
        let f = |_t: f64, y: &[f64], d: &mut [f64]| d[0] = -2.0 * y[0];
        let times = [3.0, 3.0, 3.5, 3.5, 4.0];
        let ys = solve_reference(f, 3.0, &[1.0], &times, &Default::default()).unwrap();
        assert_eq!(ys.len(), times.len());
        for (t, y) in times.iter().zip(&ys) {
            assert!(
                (y[0] - (-2.0 * (t - 3.0)).exp()).abs() < 1e-8,
                "t = {t}: {y:?}"
            );
        }
        assert!(solve_reference(f, 3.0, &[1.0], &[], &Default::default())
            .unwrap()
            .is_empty());
    }
}
