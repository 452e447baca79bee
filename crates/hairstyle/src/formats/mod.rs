//! Hair file formats and their common in-memory type, [`HairCurves`].
//!
//! One module per format, each with a byte-level `read(&[u8])` and `write(&HairCurves) -> Vec<u8>`
//! (the writer returns `Result` because some data cannot be written to some formats):
//! [`hair`] (Cem Yuksel's `.hair`), [`usc`] (USC-HairSalon `.data`), [`tfx`] (AMD TressFX 4
//! `.tfx`) and [`usda`] (USD `BasisCurves` text). [`read_file`] and [`write_file`] choose the
//! format from the file extension.
//!
//! Readers are all-or-nothing: a malformed or truncated file gives an [`FormatError`] naming the
//! byte offset (binary formats) or line (text) and what was expected, never partially loaded data.
//! Counts read from a header are checked against the file size before anything is allocated.

use std::path::{Path, PathBuf};

pub(crate) use bytes::{put_f32, put_u32, Cursor};

mod atomic;
pub mod bytes;
pub mod hair;
pub mod tfx;
pub mod usc;
pub mod usda;

pub use atomic::write_atomic;

/// A set of hair strands as polylines, with optional per-vertex attributes.
///
/// Units: positions are kept in the file's own units, unconverted (Coiffure works in metres, so
/// files in other units, e.g. centimetres, must be scaled by the caller). Thickness is a diameter
/// in the same units as the positions. Per-vertex attributes are flat, in strand order (all the
/// vertices of strand 0, then strand 1, ...), and, when present, hold exactly one value per vertex.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HairCurves {
    /// Strands, each a polyline of vertex positions (root first), in file units.
    pub strands: Vec<Vec<[f32; 3]>>,
    /// Per-vertex thickness (diameter, file units), if the file carries one.
    pub thickness: Option<Vec<f32>>,
    /// Per-vertex transparency (0 = opaque, 1 = invisible), if the file carries one.
    pub transparency: Option<Vec<f32>>,
    /// Per-vertex colour (linear RGB, 0 to 1), if the file carries one.
    pub color: Option<Vec<[f32; 3]>>,
}

impl HairCurves {
    /// Strands only, no attributes.
    pub fn from_strands(strands: Vec<Vec<[f32; 3]>>) -> Self {
        Self {
            strands,
            ..Self::default()
        }
    }

    /// Total number of vertices over all strands.
    pub fn num_points(&self) -> usize {
        self.strands.iter().map(Vec::len).sum()
    }

    /// Check that every per-vertex attribute present has one value per vertex.
    /// `format` names the format being written, for the error.
    pub fn check_attributes(&self, format: &'static str) -> Result<(), FormatError> {
        let n = self.num_points();
        let lens = [
            ("thickness", self.thickness.as_ref().map(Vec::len)),
            ("transparency", self.transparency.as_ref().map(Vec::len)),
            ("color", self.color.as_ref().map(Vec::len)),
        ];
        for (name, len) in lens {
            if let Some(len) = len.filter(|&l| l != n) {
                return Err(FormatError::Unwritable {
                    format,
                    reason: format!("{name} has {len} values for {n} vertices"),
                });
            }
        }
        Ok(())
    }
}

/// What can go wrong reading or writing a hair file.
#[derive(Debug, thiserror::Error)]
pub enum FormatError {
    /// A binary file is malformed or truncated at `offset` (bytes from the file start).
    #[error("{format} file, byte {offset}: expected {expected}")]
    Binary {
        /// Format name, e.g. ".hair".
        format: &'static str,
        /// Byte offset from the start of the file where the problem is.
        offset: u64,
        /// What was expected there (and what was found, when useful).
        expected: String,
    },
    /// A text file is malformed at `line` (1-based).
    #[error("{format} file, line {line}: {message}")]
    Text {
        /// Format name, e.g. ".usda".
        format: &'static str,
        /// 1-based line number.
        line: usize,
        /// What was expected and what was found.
        message: String,
    },
    /// The data cannot be written in this format (e.g. unequal strands for `.tfx`).
    #[error("cannot write {format} file: {reason}")]
    Unwritable {
        /// Format name.
        format: &'static str,
        /// Why.
        reason: String,
    },
    /// The file extension is not one of `.hair`, `.data`, `.tfx`, `.usda` (or `.usd` holding text).
    #[error("{0}: unknown hair file extension (expected .hair, .data, .tfx or .usda)")]
    UnknownExtension(PathBuf),
    /// Binary (`.usdc`, crate) or zipped (`.usdz`) USD, which this build cannot read.
    #[error("{what}: binary (.usdc) and zipped (.usdz) USD cannot be read: no maintained Rust USD library builds with this toolchain (the `openusd` crate needs rustc 1.96); convert it to text with Pixar's `usdcat FILE -o FILE.usda` (`pip install usd-core`) and load the .usda")]
    UnsupportedUsd {
        /// The file (or "the data" when read from bytes).
        what: String,
    },
    /// Reading or writing the file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// The formats, as chosen by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Cem Yuksel's `.hair`.
    Hair,
    /// USC-HairSalon `.data`.
    Usc,
    /// AMD TressFX 4 `.tfx`.
    Tfx,
    /// USD `BasisCurves` text, `.usda`.
    Usda,
}

