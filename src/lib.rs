//! # hmdist
//!
//! Harmonic mean distance (HMD) images of triangle-mesh scenes, and the accuracy and cost of
//! the estimators compared by Cha & Ihm (2010). For a surface point `x`, H is the harmonic
//! mean of the distances from `x` to the surfaces it sees over its hemisphere,
//! `H = N / Σ 1/dᵢ`; it sets record spacing in irradiance and radiance caching and drives
//! ambient occlusion.
//!
//! The pipeline, one module per stage: [`scene`] (loading, built-in scenes, camera, light)
//! → [`accel`] (watertight ray casting over a BVH) → [`estimators`] (`gather`, `cubemap`,
//! `photon1`, `photon2`, behind one interface and a registry) → [`render`] (the driver that
//! owns the pixel loop) → [`image`] (EXR, PNG) and [`report`] (the JSON sidecar) →
//! [`metrics`] (`f_diff`) → `experiments` (the paper's tables and figures). [`points`]
//! gives H at points the caller chooses rather than at pixels; `gpu` casts rays on a GPU.
//! Long work stops early when [`interrupt::request`] is called (the CLI: on Ctrl-C or
//! SIGTERM), and requests that cannot fit in memory are refused before they allocate
//! ([`memory`]).
//!
//! ## Conventions
//!
//! - Distances are in scene units; `l_diag` is the diagonal of the scene's bounding box and
//!   every sample distance is clamped below at `d_min = 1e-6 · l_diag`.
//! - Surfaces are two-sided: a pixel's normal is flipped to face the camera; a point given to
//!   [`points::hmd_at`] is gathered over the hemisphere its normal points into.
//! - In an image, H is NaN for background pixels (and for photon-map holes) and `+inf` where
//!   every ray escaped.
//! - Same scene, camera, method, parameters and seed: the same bits, whatever the thread
//!   count.
//!
//! ## Example
//!
//! Inside a closed sphere of radius R, every point has H = R under cosine weighting
//! (spec §1), so the mean of R/H over an image is 1:
//!
//! ```
//! use hmdist::estimators::Gather;
//! use hmdist::progress::Silent;
//! use hmdist::render::{render, RenderOptions};
//! use hmdist::sampling::Weighting;
//! use hmdist::scene::procedural::validation;
//!
//! let r = validation::SPHERE_RADIUS;
//! let scene = validation::sphere(r, 6);
//! let gather = Gather::new(256, Weighting::Cosine)?;
//! let options = RenderOptions { width: 16, height: 16, ..RenderOptions::default() };
//! let rendered = render(&scene, &gather, &options, &Silent)?;
//!
//! let h = &rendered.image.data;
//! let mean_r_over_h = h.iter().map(|&h| (r / h) as f64).sum::<f64>() / h.len() as f64;
//! assert!((mean_r_over_h - 1.0).abs() < 0.02, "mean R/H = {mean_r_over_h}");
//! assert_eq!(rendered.report.escaped_rays, Some(0));
//! # Ok::<(), hmdist::error::Error>(())
//! ```
//!
//! ## Features
//!
//! `cli` (clap, indicatif: the `hmdist` program), `gpu` (wgpu: gather's and the cube map's GPU backends, [`gpu`])
//! and `experiments` (plotters: the paper's analysis) are on by default; a library user can
//! leave them out with `default-features = false`.

#![warn(missing_docs)]

pub mod accel;
pub mod backend;
pub mod cache;
pub mod denoise;
pub mod error;
pub mod estimators;
#[cfg(feature = "experiments")]
pub mod experiments;
pub mod files;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod image;
pub mod interrupt;
pub mod memory;
pub mod metrics;
pub mod options;
pub mod points;
pub mod progress;
pub mod render;
pub mod report;
pub mod sampling;
pub mod scene;
pub mod shard;
pub mod sincos;

/// The README's Rust examples, run as doctests so that they stay true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeExamples;

/// The guide's Rust examples (docs/guide.md: the library), run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../docs/guide.md")]
struct GuideExamples;
