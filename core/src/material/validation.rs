//! Validation problems: every invalid field of a material is reported at once, each with the path of
//! the field (`color.stops[2].position`) and what is wrong with it.

use crate::microfacet::transfer::Curve;
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

/// A transfer curve's validation lives with the material's, which reports every field at once.
impl Curve {
    /// Record every problem: fewer than two points or more than [`Curve::MAX_POINTS`], values beyond ±[`Curve::MAX_F`] / ±[`Curve::MAX_G`]
    /// (or not finite), unsorted f.
    pub fn validate(&self, field: &str, problems: &mut Problems) {
        if self.points.len() < 2 {
            problems.push(
                format!("{field}.points"),
                "a transfer curve needs at least two points",
            );
        }
        if self.points.len() > Curve::MAX_POINTS {
            problems.push(
                format!("{field}.points"),
                format!(
                    "a transfer curve has at most {} points, got {}",
                    Curve::MAX_POINTS,
                    self.points.len()
                ),
            );
            return;
        }
        for (i, p) in self.points.iter().enumerate() {
            problems.in_range(
                &format!("{field}.points[{i}][0]"),
                p[0],
                -Curve::MAX_F,
                Curve::MAX_F,
            );
            problems.in_range(
                &format!("{field}.points[{i}][1]"),
                p[1],
                -Curve::MAX_G,
                Curve::MAX_G,
            );
        }
        for (i, w) in self.points.windows(2).enumerate() {
            let gap = w[1][0] - w[0][0];
            if gap < 0.0 {
                problems.push(
                    format!("{field}.points[{}][0]", i + 1),
                    format!(
                        "points must be sorted by f: {} comes after {}",
                        w[1][0], w[0][0]
                    ),
                );
            } else if gap > 0.0 && gap < Curve::MIN_GAP {
                // A near-vertical segment would have a slope beyond f64 (use equal f for a cliff).
                problems.push(
                    format!("{field}.points[{}][0]", i + 1),
                    format!(
                        "points closer than {} in f must be equal (a cliff): {} and {}",
                        Curve::MIN_GAP,
                        w[0][0],
                        w[1][0]
                    ),
                );
            }
        }
    }
}
