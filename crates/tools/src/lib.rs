//! # Coiffure tools: shapes, tool-strand collision and contact, wetness and the global tools
//!
//! Tools (comb, brush, finger, clip, ...) are sets of capsules and spheres described in data
//! ([`shape`]). Collision with strands goes through an AABB tree over the strands' centreline pieces
//! ([`bvh`]) and closest-point tests between capsule axes and pieces ([`geometry`], [`contact`]); contact
//! between the strands themselves goes through a sweep and prune ([`hair_contact`]); a tooth passing through a
//! wisp drags against the fibres it parts ([`entanglement`]).
//! Wetness and what it does to the fibre ([`wetness`]); the hair's surface treatment ([`treatment`]); the hair dryer ([`dryer`]) and the water
//! sprayer ([`sprayer`]), cones of influence that blow and change wetness.
//! Physics only: no threads, no I/O beyond parsing a shape's text. SI units (m, s, N).

pub mod bvh;
pub mod contact;
pub mod cushion;
pub mod dryer;
pub mod entanglement;
pub mod geometry;
pub mod hair_contact;
pub mod interaction;
pub mod segments4;
pub mod shape;
pub mod sprayer;
pub mod sweep;
pub mod treatment;
pub mod wetness;
