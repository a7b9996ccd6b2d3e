//! How much work an experiment does: the presets' sizes and counts, the reference's seed, and
//! when an image is rendered in parts.

/// Images that cast at least this many rays (2³³, about 20 minutes at 7 M rays/s) are
/// rendered in [`PARTS`] row shards, each cached when done, so that a run stopped by the end
/// of a working session keeps most of the work (at paper scale: the 65,536-ray reference,
/// 6.9·10¹⁰ rays, and Fig. 9's cube maps).
pub const PART_RAYS: u64 = 1 << 33;
/// Parts of such an image.
pub const PARTS: u32 = 16;

/// Seed of the reference images: independent of the seed of the images compared with them.
pub const REFERENCE_SEED: u64 = 1_000_003;

/// How much work an experiment does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Preset {
    /// Small images, a 16,384-ray reference, fewer points: minutes on 2 cores. What CI runs.
    Quick,
    /// The paper's scale: 1024², a 65,536-ray reference. Hours on a CPU.
    Paper,
}

/// The sizes and counts a preset stands for.
#[derive(Clone, Debug)]
pub struct PresetParams {
    /// Image side in pixels (square images).
    pub size: u32,
    /// Gather rays of the reference image.
    pub reference_rays: u32,
    /// Gather ray counts of Tables 1 and 2.
    pub rays: Vec<u32>,
    /// Photon counts of Tables 3 and 4.
    pub photons: Vec<usize>,
    /// Photons gathered per pixel (K) for Table 3.
    pub nearest: Vec<usize>,
    /// Photon counts of Fig. 16/17.
    pub fig16_photons: Vec<usize>,
    /// Photons gathered per pixel (K) of Fig. 16/17 (the paper's: 64, 256, 1,024).
    pub fig16_nearest: Vec<usize>,
    /// Photons of Fig. 10.
    pub fig10_photons: usize,
    /// Photons gathered per pixel (K) of Fig. 10.
    pub fig10_nearest: usize,
    /// Per-quadrant hemicube resolution R of Tables 1 and 2.
    pub cube_res: u32,
    /// Gather rays M of each irradiance-cache record (the cache study).
    pub cache_rays: u32,
    /// Rays of the cache study's brute-force images of E.
    pub cache_reference_rays: u32,
}

impl Preset {
    /// The name `--preset` takes.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Quick => "quick",
            Preset::Paper => "paper",
        }
    }

    /// The sizes and counts it stands for.
    pub fn params(self) -> PresetParams {
        let doubling = |from: u32, to: u32| (0..).map(move |k| from << k).take_while(move |&n| n <= to);
        match self {
            Preset::Quick => PresetParams {
                size: 48,
                reference_rays: 16_384,
                rays: doubling(32, 2048).collect(),
                photons: vec![130_000, 260_000, 530_000, 1_060_000],
                nearest: vec![64, 256, 1024],
                fig16_photons: vec![260_000, 1_060_000],
                fig16_nearest: vec![64, 256, 1024],
                fig10_photons: 1_060_000,
                fig10_nearest: 4096,
                cube_res: 64,
                cache_rays: 512,
                cache_reference_rays: 4096,
            },
            Preset::Paper => PresetParams {
                size: 1024,
                reference_rays: 65_536,
                rays: doubling(32, 16_384).collect(),
                photons: vec![
                    130_000, 260_000, 530_000, 1_060_000, 2_130_000, 4_260_000, 8_530_000,
                ],
                nearest: vec![64, 128, 256, 512, 1024],
                fig16_photons: vec![1_060_000, 8_530_000],
                fig16_nearest: vec![64, 256, 1024],
                fig10_photons: 8_530_000,
                fig10_nearest: 65_536,
                cube_res: 64,
                cache_rays: 512,
                cache_reference_rays: 16_384,
            },
        }
    }
}
