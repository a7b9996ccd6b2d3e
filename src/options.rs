//! How to render, apart from the estimator and its parameters: size, seed, threads, distance
//! clamp, BVH preset, AOVs and the rows of a shard ([`RenderOptions`]); shared by the render
//! driver ([`crate::render`]) and the estimators that run work of their own (a photon map
//! built as a file), below both.

use serde::{Deserialize, Serialize};

use crate::accel::{BuildQuality, Kernel};
pub use crate::denoise::DenoiseParams;
use crate::error::{Error, Result};

/// One AOV: a per-pixel companion of H, written as an EXR channel beside `Y` (spec §8;
/// [`crate::estimators::aov`] measures them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    /// Relative standard error of H, from independent rounds.
    Relerr,
    /// Rays cast for the pixel.
    Rays,
    /// The smallest hit distance over the pixel's rays.
    Dmin,
    /// Cosine-weighted fraction of directions that meet nothing within the AO radius.
    Ao,
    /// Fraction of rays that met nothing.
    Escaped,
    /// Direct irradiance from the spot light at the pixel's point (`irradiance` only).
    #[serde(rename = "E_direct")]
    #[cfg_attr(feature = "cli", value(name = "E_direct"))]
    EDirect,
}

impl Aov {
    /// Every AOV, in channel order.
    pub const ALL: [Aov; 6] = [
        Aov::Relerr,
        Aov::Rays,
        Aov::Dmin,
        Aov::Ao,
        Aov::Escaped,
        Aov::EDirect,
    ];

    /// The AOVs of H that the gather measures (and `adaptive`): all but `E_direct`.
    pub const OF_GATHER: [Aov; 5] = [Aov::Relerr, Aov::Rays, Aov::Dmin, Aov::Ao, Aov::Escaped];

    /// The EXR channel's name.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Relerr => "relerr",
            Aov::Rays => "rays",
            Aov::Dmin => "dmin",
            Aov::Ao => "ao",
            Aov::Escaped => "escaped",
            Aov::EDirect => "E_direct",
        }
    }

    /// The AOV called `name`.
    pub fn parse(name: &str) -> Result<Aov> {
        Aov::ALL.into_iter().find(|a| a.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
            Error::invalid("aov", format!("'{name}' is not one of {}", names.join(", ")))
        })
    }
}

/// Default image size (spec §2).
pub const DEFAULT_SIZE: (u32, u32) = (1024, 1024);
/// Default seed of the counter-based random numbers.
pub const DEFAULT_SEED: u64 = 1;
/// Largest image accepted: 64 M pixels (the G-buffer alone then takes about 3 GB).
pub const MAX_PIXELS: u64 = 1 << 26;

/// How to render, apart from the estimator and its parameters. Checked by [`crate::render::render`]
/// ([`RenderOptions::validate`]).
#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of the counter-based random numbers.
    pub seed: u64,
    /// Worker threads; `None` uses every core. Never changes the output.
    pub threads: Option<usize>,
    /// Clamp distances (and count escapes) at this value; `None` for no clamp.
    pub max_distance: Option<f32>,
    /// The BVH preset.
    pub bvh_quality: BuildQuality,
    /// The ray-casting kernel (default [`Kernel::best`]; every kernel gives the same bits).
    /// The library never reads `HMDIST_KERNEL`: the CLI and Python read it, with
    /// [`Kernel::from_env`], and set this.
    pub kernel: Kernel,
    /// AOVs to measure beside H, each an EXR channel (spec §8).
    pub aovs: Vec<Aov>,
    /// Render only this shard's rows ([`crate::shard`]); `None` for the whole image.
    pub shard: Option<Shard>,
    /// Filter the image with its neighbours' rays ([`crate::denoise`]); `None` for the
    /// estimator's own pixels.
    pub denoise: Option<DenoiseParams>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: DEFAULT_SIZE.0,
            height: DEFAULT_SIZE.1,
            seed: DEFAULT_SEED,
            threads: None,
            max_distance: None,
            bvh_quality: BuildQuality::default(),
            kernel: Kernel::best(),
            aovs: vec![],
            shard: None,
            denoise: None,
        }
    }
}

