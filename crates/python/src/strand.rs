//! `coiffure.Strand`: one Super-Helix strand (`strand::Strand`) built from a strand spec (docs/strand-spec.md),
//! the same spec and code as `coiffure strand --spec FILE.toml`.

use crate::convert::Source;
use crate::errors::strand_err;
use crate::interrupt::Watch;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use strand::kinematics::{centerline, segment_frames};
use strand::spec::StrandSpec;
use strand::statics::{natural_frequencies, solve_equilibrium, StaticOptions};
use strand::{Integrator, ModelKind, StrandState};

/// One Super-Helix hair strand: N helical segments clamped at a root, reduced (twist + bend about the major
/// axis, 2N coordinates) or full (3N). SI units: m, kg, s; coordinates are curvatures in rad/m.
#[pyclass(name = "Strand", module = "coiffure")]
pub struct PyStrand {
    inner: strand::Strand,
}

fn name_of(kind: ModelKind) -> &'static str {
    match kind {
        ModelKind::Reduced => "reduced",
        ModelKind::Full => "full",
    }
}

fn vector(v: Vec<f64>, n: usize, what: &str) -> PyResult<nalgebra::DVector<f64>> {
    if v.len() != n {
        return Err(PyValueError::new_err(format!("{what} needs {n} values (the strand's coordinates), got {}", v.len())));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(PyValueError::new_err(format!("{what}[{i}] must be finite, got {}", v[i])));
    }
    Ok(nalgebra::DVector::from_vec(v))
}

#[pymethods]
impl PyStrand {
    /// A strand from a spec: a dict with the keys of the strand spec TOML (docs/strand-spec.md; ``None``
    /// values mean "default"), or a path to such a file. The strand starts at its rest shape, at rest, at
    /// time 0. Raises ``ValueError`` naming the key for a bad spec.
    #[staticmethod]
    fn from_spec(spec: &Bound<'_, PyAny>) -> PyResult<Self> {
        let source = Source::from_py(spec, "spec")?;
        let parsed: StrandSpec = source.parse("spec")?;
        let context = match source.path() {
            Some(p) => format!("invalid spec {}", p.display()),
            None => "invalid spec".to_string(),
        };
        let (model, root) = parsed.build().map_err(|e| strand_err(&context, e))?;
        let inner = strand::Strand::new(model, root).map_err(|e| strand_err(&context, e))?;
        Ok(Self { inner })
    }

