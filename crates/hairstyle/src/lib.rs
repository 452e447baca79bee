//! # Coiffure hairstyles
//!
//! Reading and writing hair as sets of polyline strands ([`formats`]): Cem Yuksel's `.hair`,
//! USC-HairSalon `.data`, AMD TressFX 4 `.tfx` and USD `BasisCurves` (`.usda` text).
//! No physics here; positions are kept in the file's own units (see [`formats::HairCurves`]).

#![warn(missing_docs)]

pub mod cut;
pub mod formats;

pub use formats::{info, read_file, write_file, FormatError, HairCurves};
