//! The irradiance cache (Ward 1988) that H exists to space: records of one-bounce irradiance
//! ([`crate::estimators::irradiance`]) placed coarse to fine over an image's primary hits,
//! each holding for a radius from H (any estimator's, or the records' own rays') or from a
//! renderer's rule (pbrt-v2's, Mitsuba's), and every pixel's E interpolated from the records
//! that cover it: so that an estimator of H is judged by the cache it makes.
//!
//! `records.rs` holds the records, Ward's weight and the grids that find them; `spacing.rs`
//! where a radius comes from; `gradients.rs` Ward and Heckbert's gradients of a record;
//! `neighbours.rs` Křivánek's neighbour clamping; `params.rs` what a cache is built
//! with; `build.rs` the placement and the interpolation; `report.rs` the report and the error against a reference.

mod build;
mod gradients;
mod neighbours;
mod params;
mod records;
mod report;
mod spacing;

pub use build::{cache, top_stride, Cached};
pub use gradients::Gradients;
pub use params::{CacheParams, DEFAULT_ACCURACY};
pub use records::{interpolate, Record};
pub use report::{relative_errors, CacheErrors, CacheReport, CacheSeconds, Level};
pub use spacing::{Range, Spacing};
