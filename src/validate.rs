//! How settings refuse what is out of range: one sentence that names the settings struct's
//! field, the value given and the range allowed, as Mitsuba's plugins do. Every settings
//! struct's `validate()` is made of these, and every entry point (bake, render, compare)
//! calls it before any work, so a bad value is never clamped into a good one silently.

use crate::error::{Error, Result};
use std::fmt::Display;

/// Refuse `value` of field `field` of `settings` (the struct's name) unless `ok`; `allowed`
/// says what the field accepts ("at least 1", "in [0, 1)").
pub(crate) fn require(
    ok: bool,
    settings: &str,
    field: &str,
    value: impl Display,
    allowed: &str,
) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidSetting(format!(
            "{settings}.{field} is {value}; it must be {allowed}"
        )))
    }
}

/// Whether `x` is a finite number in [lo, hi) (`hi` excluded) or [lo, hi] (`hi_included`).
pub(crate) fn in_range(x: f32, lo: f32, hi: f32, hi_included: bool) -> bool {
    x.is_finite() && x >= lo && (x < hi || (hi_included && x == hi))
}

/// Refuse a `max_depth` (Mitsuba's: path segments) other than −1 (unlimited) or a count from 1.
pub(crate) fn require_max_depth(settings: &str, max_depth: i32) -> Result<()> {
    require(
        max_depth == -1 || max_depth >= 1,
        settings,
        "max_depth",
        max_depth,
        "-1 (unlimited) or at least 1",
    )
}

/// Refuse a count of `field` below 1.
pub(crate) fn require_positive(settings: &str, field: &str, value: u64) -> Result<()> {
    require(value >= 1, settings, field, value, "at least 1")
}
