//! # Coiffure hairstyles
//!
//! Reading and writing hair as sets of polyline strands ([`formats`]): Cem Yuksel's `.hair`,
//! USC-HairSalon `.data`, AMD TressFX 4 `.tfx` and USD `BasisCurves` (`.usda` text).
//! Positions in files are kept in the file's own units (see [`formats::HairCurves`]).
//!
//! The built-in head, neck and shoulders with its scalp ([`head`]) and hairstyle generation
//! ([`generate`]): guide Super-Helices and render strands bound to them, in SI units (m) in the
//! head frame (origin at the head's centre, z up, y forward).

#![warn(missing_docs)]

pub mod formats;
pub mod generate;
pub mod head;

pub use formats::{info, read_file, write_file, FormatError, HairCurves};
pub use generate::{Curl, GenerateError, Guide, Hairstyle, HairstyleParams, RenderStrands};
pub use head::{Head, HeadError, HeadMesh, HeadParams, ScalpPoint};
