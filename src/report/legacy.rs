//! The parameters as reports and keys held them before they were an object of their own:
//! their fields at the report's top level, in groups with names of their own (K was `gather`),
//! with values the report now leaves out (`strata`, `normal_filter_cos`, `rays_per_round`).
//! Kept, frozen, for two readers only: [`super::RenderReport::read`] takes a report written
//! then, and the experiment cache finds the images it keyed then (a key is a hash of this
//! serialisation, so its fields, their order and their omissions must not change). A field
//! means what its namesake in today's parameter structs (`GatherParams`, ...) means.
#![allow(missing_docs)]

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::backend::GpuFill;
use crate::sampling::{Sampler, Weighting};

/// A method's parameters as earlier reports wrote them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FlatParameters {
    /// Gather rays per pixel N.
    pub rays: Option<u32>,
    /// `gather`, `cubemap` and `adaptive`.
    #[serde(flatten)]
    pub gather: Option<GatherGroup>,
    /// `cubemap`.
    #[serde(flatten)]
    pub cubemap: Option<CubemapGroup>,
    /// `photon1` and `photon2`.
    #[serde(flatten)]
    pub photon: Option<PhotonGroup>,
    /// `adaptive`.
    #[serde(flatten)]
    pub adaptive: Option<AdaptiveGroup>,
}

/// The gather directions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GatherGroup {
    pub weighting: Weighting,
    /// The stratification grid `a × b` of one round.
    pub strata: [u32; 2],
    pub rounds: u32,
    #[serde(default = "Sampler::unnamed", skip_serializing_if = "Sampler::is_grid")]
    pub sampler: Sampler,
}

/// The hemicube.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CubemapGroup {
    pub cube_res: u32,
    #[serde(default, skip_serializing_if = "GpuFill::is_raster")]
    pub gpu_fill: GpuFill,
}

/// The photon map and its gather.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhotonGroup {
    pub photons: usize,
    /// K, now `nearest`.
    pub gather: usize,
    pub source: String,
    pub max_bounces: u32,
    pub absorption: f32,
    pub max_radius: Option<f32>,
    pub normal_filter_cos: f32,
}

/// When adaptive gathering stops.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveGroup {
    pub tolerance: f32,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub abs_tolerance: f32,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub loosen: f32,
    pub min_rays: u32,
    pub max_rays: u32,
    pub rays_per_round: u32,
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}

impl FlatParameters {
    /// Whether any group is here: a report written before the parameters were an object.
    pub fn is_some(&self) -> bool {
        self.gather.is_some() || self.cubemap.is_some() || self.photon.is_some() || self.adaptive.is_some()
    }

    /// The parameters of method `method` by today's names: each field its parameter struct
    /// has, with the values written then (K as `nearest`); the derived values dropped.
    pub fn fields(&self, method: &str) -> BTreeMap<String, Value> {
        let mut fields = BTreeMap::new();
        let mut put = |name: &str, value: Value| {
            fields.insert(name.to_string(), value);
        };
        if let Some(rays) = self.rays {
            put("rays", rays.into());
        }
        if let Some(g) = &self.gather {
            put("weighting", json(&g.weighting));
            if method == "gather" {
                put("rounds", g.rounds.into());
            }
            if method != "cubemap" {
                put("sampler", json(&g.sampler));
            }
        }
        if let Some(c) = &self.cubemap {
            put("cube_res", c.cube_res.into());
            put("gpu_fill", json(&c.gpu_fill));
        }
        if let Some(p) = &self.photon {
            put("photons", p.photons.into());
            put("nearest", p.gather.into());
            put("source", json(&p.source));
            put("max_bounces", p.max_bounces.into());
            put("absorption", json(&p.absorption));
            put("max_radius", json(&p.max_radius));
        }
        if let Some(a) = &self.adaptive {
            put("tolerance", json(&a.tolerance));
            put("abs_tolerance", json(&a.abs_tolerance));
            put("loosen", json(&a.loosen));
            put("min_rays", a.min_rays.into());
            put("max_rays", a.max_rays.into());
        }
        fields
    }
}

/// A parameter's value as JSON.
fn json(value: &impl Serialize) -> Value {
    serde_json::to_value(value).expect("a parameter serialises")
}