impl Format {
    /// The format for a path's extension (case-insensitive), if known.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "hair" => Some(Format::Hair),
            "data" => Some(Format::Usc),
            "tfx" => Some(Format::Tfx),
            "usda" | "usd" => Some(Format::Usda),
            _ => None,
        }
    }

    /// Parse bytes in this format.
    pub fn read(self, bytes: &[u8]) -> Result<HairCurves, FormatError> {
        match self {
            Format::Hair => hair::read(bytes),
            Format::Usc => usc::read(bytes),
            Format::Tfx => tfx::read(bytes),
            Format::Usda => usda::read(bytes),
        }
    }

    /// Parse bytes in this format, with the metadata the format carries (USD: `metersPerUnit`,
    /// `upAxis`; the other formats carry none).
    pub fn read_with_metadata(self, bytes: &[u8]) -> Result<(HairCurves, Metadata), FormatError> {
        match self {
            Format::Usda => usda::read_stage(bytes),
            f => f.read(bytes).map(|c| (c, Metadata::default())),
        }
    }

    /// Serialise curves in this format.
    pub fn write(self, curves: &HairCurves) -> Result<Vec<u8>, FormatError> {
        match self {
            Format::Hair => hair::write(curves),
            Format::Usc => usc::write(curves),
            Format::Tfx => tfx::write(curves),
            Format::Usda => usda::write(curves),
        }
    }
}

/// Read a hair file, choosing the format from its extension.
pub fn read_file(path: impl AsRef<Path>) -> Result<HairCurves, FormatError> {
    read_file_with_metadata(path).map(|r| r.0)
}

/// What a file says about its own frame, where the format can say it (USD's stage metadata);
/// None where it does not.
pub type Metadata = usda::StageMetadata;

/// Read a hair file, choosing the format from its extension; also its format and authored
/// metadata (units, up axis). `.usdc` and `.usdz` give [`FormatError::UnsupportedUsd`].
pub fn read_file_with_metadata(
    path: impl AsRef<Path>,
) -> Result<(HairCurves, Format, Metadata), FormatError> {
    let path = path.as_ref();
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if matches!(ext.as_deref(), Some("usdc" | "usdz")) {
        return Err(FormatError::UnsupportedUsd { what: path.display().to_string() });
    }
    let format =
        Format::from_path(path).ok_or_else(|| FormatError::UnknownExtension(path.into()))?;
    let bytes = std::fs::read(path).map_err(|source| FormatError::Io {
        path: path.into(),
        source,
    })?;
    let (curves, meta) = format.read_with_metadata(&bytes).map_err(|e| match e {
        FormatError::UnsupportedUsd { .. } => FormatError::UnsupportedUsd { what: path.display().to_string() },
        e => e,
    })?;
    Ok((curves, format, meta))
}

/// Write a hair file, choosing the format from its extension. Nothing is written on error, and the file is
/// replaced whole ([`write_atomic`]).
pub fn write_file(path: impl AsRef<Path>, curves: &HairCurves) -> Result<(), FormatError> {
    let path = path.as_ref();
    let format =
        Format::from_path(path).ok_or_else(|| FormatError::UnknownExtension(path.into()))?;
    let bytes = format.write(curves)?;
    write_atomic(path, &bytes).map_err(|source| FormatError::Io {
        path: path.into(),
        source,
    })
}

/// Summary for `coiffure info FILE`: (number of strands, number of vertices, bounding box min,
/// bounding box max), bounds in file units. With no vertices the bounds are both `[0, 0, 0]`.
pub fn info(curves: &HairCurves) -> (usize, usize, [f32; 3], [f32; 3]) {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in curves.strands.iter().flatten() {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    let n = curves.num_points();
    if n == 0 {
        (min, max) = ([0.0; 3], [0.0; 3]);
    }
    (curves.strands.len(), n, min, max)
}