impl RenderOptions {
    /// What a [`crate::report::RenderKey`] holds of the image these options render.
    pub fn key_image(&self) -> crate::report::KeyImage {
        crate::report::KeyImage {
            width: self.width,
            height: self.height,
            seed: self.seed,
            max_distance: self.max_distance,
            aovs: self.aovs.iter().map(|a| a.name().into()).collect(),
            denoise: self.denoise,
        }
    }

    /// Refuses an empty or oversized image, a non-positive `max_distance`, bad denoising
    /// parameters, and zero threads or more than [`max_threads`].
    pub fn validate(&self) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 {
            let message = format!("{w}x{h} is empty: width and height must be at least 1");
            return Err(Error::invalid("size", message));
        }
        if w as u64 * h as u64 > MAX_PIXELS {
            let message = format!("{w}x{h} exceeds the limit of {MAX_PIXELS} pixels");
            return Err(Error::invalid("size", message));
        }
        Error::check_positive("max_distance", self.max_distance)?;
        if let Some(denoise) = &self.denoise {
            denoise.validate()?;
        }
        check_threads(self.threads)
    }
}

/// The most worker threads a run takes: this many per CPU the process may use. More only
/// slow a render down, and tens of thousands exhaust the machine before the first pixel.
pub const MAX_THREADS_PER_CPU: usize = 4;

/// The most worker threads a run takes here: [`MAX_THREADS_PER_CPU`] × the CPUs this process
/// may use (at least 4 × 1).
pub fn max_threads() -> usize {
    MAX_THREADS_PER_CPU * std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Refuses a thread count beyond [`max_threads`], before any thread is started.
pub fn check_threads(threads: Option<usize>) -> Result<()> {
    match threads {
        Some(0) => Err(Error::invalid("threads", "must be at least 1, not 0")),
        Some(n) if n > max_threads() => {
            let cpus = max_threads() / MAX_THREADS_PER_CPU;
            let message = format!(
                "{n} is more than {MAX_THREADS_PER_CPU} per CPU this process may use ({cpus} CPUs: at most {})",
                max_threads()
            );
            Err(Error::invalid("threads", message))
        }
        _ => Ok(()),
    }
}

/// Runs `f` on a pool of `threads` workers (`None`: every core); refuses more than
/// [`max_threads`].
pub(crate) fn in_pool<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    check_threads(threads)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::parameter(format!("cannot start worker threads: {e}")))?;
    Ok(pool.install(f))
}

/// Shard `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which shard, from 0.
    pub index: u32,
    /// How many shards.
    pub count: u32,
}

impl Shard {
    /// Shard `index` of `count`: `index < count`.
    pub fn new(index: u32, count: u32) -> Result<Shard> {
        if count == 0 || index >= count {
            let message = format!("{index}/{count} is not a shard: K/M needs 0 <= K < M");
            return Err(Error::invalid("shard", message));
        }
        Ok(Shard { index, count })
    }

    /// `K/M`, e.g. `0/4`.
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = || Error::invalid("shard", format!("'{text}' is not K/M, e.g. 0/4"));
        let (k, m) = text.split_once('/').ok_or_else(bad)?;
        Shard::new(
            k.trim().parse().map_err(|_| bad())?,
            m.trim().parse().map_err(|_| bad())?,
        )
    }

    /// Whether image row `row` is this shard's.
    pub fn has_row(&self, row: u32) -> bool {
        row % self.count == self.index
    }

    /// A hash of this shard's rows of each of `channels` (images `width` pixels wide: H, then
    /// the AOVs), their bits in order: what a part's report records and `merge` checks its
    /// EXR against.
    pub fn rows_hash(&self, width: u32, channels: &[&[f32]]) -> String {
        let width = width.max(1) as usize;
        let bytes = channels.iter().flat_map(|data| {
            data.chunks_exact(width)
                .enumerate()
                .filter(|(row, _)| self.has_row(*row as u32))
                .flat_map(|(_, row)| row.iter().flat_map(|v| v.to_bits().to_le_bytes()))
        });
        format!("{:016x}", crate::scene::stable_hash_of(bytes))
    }
}
