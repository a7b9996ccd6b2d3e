//! The paper's analysis, reproduced on any scene (spec §4, §6): experiments that render with
//! several estimators and parameters, compare against a final-gathering reference, and write
//! CSV and Markdown tables and an HTML report.
//!
//! Every image an experiment needs is cached under `OUT/cache`, keyed by everything that
//! determines it (hmdist's version, the scene's content, method, parameters, size, seed), and
//! reused across experiments and reruns: an interrupted run resumes where it stopped. The
//! scene's content is its [`Scene::fingerprint`], so editing any file it was loaded from (a
//! TOML scene's meshes included) renders again.
//!
//! The experiments are listed once, in [`EXPERIMENTS`]: the ray studies (`rays.rs`: Tables
//! 1–2, Fig. 9), the photon studies (`photons.rs`: Tables 3–4, Fig. 10, 16/17, memory) and
//! the adaptive study (`adaptive.rs`: rays saved at equal f_diff), the irradiance-cache study
//! (`caches.rs`: what each source of H makes of the cache it spaces), and accuracy against
//! cost over them all (`cost.rs`).
//! The paper's published numbers are in [`paper`].
//!
//! The module is an index; its files point down: [`catalogue`] (the list, running it) above
//! the studies (`rays`, `photons`, `adaptive`, `caches`, `cost`) and the HTML report, above the
//! [`Runner`] (`runner.rs`, with `cache.rs`, `legacy.rs` (earlier versions' cache keys) and
//! `planning.rs`), above the vocabulary
//! ([`presets`], [`Section`], [`Table`], [`plan`], `plot`, `grid`, [`paper`]).

mod adaptive;
mod cache;
mod caches;
pub mod catalogue;
mod cost;
mod grid;
mod legacy;
pub mod paper;
mod photons;
pub mod plan;
mod planning;
pub mod plot;
pub mod presets;
mod rays;
mod report;
mod runner;
mod section;
pub mod table;

pub use catalogue::{select, Experiment, EXPERIMENTS};
pub use plan::Plan;
pub use presets::{Preset, PresetParams, PARTS, PART_RAYS, REFERENCE_SEED};
pub use runner::Runner;
pub use section::Section;
pub use table::Table;
