//! The flags that determine an image besides the scene and the method, shared by `render` and
//! `photons build`.

use hmdist::error::Result;

/// What determines an image besides the scene and the method, as `render` and `photons
/// build` both take it (a photon map is built for the renders that will use it).
#[derive(clap::Args)]
pub struct ImageArgs {
    /// Image size, WIDTHxHEIGHT [default: the scene file's own (a pbrt Film, a Mitsuba film),
    /// else 1024x1024].
    #[arg(long, value_parser = parse_size)]
    size: Option<Size>,
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
    /// Without `--size`, the size is [`hmdist::render::DEFAULT_SIZE`] until
    /// [`ImageArgs::size_for`] gives the scene's own.
    pub fn options(&self) -> Result<hmdist::render::RenderOptions> {
        let (width, height) = self.size.map_or(hmdist::render::DEFAULT_SIZE, |s| s.0);
        Ok(hmdist::render::RenderOptions {
            width,
            height,
            seed: self.seed,
            threads: self.threads,
            bvh_quality: self.bvh,
            kernel: hmdist::accel::Kernel::from_env()?,
            ..Default::default()
        })
    }

    /// `--size`, or else the size the scene's file asks for, or else the default: the image
    /// size of a render of `scene`.
    pub fn size_for(&self, scene: &hmdist::scene::Scene) -> (u32, u32) {
        match self.size {
            Some(size) => size.0,
            None => scene.notes.size.unwrap_or(hmdist::render::DEFAULT_SIZE),
        }
    }
}

/// An image size as `--size` spells it, `WIDTHxHEIGHT`.
#[derive(Clone, Copy, Debug)]
struct Size((u32, u32));

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
