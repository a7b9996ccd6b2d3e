//! The registry of methods: one entry per estimator, with its name, a sentence on what it is,
//! the parameters it reads and its constructor. The CLI's `--method`, the experiments and the
//! Python package all build estimators from here; a new estimator is one new line.

use super::adaptive::{self, Adaptive};
use super::aov::Aov;
use super::cubemap::{self, Cubemap};
use super::gather::{self, Gather, DEFAULT_ERROR_ROUNDS};
use super::photon::{self, PathRules, PhotonEstimator, PhotonMethod, PhotonParams, SourceKind};
use super::Estimator;
use crate::backend::Backend;
use crate::error::{Error, Result};
use crate::sampling::Weighting;

/// Every method parameter, with the library's defaults; each method reads the ones its
/// [`MethodEntry::parameters`] names, and its constructor checks them. With the `cli`
/// feature these are also `hmdist render`'s flags (`rays` is `--rays`).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct MethodConfig {
    /// Gather rays per pixel N, for gather and cubemap (the paper's reference is 65536).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = gather::DEFAULT_RAYS))]
    pub rays: u32,
    /// Direction weighting over the hemisphere.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Weighting::Cosine))]
    pub weighting: Weighting,
    /// gather: cast the rays as R independent rounds (R divides N), for the relerr AOV
    /// [default: 1; 8 with --aov relerr].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "R", help_heading = "AOVs and adaptive")
    )]
    pub rounds: Option<u32>,
    /// Radius of the ao AOV [default: the median of the image's H; needed for adaptive].
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "R", help_heading = "AOVs and adaptive")
    )]
    pub ao_radius: Option<f32>,
    /// adaptive: a pixel stops once the relative standard error of its H is below T.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "T", default_value_t = adaptive::DEFAULT_TOLERANCE, help_heading = "AOVs and adaptive")
    )]
    pub tolerance: f32,
    /// adaptive: rays before the first check, as 8 rounds (a multiple of 8).
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "m", default_value_t = adaptive::DEFAULT_MIN_RAYS, help_heading = "AOVs and adaptive")
    )]
    pub min_rays: u32,
    /// adaptive: a pixel never casts more rays than this.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "M", default_value_t = adaptive::DEFAULT_MAX_RAYS, help_heading = "AOVs and adaptive")
    )]
    pub max_rays: u32,
    /// Per-quadrant hemicube resolution R: top face 2R x 2R, sides 2R x R.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = cubemap::DEFAULT_CUBE_RES, help_heading = "Cube map")
    )]
    pub cube_res: u32,
    /// Where gather casts its rays and the cube map builds its hemicubes.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Backend::Auto))]
    pub backend: Backend,
    /// Photons stored P, exactly.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = photon::DEFAULT_PHOTONS, help_heading = "Photon methods")
    )]
    pub photons: usize,
    /// Nearest photons gathered per pixel K.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = photon::DEFAULT_GATHER, help_heading = "Photon methods")
    )]
    pub gather: usize,
    /// Where paths start.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_enum, default_value_t = SourceKind::Light, help_heading = "Photon methods")
    )]
    pub source: SourceKind,
    /// A path ends at this many surface interactions.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = photon::DEFAULT_MAX_BOUNCES, help_heading = "Photon methods")
    )]
    pub max_bounces: u32,
    /// Probability that a path ends at each interaction.
    #[cfg_attr(
        feature = "cli",
        arg(long, default_value_t = photon::DEFAULT_ABSORPTION, help_heading = "Photon methods")
    )]
    pub absorption: f32,
    /// Gather over this photon map file (from `hmdist photons build`) instead of tracing one.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_name = "FILE", help_heading = "Photon methods")
    )]
    pub photon_map: Option<std::path::PathBuf>,
    /// Gather only within this distance of the pixel [default: no limit].
    #[cfg_attr(feature = "cli", arg(long, value_name = "R", help_heading = "Photon methods"))]
    pub max_radius: Option<f32>,
}

impl Default for MethodConfig {
    fn default() -> Self {
        MethodConfig {
            rays: gather::DEFAULT_RAYS,
            weighting: Weighting::default(),
            rounds: None,
            ao_radius: None,
            tolerance: adaptive::DEFAULT_TOLERANCE,
            min_rays: adaptive::DEFAULT_MIN_RAYS,
            max_rays: adaptive::DEFAULT_MAX_RAYS,
            cube_res: cubemap::DEFAULT_CUBE_RES,
            backend: Backend::default(),
            photons: photon::DEFAULT_PHOTONS,
            gather: photon::DEFAULT_GATHER,
            source: SourceKind::default(),
            max_bounces: photon::DEFAULT_MAX_BOUNCES,
            absorption: photon::DEFAULT_ABSORPTION,
            max_radius: None,
            photon_map: None,
        }
    }
}

