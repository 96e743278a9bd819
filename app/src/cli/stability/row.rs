//! A row of `lodestone stability`: which path it measured, its largest deviation against its
//! bound, and whether it passed.

use serde::Serialize;

/// Which implementation a row measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Path {
    /// lodestone-core, f64.
    CoreF64,
    /// lodestone-core's f32 mirror of the GPU code (`special_f32`).
    CoreF32,
    /// The WGSL on the GPU adapter.
    Wgsl,
}

impl Path {
    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::CoreF64 => "core f64",
            Self::CoreF32 => "core f32",
            Self::Wgsl => "wgsl",
        }
    }
}

/// One case through one path.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// What was run.
    pub case: String,
    /// Which implementation.
    pub path: Path,
    /// Outputs checked.
    pub outputs: usize,
    /// Largest deviation from the reference (see the module docs; 0 when the case has no reference).
    pub max_deviation: f64,
    /// The documented bound on `max_deviation`.
    pub bound: f64,
    /// Outputs that were NaN, infinite, or negative where they cannot be.
    pub non_finite: usize,
    /// The reference and the deviation's unit.
    pub reference: String,
}

impl Row {
    /// Whether the row is within its bound and all outputs are finite.
    pub fn passed(&self) -> bool {
        self.non_finite == 0 && self.max_deviation <= self.bound
    }
}

/// `|got − reference| / max(|reference|, floor)`; infinite when `got` is not finite and the
/// reference is.
pub fn deviation(got: f64, reference: f64, floor: f64) -> f64 {
    if !got.is_finite() {
        return if got == reference { 0.0 } else { f64::INFINITY };
    }
    (got - reference).abs() / reference.abs().max(floor)
}