    /// Solves the static equilibrium under gravity (Newton with line search on the potential energy), starting
    /// from the current coordinates with the root held still; sets ``q`` to it and ``qdot`` to zero.
    /// Returns a dict: ``iterations``, ``stable`` (whether the equilibrium is stable), ``potential`` (J).
    /// ``tolerance``: relative size of the last Newton update; ``max_iterations``: Newton iterations.
    #[pyo3(signature = (tolerance = 1e-11, max_iterations = 200))]
    fn solve_static<'py>(&mut self, py: Python<'py>, tolerance: f64, max_iterations: usize) -> PyResult<Bound<'py, PyDict>> {
        if !(tolerance.is_finite() && tolerance > 0.0) {
            return Err(PyValueError::new_err(format!("tolerance must be a finite positive number, got {tolerance}")));
        }
        let s = &mut self.inner;
        let opts = StaticOptions { tolerance, max_iterations };
        let eq = py.detach(|| solve_equilibrium(&s.model, &s.state, &[], &opts)).map_err(|e| strand_err("static equilibrium", e))?;
        s.state.q = eq.q;
        s.state.qdot.fill(0.0);
        let d = PyDict::new(py);
        d.set_item("iterations", eq.iterations)?;
        d.set_item("stable", eq.stable)?;
        d.set_item("potential", eq.potential)?;
        Ok(d)
    }

    /// Advances ``steps`` time steps of ``dt`` seconds (default 1 ms) with the strand's integrator, under
    /// gravity, air drag and internal damping. The GIL is released meanwhile and Ctrl-C stops the run between
    /// steps (raising ``KeyboardInterrupt``; the state is that of the last completed step). A failed step
    /// (non-finite state) raises ``coiffure.SimulationError`` and keeps the previous state.
    #[pyo3(signature = (dt = 1e-3, steps = 1))]
    fn step(&mut self, py: Python<'_>, dt: f64, steps: u64) -> PyResult<()> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(PyValueError::new_err(format!("dt must be a finite positive time step in s, got {dt}")));
        }
        let s = &mut self.inner;
        let (result, watch) = py.detach(|| {
            let mut watch = Watch::default();
            for n in 0..steps {
                if let Err(e) = s.step(dt, &[]) {
                    return (Err((n, e)), watch);
                }
                if watch.stop() {
                    break;
                }
            }
            (Ok(()), watch)
        });
        if let Err((n, e)) = result {
            return Err(strand_err(&format!("step {n} (t = {} s)", s.state.time), e));
        }
        match watch.error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// The centreline at ``samples`` points evenly spaced in arc length from root to tip, m: an array of
    /// shape (samples, 3). (Arc lengths: ``numpy.linspace(0, strand.length, samples)``.)
    #[pyo3(signature = (samples = 17))]
    fn centerline<'py>(&self, py: Python<'py>, samples: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        if samples < 2 {
            return Err(PyValueError::new_err(format!("samples must be at least 2, got {samples}")));
        }
        let pts = centerline(&self.inner.model, &self.inner.state, samples);
        let flat: Vec<f64> = pts.iter().flat_map(|(_, x)| [x.x, x.y, x.z]).collect();
        let a = Array2::from_shape_vec((samples, 3), flat).expect("samples x 3 values");
        Ok(a.into_pyarray(py))
    }

    /// Natural angular frequencies of small oscillations about the current state (which should be an
    /// equilibrium: call ``solve_static()`` first), rad/s, ascending; the ``k`` lowest (all if None).
    /// Modes of an unstable equilibrium are negative numbers ``-sqrt(|lambda|)``.
    #[pyo3(signature = (k = None))]
    fn natural_frequencies<'py>(&self, py: Python<'py>, k: Option<usize>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let s = &self.inner;
        let mut w = py.detach(|| natural_frequencies(&s.model, &s.state)).map_err(|e| strand_err("natural frequencies", e))?;
        if let Some(k) = k {
            w.truncate(k);
        }
        Ok(w.into_pyarray(py))
    }

    /// Generalized coordinates, rad/m: per segment (twist, bend[, bend2]); length 2N (reduced) or 3N (full).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.state.q.as_slice().to_vec().into_pyarray(py)
    }

    #[setter]
    fn set_q(&mut self, value: Vec<f64>) -> PyResult<()> {
        self.inner.state.q = vector(value, self.inner.model.dofs(), "q")?;
        Ok(())
    }

    /// Their time derivatives, rad/(m s).
    #[getter]
    fn qdot<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.state.qdot.as_slice().to_vec().into_pyarray(py)
    }

    #[setter]
    fn set_qdot(&mut self, value: Vec<f64>) -> PyResult<()> {
        self.inner.state.qdot = vector(value, self.inner.model.dofs(), "qdot")?;
        Ok(())
    }

    /// Rest coordinates, rad/m (same layout as ``q``).
    #[getter]
    fn q_rest<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.inner.model.rest_coordinates().as_slice().to_vec().into_pyarray(py)
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.inner.state.time
    }

    /// "reduced" or "full".
    #[getter]
    fn model(&self) -> &'static str {
        name_of(self.inner.model.kind)
    }

    /// Strand length, m.
    #[getter]
    fn length(&self) -> f64 {
        self.inner.model.length
    }

    /// Number of helical segments N.
    #[getter]
    fn segments(&self) -> usize {
        self.inner.model.segments
    }

    /// Number of generalized coordinates (2N or 3N).
    #[getter]
    fn dofs(&self) -> usize {
        self.inner.model.dofs()
    }

    /// Mass, kg.
    #[getter]
    fn mass(&self) -> f64 {
        self.inner.model.mass()
    }

    /// Tip position, m (array of 3).
    #[getter]
    fn tip<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p = segment_frames(&self.inner.model, &self.inner.state)[self.inner.model.segments].position;
        vec![p.x, p.y, p.z].into_pyarray(py)
    }

    /// Root position, m (array of 3).
    #[getter]
    fn root<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let p = self.inner.state.root.position;
        vec![p.x, p.y, p.z].into_pyarray(py)
    }

    /// Steps whose velocities the safety net scaled down (a segment may turn at most 0.5 rad per step).
    #[getter]
    fn clamped_steps(&self) -> u64 {
        self.inner.clamped_steps
    }

    /// Time integrator of ``step``: "euler" (linearly implicit Euler, the default) or "midpoint" (implicit
    /// midpoint, no numerical dissipation).
    #[getter]
    fn integrator(&self) -> &'static str {
        match self.inner.integrator {
            Integrator::LinearlyImplicitEuler => "euler",
            Integrator::ImplicitMidpoint => "midpoint",
        }
    }

    #[setter]
    fn set_integrator(&mut self, name: &str) -> PyResult<()> {
        self.inner.integrator = match name {
            "euler" => Integrator::LinearlyImplicitEuler,
            "midpoint" => Integrator::ImplicitMidpoint,
            other => return Err(PyValueError::new_err(format!("integrator must be \"euler\" or \"midpoint\", got {other:?}"))),
        };
        Ok(())
    }

    /// Total energy (kinetic + gravity + elastic) at the current state, J.
    fn energy(&mut self) -> f64 {
        self.inner.energy()
    }

    /// Back to the rest shape, at rest, at time 0 (same root).
    fn reset(&mut self) {
        let root = self.inner.state.root.clone();
        self.inner.state = StrandState::at_rest(&self.inner.model, root);
        self.inner.clamped_steps = 0;
    }

    /// An independent copy (model and state).
    fn copy(&self) -> Self {
        Self { inner: self.inner.clone() }
    }

    fn __repr__(&self) -> String {
        let m = &self.inner.model;
        format!("<coiffure.Strand {} model, {} segments, length {} m, t = {} s>", name_of(m.kind), m.segments, m.length, self.inner.state.time)
    }
}
