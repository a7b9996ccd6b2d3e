//! The flags that determine an image besides the scene and the method, shared by `render` and
//! `photons build`.

use hmdist::error::Result;

/// What determines an image besides the scene and the method, as `render` and `photons
/// build` both take it (a photon map is built for the renders that will use it).
#[derive(clap::Args)]
pub struct ImageArgs {
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value_t = Size(hmdist::render::DEFAULT_SIZE), value_parser = parse_size)]
    size: Size,
    /// Seed of the per-pixel random numbers: same seed, same image, whatever the thread count.
    #[arg(long, default_value_t = hmdist::render::DEFAULT_SEED)]
    seed: u64,
    /// Worker threads [default: all cores]. Never changes the output.
    #[arg(long)]
    threads: Option<usize>,
    /// BVH build preset, by the work to come unless named.
    #[arg(long, value_enum, default_value_t = hmdist::accel::BuildQuality::Auto)]
    bvh: hmdist::accel::BuildQuality,
}

impl ImageArgs {
    /// The library's render options for these flags, with the kernel `HMDIST_KERNEL` names.
    pub fn options(&self) -> Result<hmdist::render::RenderOptions> {
        Ok(hmdist::render::RenderOptions {
            width: self.size.0 .0,
            height: self.size.0 .1,
            seed: self.seed,
            threads: self.threads,
            bvh_quality: self.bvh,
            kernel: hmdist::accel::Kernel::from_env()?,
            ..Default::default()
        })
    }
}

/// An image size as `--size` spells it, `WIDTHxHEIGHT` (so that its default is the library's
/// [`hmdist::render::DEFAULT_SIZE`], written once).
#[derive(Clone, Copy, Debug)]
struct Size((u32, u32));

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.0 .0, self.0 .1)
    }
}

/// `WIDTHxHEIGHT`, e.g. `1024x1024`.
fn parse_size(s: &str) -> std::result::Result<Size, String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT, e.g. 1024x1024"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{v}' in '{s}' is not a whole number"))
    };
    Ok(Size((parse(w)?, parse(h)?)))
}
