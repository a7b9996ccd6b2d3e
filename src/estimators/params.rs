//! What every method's parameter struct is ([`MethodParams`]): below both the estimators,
//! which each own one, and the registry, which builds estimators from them.

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::aov::Aov;
use crate::backend::{Backend, GpuFill};

/// With the `cli` feature, a method's parameters are also clap flags (derived on the struct).
#[cfg(feature = "cli")]
pub trait Flags: clap::Args + clap::FromArgMatches {}
#[cfg(feature = "cli")]
impl<T: clap::Args + clap::FromArgMatches> Flags for T {}
/// With the `cli` feature, a method's parameters are also clap flags (derived on the struct).
#[cfg(not(feature = "cli"))]
pub trait Flags {}
#[cfg(not(feature = "cli"))]
impl<T> Flags for T {}

/// A method's parameter struct: its fields are the method's parameters with serde's names
/// (Python's keywords, the JSON object's keys) and, with the `cli` feature, its flags; its
/// `Default` is the library's defaults, and `#[serde(default, deny_unknown_fields)]` lets an
/// object name any subset of the fields and nothing else.
pub trait MethodParams:
    Clone + Default + std::fmt::Debug + PartialEq + Serialize + DeserializeOwned + Flags + 'static
{
    /// Defaults that depend on the AOVs asked for (`gather`: 8 rounds where `relerr` is asked
    /// for and no rounds are named).
    fn for_aovs(&mut self, _aovs: &[Aov]) {}

    /// Where the method runs, for a method that has a backend (`gather`, `cubemap`); how the
    /// GPU fills a cube map's texels, for `cubemap`. The others ignore them.
    fn on_backend(&mut self, _backend: Backend, _gpu_fill: GpuFill) {}
}
