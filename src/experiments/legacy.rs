//! The cache keys of earlier versions, read only, so that a cache on disk stays usable: an
//! image cached under one is renamed to today's key ([`Runner::stem`]) when first asked for.
//! Two came before today's:
//! - the first stem: a hash of the scene's key, the method, its parameters, the size, the
//!   seed, the backend as requested and the AOVs;
//! - the first [`RenderKey`] digest, whose parameters were flat fields of the key
//!   ([`FlatParameters`], K named `gather`, with the derived strata).
//!
//! Both hash the parameters as those versions serialised them, which [`flat_parameters`]
//! rebuilds from the estimator's parameter struct.

use serde::Serialize;

use crate::estimators::adaptive::FIRST_ROUNDS;
use crate::estimators::photon::{PhotonMethod, NORMAL_FILTER_COS};
use crate::estimators::{AdaptiveParams, CubemapParams, Estimator, GatherParams, PhotonParams};
use crate::report::legacy::{AdaptiveGroup, CubemapGroup, FlatParameters, GatherGroup, PhotonGroup};
use crate::report::RenderKey;
use crate::sampling::{strata, Sampler, Weighting};
use crate::scene::stable_hash;

use super::runner::Runner;

impl Runner<'_> {
    /// The stems earlier versions gave the image that `key` (today's, for `estimator`) names,
    /// oldest first.
    pub(super) fn legacy_stems(&self, estimator: &dyn Estimator, key: &RenderKey) -> [String; 2] {
        let method = estimator.method();
        let parameters = flat_parameters(estimator);
        let size = self.params.size;
        let mut first = format!(
            "{}|{method}|{}|{size}x{size}|{}|{:?}",
            self.scene_key,
            serde_json::to_string(&parameters).expect("parameters serialise"),
            key.seed,
            self.backend,
        );
        for aov in &key.aovs {
            first += &format!("|{aov}");
        }
        let digest = FlatKey::from((key, parameters)).digest();
        [
            format!("{method}-{:016x}", stable_hash(first.as_bytes())),
            format!("{method}-{digest:016x}"),
        ]
    }
}

/// [`RenderKey`] as its first version serialised it: the parameters flat among its fields.
#[derive(Serialize)]
struct FlatKey<'a> {
    hmdist_version: &'a str,
    scene: &'a str,
    scene_content: &'a str,
    method: &'a str,
    #[serde(flatten)]
    parameters: FlatParameters,
    backend: &'a str,
    adapter_class: &'a Option<String>,
    bvh: &'a str,
    width: u32,
    height: u32,
    seed: u64,
    max_distance: Option<f32>,
    aovs: &'a [String],
    ao_radius: Option<f32>,
}

impl FlatKey<'_> {
    fn digest(self) -> u64 {
        stable_hash(serde_json::to_string(&self).expect("a key serialises").as_bytes())
    }
}

impl<'a> From<(&'a RenderKey, FlatParameters)> for FlatKey<'a> {
    fn from((key, parameters): (&'a RenderKey, FlatParameters)) -> Self {
        FlatKey {
            hmdist_version: &key.hmdist_version,
            scene: &key.scene,
            scene_content: &key.scene_content,
            method: &key.method,
            parameters,
            backend: &key.backend,
            adapter_class: &key.adapter_class,
            bvh: &key.bvh,
            width: key.width,
            height: key.height,
            seed: key.seed,
            max_distance: key.max_distance,
            aovs: &key.aovs,
            ao_radius: key.ao_radius,
        }
    }
}

