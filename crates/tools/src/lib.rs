//! # Coiffure tools: shapes, tool-strand collision and contact
//!
//! Tools (comb, brush, finger, clip, ...) are sets of capsules and spheres described in data
//! ([`shape`]). Collision with strands goes through an AABB tree over the strands' centreline pieces
//! ([`bvh`]) and closest-point tests between capsule axes and pieces ([`geometry`], [`contact`]).
//! Physics only: no threads, no I/O beyond parsing a shape's text. SI units (m, s, N).

pub mod bvh;
pub mod contact;
pub mod geometry;
pub mod interaction;
pub mod shape;
