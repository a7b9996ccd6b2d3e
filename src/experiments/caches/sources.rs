//! The cache study's vocabulary: its accuracies, the sources of the records' radii (with the
//! flags `hmdist cache` takes for each), and what one cache measured.

use serde::{Deserialize, Serialize};

use crate::cache::{CacheErrors, CacheParams, Range, Spacing};
use crate::error::Result;
use crate::estimators::IrradianceParams;
use crate::image::HmdImage;

/// Ward's a of every source, coarsest first.
pub const ACCURACIES: [f32; 6] = [0.4, 0.3, 0.2, 0.15, 0.1, 0.05];
/// The accuracy whose records are pictured.
pub(super) const PICTURED_ACCURACY: f32 = 0.2;
/// The seed of the caches' records.
pub(super) const SEED: u64 = 1;

/// One way to space the records.
pub(super) struct Source {
    pub(super) name: &'static str,
    /// `--spacing`.
    pub(super) spacing: &'static str,
    pub(super) clamp_pixels: Option<(f32, f32)>,
    pub(super) clamp_scene: Option<(f32, f32)>,
    pub(super) neighbour_clamp: bool,
    pub(super) gradients: bool,
    /// Pictured at [`PICTURED_ACCURACY`].
    pub(super) pictured: bool,
}

/// pbrt-v2's clamp in pixel footprints; Mitsuba 0.6's, and its clamp in fractions of l_diag.
const PBRT_PIXELS: Option<(f32, f32)> = Some((2.5, 15.0));
const MITSUBA_PIXELS: Option<(f32, f32)> = Some((3.0, 20.0));
const MITSUBA_SCENE: Option<(f32, f32)> = Some((0.005, 0.32));

const fn source(name: &'static str, spacing: &'static str) -> Source {
    Source {
        name,
        spacing,
        clamp_pixels: None,
        clamp_scene: None,
        neighbour_clamp: false,
        gradients: false,
        pictured: false,
    }
}

/// Mitsuba 0.6's clamps, neighbour clamping and gradients (its defaults) with `spacing`.
const fn mitsuba(name: &'static str, spacing: &'static str) -> Source {
    Source {
        clamp_pixels: MITSUBA_PIXELS,
        clamp_scene: MITSUBA_SCENE,
        neighbour_clamp: true,
        gradients: true,
        pictured: true,
        ..source(name, spacing)
    }
}

/// The sources, the records' own H first (the others are measured against it).
pub(super) const SOURCES: [Source; 13] = [
    Source {
        pictured: true,
        ..source("hmd", "hmd")
    },
    Source {
        pictured: true,
        ..source("oracle", "oracle")
    },
    source("gather64", "hmd:gather:rays=64,backend=cpu"),
    source("cubemap", "hmd:cubemap:cube_res=16,rays=256,backend=cpu"),
    source("photon1", "hmd:photon1:photons=200000,nearest=64"),
    Source {
        pictured: true,
        ..source("photon2", "hmd:photon2:photons=200000,nearest=64")
    },
    Source {
        clamp_pixels: PBRT_PIXELS,
        pictured: true,
        ..source("pbrt-v2", "min")
    },
    Source {
        clamp_pixels: MITSUBA_PIXELS,
        clamp_scene: MITSUBA_SCENE,
        ..source("min10-clamped", "min10")
    },
    Source {
        clamp_pixels: MITSUBA_PIXELS,
        clamp_scene: MITSUBA_SCENE,
        ..source("hmd-clamped", "hmd")
    },
    Source {
        gradients: true,
        ..source("hmd-gradients", "hmd")
    },
    Source {
        neighbour_clamp: true,
        ..source("hmd-neighbours", "hmd")
    },
    mitsuba("mitsuba", "min10"),
    mitsuba("hmd-mitsuba", "hmd"),
];

/// How many caches the study makes: the progress bar's share.
pub const CACHES: usize = SOURCES.len() * ACCURACIES.len();

impl Source {
    /// `--spacing` and the options that differ from the defaults, as the CLI takes them.
    pub(super) fn flags(&self) -> String {
        let mut flags = vec![format!("--spacing {}", self.spacing)];
        let range = |(lo, hi): (f32, f32)| format!("{lo},{hi}");
        flags.extend(self.clamp_pixels.map(|r| format!("--clamp-pixels {}", range(r))));
        flags.extend(self.clamp_scene.map(|r| format!("--clamp-scene {}", range(r))));
        flags.extend(self.neighbour_clamp.then(|| "--neighbour-clamp".to_string()));
        flags.extend(self.gradients.then(|| "--gradients".to_string()));
        flags.join(" ")
    }

    pub(super) fn params(&self, rays: u32, accuracy: f32) -> Result<CacheParams> {
        let range = |(lo, hi): (f32, f32)| Range { lo, hi };
        Ok(CacheParams {
            irradiance: IrradianceParams {
                rays,
                ..IrradianceParams::default()
            },
            accuracy,
            spacing: Spacing::parse(self.spacing)?,
            clamp_pixels: self.clamp_pixels.map(range),
            clamp_scene: self.clamp_scene.map(range),
            neighbour_clamp: self.neighbour_clamp,
            gradients: self.gradients,
        })
    }
}

/// What one cache cost and how far it is from the brute-force image.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct Run {
    pub(super) records: usize,
    pub(super) rays_e: u64,
    pub(super) rays_h: u64,
    pub(super) seconds: f64,
    pub(super) errors: CacheErrors,
}

impl Run {
    pub(super) fn rays(&self) -> f64 {
        (self.rays_e + self.rays_h) as f64
    }
    pub(super) fn mean(&self) -> f64 {
        self.errors.mean_relative_error
    }
}

/// The references the caches are measured against, and what they say of themselves.
pub(super) struct References {
    pub(super) e: HmdImage,
    pub(super) h: HmdImage,
    /// The second brute-force image against the first: the floor under every error.
    pub(super) noise: CacheErrors,
    /// Digest of both images' bits: part of each cache's key.
    pub(super) digest: u64,
}