/// `estimator`'s parameters as reports wrote them before they were an object of their own.
pub(super) fn flat_parameters(estimator: &dyn Estimator) -> FlatParameters {
    let parameters = estimator.parameters();
    let directions = |weighting: Weighting, rays: u32, rounds: u32, sampler: Sampler| {
        let (a, b) = strata(rays / rounds);
        Some(GatherGroup {
            weighting,
            strata: [a, b],
            rounds,
            sampler,
        })
    };
    let method = estimator.method();
    if let Some(g) = parameters.typed::<GatherParams>().filter(|_| method == "gather") {
        let rounds = g.rounds.unwrap_or(1);
        return FlatParameters {
            rays: Some(g.rays),
            gather: directions(g.weighting, g.rays, rounds, g.sampler),
            ..FlatParameters::default()
        };
    }
    if let Some(c) = parameters
        .typed::<CubemapParams>()
        .filter(|_| method == "cubemap")
    {
        return FlatParameters {
            rays: Some(c.rays),
            gather: directions(c.weighting, c.rays, 1, Sampler::Grid),
            cubemap: Some(CubemapGroup {
                cube_res: c.cube_res,
                gpu_fill: c.gpu_fill,
            }),
            ..FlatParameters::default()
        };
    }
    if let Some(a) = parameters
        .typed::<AdaptiveParams>()
        .filter(|_| method == "adaptive")
    {
        let per_round = a.min_rays / FIRST_ROUNDS;
        return FlatParameters {
            rays: None,
            gather: directions(a.weighting, per_round, 1, a.sampler).map(|g| GatherGroup {
                rounds: FIRST_ROUNDS,
                ..g
            }),
            adaptive: Some(AdaptiveGroup {
                tolerance: a.tolerance,
                abs_tolerance: a.abs_tolerance,
                loosen: a.loosen,
                min_rays: a.min_rays,
                max_rays: a.max_rays,
                rays_per_round: per_round,
            }),
            ..FlatParameters::default()
        };
    }
    if let Some(p) = parameters
        .typed::<PhotonParams>()
        .filter(|_| PhotonMethod::from_name(method).is_some())
    {
        return FlatParameters {
            rays: None,
            photon: Some(PhotonGroup {
                photons: p.photons,
                gather: p.nearest,
                source: p.source.name().into(),
                max_bounces: p.max_bounces,
                absorption: p.absorption,
                max_radius: p.max_radius,
                normal_filter_cos: NORMAL_FILTER_COS,
            }),
            ..FlatParameters::default()
        };
    }
    FlatParameters::default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::{Aov, Backend};
    use crate::experiments::presets::Preset;
    use crate::progress::Silent;

    /// The stems of earlier versions, rebuilt from today's parameters, are the ones those
    /// versions gave: each expected pair below was printed by the version before the
    /// parameters became an object (`0f727e0`), for `slab` at 16² with the CPU backend. That
    /// version's default sampler was the grid, so the grid is named where it printed none.
    #[test]
    fn the_earlier_keys_are_rebuilt_as_those_versions_made_them() {
        let out = std::env::temp_dir().join(format!("hmdist-legacy-stems-{}", std::process::id()));
        let runner = Runner::new("slab", Preset::Quick, &out, &Silent)
            .unwrap()
            .with_size(Some(16))
            .unwrap()
            .with_backend(Backend::Cpu);
        let cases = [
            (
                "gather",
                r#"{"rays":8,"sampler":"grid"}"#,
                "gather-7eea6ad9ce8fbfcc",
                "gather-14598e0d36664d71",
            ),
            (
                "gather",
                r#"{"rays":64,"rounds":4,"sampler":"sobol","weighting":"uniform"}"#,
                "gather-e817e547323721db",
                "gather-d1a6de9ca86d3984",
            ),
            (
                "cubemap",
                r#"{"cube_res":16,"rays":32}"#,
                "cubemap-a635018e18319ea0",
                "cubemap-1b1482eac0b124e7",
            ),
            (
                "adaptive",
                r#"{"sampler":"grid"}"#,
                "adaptive-9afd917d46ac15d2",
                "adaptive-4fce40065ab3b5a9",
            ),
            (
                "adaptive",
                r#"{"abs_tolerance":0.001,"loosen":1.0,"sampler":"sobol","tolerance":0.1}"#,
                "adaptive-0f35bf11fb08868a",
                "adaptive-ccefe2a00d1aa181",
            ),
            (
                "photon1",
                r#"{"max_radius":0.5,"nearest":20,"photons":1000,"source":"camera"}"#,
                "photon1-cd5372b84bf3d8c2",
                "photon1-4498e953775a9c4b",
            ),
            (
                "photon2",
                r#"{}"#,
                "photon2-c9ff24f6c0803887",
                "photon2-efa56d0dd49ce4b0",
            ),
        ];
        for (method, params, first, digest) in cases {
            let aovs: &[Aov] = if method == "adaptive" { &[Aov::Rays] } else { &[] };
            // As the runner builds it, on its backend.
            let mut object: serde_json::Map<String, serde_json::Value> =
                serde_json::from_str(params).unwrap();
            let entry = crate::estimators::registry::method(method).unwrap();
            if entry.reads("backend") {
                object.insert("backend".into(), "cpu".into());
            }
            let estimator = entry.build(&object, aovs).unwrap();
            let key = runner.key(estimator.as_ref(), 1, aovs);
            assert_eq!(
                runner.legacy_stems(estimator.as_ref(), &key),
                [first, digest],
                "{method} {params}"
            );
        }
    }
}
