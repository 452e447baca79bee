//! # Coiffure global layer: the lattice
//!
//! After Volino and Magnenat-Thalmann (2006): a regular lattice encloses the hairstyle and hair
//! follows the lattice by quadratic B-spline free-form deformation ([`ffd`]); the head, body and
//! tools are sets of metaballs that push lattice nodes out ([`metaball`]); the nodes are particles
//! joined by stiffeners and attached to the head, integrated implicitly ([`lattice`]; its sparse
//! linear algebra in `solver`, the step's cached factorisation and scratch in [`workspace`]). Hair cut by the
//! scissors falls as mass-spring clusters and comes to rest on the body ([`cluster`]).
//! Physics only: no threads, no I/O. SI units (m, kg, s, N), f64.

#![warn(missing_docs)]

pub mod cluster;
pub mod ffd;
pub mod lattice;
pub mod metaball;
pub mod model;
pub mod params;
pub mod sag_free;
mod solver;
pub mod workspace;