impl MethodConfig {
    /// The configuration for an image with `aovs`: `rounds` defaults to
    /// [`DEFAULT_ERROR_ROUNDS`] where `relerr` is asked for.
    pub fn for_aovs(mut self, aovs: &[Aov]) -> Self {
        if aovs.contains(&Aov::Relerr) {
            self.rounds.get_or_insert(DEFAULT_ERROR_ROUNDS);
        }
        self
    }

    fn gather(&self) -> Result<Gather> {
        Gather::new(self.rays, self.weighting)
    }

    /// The cube map this configuration names (what `build("cubemap", ..)` boxes).
    pub fn cubemap(&self) -> Result<Cubemap> {
        Cubemap::new(self.gather()?, self.cube_res, self.backend)
    }

    /// Method `method` with this configuration's photon parameters, over its `photon_map`
    /// file where it names one.
    pub fn photon_estimator(&self, method: PhotonMethod) -> Result<PhotonEstimator> {
        let estimator = PhotonEstimator::new(method, self.photon_params())?;
        match &self.photon_map {
            Some(path) => {
                let bytes = std::fs::read(path).map_err(|e| Error::io(path, "read", e))?;
                estimator.with_map_file(&bytes, path)
            }
            None => Ok(estimator),
        }
    }

    fn photon_params(&self) -> PhotonParams {
        PhotonParams {
            photons: self.photons,
            gather: self.gather,
            source: self.source,
            rules: PathRules {
                max_bounces: self.max_bounces,
                absorption: self.absorption,
            },
            max_radius: self.max_radius,
        }
    }
}

/// One method: what the CLI, the experiments and Python know of it.
pub struct MethodEntry {
    /// The name `--method` takes and the report's `method`.
    pub name: &'static str,
    /// One sentence on what it is.
    pub summary: &'static str,
    /// The [`MethodConfig`] fields it reads.
    pub parameters: &'static [&'static str],
    /// Builds the estimator from the configuration, checking its parameters.
    pub build: fn(&MethodConfig) -> Result<Box<dyn Estimator>>,
}

/// Every method, in the order `--help` lists them.
pub const METHODS: &[MethodEntry] = &[
    MethodEntry {
        name: "gather",
        summary: "Ray-traced final gathering (SPEC §3.1)",
        parameters: &["rays", "weighting", "rounds", "ao_radius", "backend"],
        build: |c| {
            let gather = c.gather()?.with_rounds(c.rounds.unwrap_or(1))?;
            Ok(Box::new(
                gather.with_ao_radius(c.ao_radius)?.with_backend(c.backend),
            ))
        },
    },
    MethodEntry {
        name: "adaptive",
        summary: "Final gathering in rounds until H's relative standard error is below --tolerance",
        parameters: &["weighting", "tolerance", "min_rays", "max_rays", "ao_radius"],
        build: |c| {
            let adaptive = Adaptive::new(c.weighting, c.tolerance, c.min_rays, c.max_rays)?;
            Ok(Box::new(adaptive.with_ao_radius(c.ao_radius)?))
        },
    },
    MethodEntry {
        name: "cubemap",
        summary: "Hemicube rasterisation, looked up with gather's directions (SPEC §3.2)",
        parameters: &["rays", "weighting", "cube_res", "backend"],
        build: |c| Ok(Box::new(c.cubemap()?)),
    },
    MethodEntry {
        name: "photon1",
        summary: "Photon map, method I: harmonic mean of the gathered photons' own distances (SPEC §3.3)",
        parameters: PHOTON_PARAMETERS,
        build: |c| Ok(Box::new(c.photon_estimator(PhotonMethod::StoredDistance)?)),
    },
    MethodEntry {
        name: "photon2",
        summary: "Photon map, method II: distances from the pixel to the photons' next hits (SPEC §3.3)",
        parameters: PHOTON_PARAMETERS,
        build: |c| Ok(Box::new(c.photon_estimator(PhotonMethod::NextHitPoint)?)),
    },
];

const PHOTON_PARAMETERS: &[&str] = &[
    "photon_map",
    "photons",
    "gather",
    "source",
    "max_bounces",
    "absorption",
    "max_radius",
];

/// The method called `name`.
pub fn method(name: &str) -> Result<&'static MethodEntry> {
    METHODS.iter().find(|m| m.name == name).ok_or_else(|| {
        let names: Vec<&str> = METHODS.iter().map(|m| m.name).collect();
        Error::invalid("method", format!("'{name}' is not one of {}", names.join(", ")))
    })
}

/// Builds method `name` from `config`.
pub fn build(name: &str, config: &MethodConfig) -> Result<Box<dyn Estimator>> {
    (method(name)?.build)(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_builds_with_the_defaults_and_reports_its_name() {
        for entry in METHODS {
            let estimator = (entry.build)(&MethodConfig::default()).unwrap();
            assert_eq!(estimator.method(), entry.name);
        }
    }

    #[test]
    fn an_unknown_method_is_a_bad_parameter_named_method() {
        let err = build("raymarch", &MethodConfig::default()).err().unwrap();
        assert!(matches!(
            err,
            Error::Parameter {
                name: Some("method"),
                ..
            }
        ));
    }
}
