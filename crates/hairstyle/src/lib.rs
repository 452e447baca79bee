//! # Coiffure hairstyles
//!
//! Reading and writing hair as sets of polyline strands ([`formats`]): Cem Yuksel's `.hair`,
//! USC-HairSalon `.data`, AMD TressFX 4 `.tfx` and USD `BasisCurves` (`.usda` text).
//! Positions in files are kept in the file's own units (see [`formats::HairCurves`]).
//!
//! The built-in head, neck and shoulders with its scalp ([`head`]) and hairstyle generation
//! ([`generate`]): guide Super-Helices and render strands bound to them ([`render`]), in SI units (m) in the
//! head frame (origin at the head's centre, z up, y forward); the lattice that carries a
//! hairstyle ([`global`]). Hairstyles from other tools are placed on the head by [`fit`].

#![warn(missing_docs)]

pub mod cut;
pub mod error;
pub mod fit;
pub mod fitted;
pub mod follow;
pub mod formats;
pub mod generate;
pub mod global;
pub mod groom;
pub mod head;
pub mod limits;
pub mod params;
pub mod render;

pub use formats::{info, read_file, write_file, FormatError, HairCurves};
pub use generate::{Curl, GenerateError, Guide, Hairstyle, HairstyleParams, RenderStrands};
pub use global::{body_in_world, HairLattice};
pub use head::{Head, HeadError, HeadMesh, HeadParams, ScalpPoint};
pub use limits::LoadLimits;
