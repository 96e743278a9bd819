//! Validation problems: every invalid field of a material is reported at once, each with the path of
//! the field (`color.stops[2].position`) and what is wrong with it.

use std::fmt;

/// One invalid field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// Dotted path of the field, e.g. `heights.sigma_h` or `color.stops[3].position`.
    pub field: String,
    /// What is wrong, in words a user can act on.
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// Collects problems while walking a value.
#[derive(Debug, Default)]
pub struct Problems(pub Vec<Problem>);

impl Problems {
    /// Record a problem.
    pub fn push(&mut self, field: impl Into<String>, message: impl Into<String>) {
        self.0.push(Problem {
            field: field.into(),
            message: message.into(),
        });
    }

    /// `value` must be finite.
    pub fn finite(&mut self, field: &str, value: f64) {
        if !value.is_finite() {
            self.push(field, format!("must be a finite number, got {value}"));
        }
    }

    /// `value` must be finite and within `[lo, hi]`.
    pub fn in_range(&mut self, field: &str, value: f64, lo: f64, hi: f64) {
        if !value.is_finite() {
            self.push(field, format!("must be a finite number, got {value}"));
        } else if value < lo || value > hi {
            self.push(field, format!("must be in [{lo}, {hi}], got {value}"));
        }
    }
}
