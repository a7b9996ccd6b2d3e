//! The render report: every parameter, the scene's statistics and the timings of one image,
//! as typed data. Serialised once, as the JSON sidecar of spec §7, whose keys scripts rely on
//! and which therefore keep their names; fields that a method does not measure are `null`
//! (or absent, for a method's own groups), never zero.

pub mod legacy;

use serde::{Deserialize, Serialize};

use std::collections::BTreeMap;

use serde_json::Value;

use crate::denoise::DenoiseParams;
use crate::scene::{Bounds, Camera, SpotLight};

/// One rendered image's report: the JSON sidecar.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct RenderReport {
    /// The hmdist that rendered it.
    pub hmdist_version: String,
    /// The estimator's registry name.
    pub method: String,
    /// The scene's name.
    pub scene: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of the random numbers.
    pub seed: u64,
    /// Worker threads used (never changes the image).
    pub threads: usize,
    /// The ray-casting kernel (`scalar`, `avx2`, `avx512`).
    pub kernel: String,
    /// The BVH preset built (`fast` or `high`).
    pub bvh: String,
    /// Distances were clamped at this; `null` for no clamp.
    pub max_distance: Option<f32>,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Diagonal of the scene's bounding box.
    pub l_diag: f32,
    /// The smallest distance a sample counts as: `1e-6 · l_diag`.
    pub d_min: f32,
    /// The scene's bounding box.
    pub bounds: BoundsReport,
    /// The camera.
    pub camera: CameraReport,
    /// The spot light, where the scene has one.
    pub light: Option<LightReport>,
    /// Grey = clamp(display_scale · H) in the PNG.
    pub display_scale: f32,
    /// Pixels whose camera ray met nothing.
    pub background_pixels: usize,
    /// Rays the estimator cast (primary rays not included); `null` for one that casts none.
    pub rays_cast: Option<u64>,
    /// Of those, rays that met nothing.
    pub escaped_rays: Option<u64>,
    /// Million rays per second over the phase that cast them.
    pub mrays_per_s: Option<f64>,
    /// Seconds per phase.
    pub seconds: Seconds,
    /// The EXR's channels: `Y` (H), then the AOVs asked for.
    pub channels: Vec<String>,
    /// The shard this part is, for `hmdist merge`; absent for a whole image.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub shard: Option<ShardReport>,
    /// A merged image's shards and their timings; absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub shards: Option<Vec<ShardTiming>>,
    /// Gather rays per pixel N, where the method casts a fixed number (`null` for the photon
    /// methods and adaptive): the spec's key, beside `parameters.rays`.
    pub rays: Option<u32>,
    /// The method's parameters.
    #[serde(default)]
    pub parameters: Parameters,
    /// The denoising filter, where the image was filtered (`--denoise`); absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub denoise: Option<DenoiseReport>,
    /// The method's own figures.
    #[serde(flatten)]
    pub details: Details,
}

/// The denoising filter of an image ([`crate::denoise`]): its parameters, whether the image's
/// `Y` is filtered, and the filter's seconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DenoiseReport {
    /// The filter's parameters.
    #[serde(flatten)]
    pub params: DenoiseParams,
    /// `true` in a filtered image; `false` in a shard's part, whose `Y` is its own rays' H
    /// and whose guide channels `hmdist merge` filters the joined image with.
    pub filtered: bool,
    /// Seconds the filter took (0 in a shard's part).
    pub seconds: f64,
}

impl RenderReport {
    /// Adds the seconds it took to load the scene (which the library does not see) to
    /// `seconds.load` and `seconds.total`.
    pub fn add_load_seconds(&mut self, seconds: f64) {
        self.seconds.load += seconds;
        self.seconds.total += seconds;
    }

    /// One line on what was rendered and what it cost, as `hmdist render` prints it.
    pub fn summary(&self) -> String {
        let r = self;
        let p = &r.parameters;
        let rays = r.rays.unwrap_or(0);
        let backend = r.details.device.as_ref().map_or("cpu", |d| d.backend.as_str());
        let number = |name| p.number(name).unwrap_or(f64::NAN);
        let what = match (&r.details.cubemap, &r.details.photon) {
            _ if r.method == "adaptive" => format!(
                "tolerance {}, {:.1} rays/pixel on average, {:.2} Mrays/s",
                number("tolerance") as f32,
                r.details.mean_rays_per_pixel.unwrap_or(f64::NAN),
                r.mrays_per_s.unwrap_or(f64::NAN)
            ),
            (Some(_), _) => format!("{rays} rays/pixel, R = {}, {backend} backend", number("cube_res")),
            (_, Some(d)) => format!(
                "{} photons, K = {}, {} holes, {:.0} queries/s",
                d.photons_stored,
                number("nearest"),
                d.holes,
                d.gather_queries_per_s
            ),
            _ => format!(
                "{rays} rays/pixel, {:.2} Mrays/s, {backend} backend",
                r.mrays_per_s.unwrap_or(f64::NAN)
            ),
        };
        // The cube map's rays fill texels; its directions are the lookups.
        let escaped = match &r.details.cubemap {
            Some(c) => c.escaped_lookups.to_string(),
            None => r.escaped_rays.map_or("null".into(), |e| e.to_string()),
        };
        format!(
            "{}: {}x{} {} ({what}): {:.2} s, {escaped} escaped, {} background",
            r.scene, r.width, r.height, r.method, r.seconds.total, r.background_pixels
        )
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("a report serialises")
    }

    /// The report in the JSON file at `path` (a render's sidecar, a shard's, a cached
    /// image's): the one place a report is read back, so every reader refuses the same way.
    pub fn read(path: &std::path::Path) -> crate::error::Result<RenderReport> {
        use crate::error::Error;
        let text = crate::files::read_text(path)?;
        /// A report as a file holds it: one written before the parameters were an object
        /// has them at the top level.
        #[derive(Deserialize)]
        struct OnDisk {
            #[serde(flatten)]
            report: RenderReport,
            #[serde(flatten)]
            legacy: legacy::FlatParameters,
        }
        let OnDisk { mut report, legacy } = serde_json::from_str(&text)
            .map_err(|e| Error::file(path, format!("not an hmdist render report: {e}")))?;
        if report.parameters.0.is_empty() && legacy.is_some() {
            let mut fields = legacy.fields(&report.method);
            if let Some(rays) = report.rays {
                fields.insert("rays".into(), rays.into());
            }
            report.parameters = Parameters(fields);
        }
        Ok(report)
    }
}

/// What a shard's report says about it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardReport {
    /// Which shard, from 0.
    pub index: u32,
    /// How many shards.
    pub count: u32,
    /// Hash of the scene, method, parameters, size, seed, clamp, AOVs and version
    /// (`fingerprint` in the JSON): what parts carried before they carried a key, still
    /// written so that `merge` can join a part that has only it with parts written since
    /// (it compares it where a part has no key). The key is what determines the pixels.
    #[serde(rename = "fingerprint")]
    pub legacy_fingerprint: String,
    /// Everything that determines the pixels; absent from reports written before it was
    /// added (`merge` then compares fingerprints alone).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub key: Option<RenderKey>,
    /// A hash of the shard's own rows of H and its AOVs ([`crate::options::Shard::rows_hash`]): `merge`
    /// checks each part's EXR against it, so an EXR swapped for another render's, another
    /// shard's or an edited one is refused. Absent from reports written before it was added.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rows_hash: Option<String>,
}

/// Everything that determines a render's pixels, and nothing that does not (threads,
/// timings, a shard's own rows): two renders with equal keys give the same pixels bit for bit.
/// A shard carries its key, and `hmdist merge` joins only parts whose keys are equal, naming
/// the fields that differ ([`RenderKey::differences`]); the render driver makes it
/// (`render_key` in `render.rs`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderKey {
    /// The hmdist that rendered it.
    pub hmdist_version: String,
    /// The scene's name.
    pub scene: String,
    /// Hash of the scene's content: vertices, triangles, camera, light, display scale
    /// ([`crate::scene::Scene::fingerprint`]).
    pub scene_content: String,
    /// The estimator's registry name.
    pub method: String,
    /// The method's parameters, as the report writes them (empty in a key written before
    /// they were an object of their own).
    #[serde(default)]
    pub parameters: Parameters,
    /// Where it ran: `cpu` or `gpu` (resolved: never `auto`). The experiment cache, which
    /// keys an image before it is rendered, puts the backend it asks for (`auto` too).
    pub backend: String,
    /// The GPU adapter's class, `hardware` or `software`; `null` on the CPU. (Hardware and
    /// software GPUs round differently in the last bits.)
    pub adapter_class: Option<String>,
    /// The BVH preset built (resolved: never `auto`; the experiment cache: as asked for).
    pub bvh: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of the random numbers.
    pub seed: u64,
    /// Distance clamp; `null` for none.
    pub max_distance: Option<f32>,
    /// The AOV channels, in order.
    pub aovs: Vec<String>,
    /// The `ao` AOV's radius, where it was computed.
    pub ao_radius: Option<f32>,
    /// The denoising filter's parameters; absent (not `null`: keys written before the filter
    /// existed keep their digests) for an image that is not filtered.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub denoise: Option<DenoiseParams>,
}

/// What every key holds of the image it names, whoever builds it: size, random numbers,
/// distance clamp, AOVs and filter ([`crate::options::RenderOptions::key_image`]).
#[derive(Clone, Debug)]
pub struct KeyImage {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Seed of the random numbers.
    pub seed: u64,
    /// Distance clamp; `None` for none.
    pub max_distance: Option<f32>,
    /// The AOV channels, in order.
    pub aovs: Vec<String>,
    /// The denoising filter's parameters, where the image is filtered.
    pub denoise: Option<DenoiseParams>,
}

impl RenderKey {
    /// The one constructor of a key, which every key is built by (the render driver's, the
    /// experiment cache's, a photon map's): hmdist's own version; the scene by name (empty for
    /// a key of its content alone) and content ([`crate::scene::Scene::fingerprint`]); the
    /// method's registry name and parameters; the BVH preset's name; the image. It ran on the
    /// CPU with no `ao` radius until [`RenderKey::on`] and [`RenderKey::with_ao_radius`] say
    /// otherwise.
    pub fn new(
        (scene, scene_content): (&str, u64),
        (method, parameters): (&str, Parameters),
        bvh: &str,
        image: KeyImage,
    ) -> RenderKey {
        RenderKey {
            hmdist_version: env!("CARGO_PKG_VERSION").into(),
            scene: scene.into(),
            scene_content: format!("{scene_content:016x}"),
            method: method.into(),
            parameters,
            backend: "cpu".into(),
            adapter_class: None,
            bvh: bvh.into(),
            width: image.width,
            height: image.height,
            seed: image.seed,
            max_distance: image.max_distance,
            aovs: image.aovs,
            ao_radius: None,
            denoise: image.denoise,
        }
    }

    /// This key for an image made on `backend` (`cpu`, `gpu`; as asked, `auto` too, in the
    /// experiment cache) by an adapter of `adapter_class`.
    pub fn on(self, backend: &str, adapter_class: Option<String>) -> RenderKey {
        RenderKey {
            backend: backend.into(),
            adapter_class,
            ..self
        }
    }

    /// This key for an image whose `ao` AOV used `ao_radius`.
    pub fn with_ao_radius(self, ao_radius: Option<f32>) -> RenderKey {
        RenderKey { ao_radius, ..self }
    }

    /// A stable 64-bit hash of every field (its JSON, fields in declaration order): what the
    /// experiment cache names an image by and a photon map file is checked by. The one set of
    /// fields that determines an image is this struct's, and [`RenderKey::new`] the one place
    /// that fills it, so a field added here is a field every key has.
    pub fn digest(&self) -> u64 {
        crate::scene::stable_hash(serde_json::to_string(self).expect("a key serialises").as_bytes())
    }

    /// The fields whose values differ from `other`'s, each as `name (this value against
    /// other's)`, in alphabetical order; empty where the keys are equal.
    pub fn differences(&self, other: &RenderKey) -> Vec<String> {
        use serde_json::Value;
        let (Value::Object(mine), Value::Object(theirs)) = (to_value(self), to_value(other)) else {
            unreachable!("a key serialises to an object")
        };
        let absent = Value::Null;
        let mut names: Vec<&String> = mine.keys().collect();
        names.extend(theirs.keys().filter(|k| !mine.contains_key(*k)));
        names
            .into_iter()
            .filter_map(|name| {
                let (a, b) = (
                    mine.get(name).unwrap_or(&absent),
                    theirs.get(name).unwrap_or(&absent),
                );
                (a != b).then(|| format!("{name} ({a} against {b})"))
            })
            .collect()
    }
}

fn to_value(key: &RenderKey) -> serde_json::Value {
    serde_json::to_value(key).expect("a key serialises")
}

/// One shard's timings in a merged report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardTiming {
    /// Which shard.
    pub index: u32,
    /// Its total seconds.
    pub seconds: f64,
    /// Rays it cast, where the method counts them.
    pub rays_cast: Option<u64>,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct BoundsReport {
    /// Smallest corner.
    pub min: [f32; 3],
    /// Largest corner.
    pub max: [f32; 3],
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct CameraReport {
    /// Eye position.
    pub eye: [f32; 3],
    /// The point looked at.
    pub target: [f32; 3],
    /// Up direction.
    pub up: [f32; 3],
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
    /// The picture's right is `up × f` (a pbrt camera); written only where true.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub mirrored: bool,
}

/// A spot light.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct LightReport {
    /// Position.
    pub position: [f32; 3],
    /// Unit direction of the cone's axis.
    pub direction: [f32; 3],
    /// Half the cone's opening angle, degrees.
    pub cone_half_angle_deg: f32,
}

impl From<&Bounds> for BoundsReport {
    fn from(bounds: &Bounds) -> Self {
        BoundsReport {
            min: bounds.min.to_array(),
            max: bounds.max.to_array(),
        }
    }
}

impl From<&Camera> for CameraReport {
    fn from(camera: &Camera) -> Self {
        CameraReport {
            eye: camera.eye.to_array(),
            target: camera.target.to_array(),
            up: camera.up.to_array(),
            fov_y_deg: camera.fov_y_deg,
            mirrored: camera.mirrored,
        }
    }
}

impl From<&SpotLight> for LightReport {
    fn from(light: &SpotLight) -> Self {
        LightReport {
            position: light.position.to_array(),
            direction: light.direction.to_array(),
            cone_half_angle_deg: light.cone_half_angle_deg,
        }
    }
}

/// Seconds per phase: the driver's, then the estimator's own (absent where it has none).
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct Seconds {
    /// Loading the scene (added by the caller that loaded it).
    pub load: f64,
    /// Building the BVH.
    pub accel_build: f64,
    /// Primary rays.
    pub primary: f64,
    /// The estimator, from preparation to the last pixel.
    pub estimate: f64,
    /// Everything.
    pub total: f64,
    /// The estimator's own phases.
    #[serde(flatten)]
    pub phases: PhaseSeconds,
}

/// The estimators' own phases; each present only for the method that has it.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize)]
pub struct PhaseSeconds {
    /// CPU cube map: texels are filled at their first lookup.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cubemap_build_and_lookup: Option<f64>,
    /// GPU cube map: rasterising the hemicubes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cubemap_build: Option<f64>,
    /// GPU cube map: the lookups.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cubemap_lookup: Option<f64>,
    /// Photon methods: tracing the paths.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photon_trace: Option<f64>,
    /// Photon methods: building the kd-tree.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photon_index: Option<f64>,
    /// Photon methods: the K-nearest gathers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gather: Option<f64>,
    /// GPU gather: uploading the scene and the points, and compiling the shaders.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub gpu_upload: Option<f64>,
    /// GPU gather: the dispatches that cast the rays.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub gpu_trace: Option<f64>,
    /// GPU gather: reading the sums back.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub gpu_readback: Option<f64>,
}

/// A method's parameters: the fields of its parameter struct (`GatherParams`,
/// `CubemapParams`, ...) by the names its flags and Python's keywords have, as one JSON
/// object (`"parameters"` in the report), less what the report says elsewhere (the backend, the
/// `ao` radius, a photon map file's path). What the estimator itself holds, after the defaults
/// that depend on the AOVs are filled in; the experiments read it back into the struct.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Parameters(BTreeMap<String, Value>);

impl Parameters {
    /// `params` (a method's parameter struct) every field under its own name, less `omit`.
    pub fn of(params: &impl Serialize, omit: &[&str]) -> Parameters {
        let mut fields: BTreeMap<String, Value> = match serde_json::to_value(params) {
            Ok(Value::Object(map)) => map.into_iter().collect(),
            _ => BTreeMap::new(),
        };
        fields.retain(|name, _| !omit.contains(&name.as_str()));
        Parameters(fields)
    }

    /// The value of parameter `name`, where the method has it.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.0.get(name)
    }

    /// Parameter `name` as a number, where the method has it and it is one.
    pub fn number(&self, name: &str) -> Option<f64> {
        self.get(name).and_then(Value::as_f64)
    }

    /// The parameters as the struct `T` (the method's own), where they are its fields.
    pub fn typed<T: serde::de::DeserializeOwned>(&self) -> Option<T> {
        serde_json::from_value(Value::Object(self.0.clone().into_iter().collect())).ok()
    }
}

/// Where photon paths start.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum SourceKind {
    /// The scene's spot light.
    #[default]
    Light,
    /// The camera, through random image positions.
    Camera,
}

impl SourceKind {
    /// The name the CLI and the report use.
    pub fn name(self) -> &'static str {
        match self {
            SourceKind::Light => "light",
            SourceKind::Camera => "camera",
        }
    }
}

/// A method's own figures; each group is there for the methods that measure it.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Details {
    /// The `ao` AOV's radius, where it was computed (given, or the median of H).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub ao_radius: Option<f32>,
    /// `adaptive`: rays cast per surface pixel, on average.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub mean_rays_per_pixel: Option<f64>,
    /// `gather` and `cubemap`: where the work ran.
    #[serde(flatten)]
    pub device: Option<DeviceDetails>,
    /// `gather` on the GPU: billions of rays cast per second of tracing.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub grays_per_s: Option<f64>,
    /// `cubemap`.
    #[serde(flatten)]
    pub cubemap: Option<CubemapDetails>,
    /// `photon1` and `photon2`.
    #[serde(flatten)]
    pub photon: Option<PhotonDetails>,
    /// How `seconds.estimate` was measured, where not by timing this image alone (one
    /// output of a multi-output pass).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub timed_as: Option<String>,
}

/// The backend a method ran on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceDetails {
    /// `cpu` or `gpu`: the backend that ran.
    pub backend: String,
    /// The GPU adapter; `null` for the CPU backend.
    pub adapter: Option<String>,
    /// `hardware` or `software` (Mesa's lavapipe): the GPU adapter's class, which a shard's
    /// key holds (the two classes' images differ in the last bits); `null` for the CPU.
    #[serde(default)]
    pub adapter_class: Option<String>,
}

impl DeviceDetails {
    /// The CPU backend.
    pub fn cpu() -> Self {
        DeviceDetails {
            backend: "cpu".into(),
            adapter: None,
            adapter_class: None,
        }
    }

    /// The GPU backend on `adapter`, a software implementation where `software`.
    pub fn gpu(adapter: &str, software: bool) -> Self {
        DeviceDetails {
            backend: "gpu".into(),
            adapter: Some(adapter.into()),
            adapter_class: Some(if software { "software" } else { "hardware" }.into()),
        }
    }
}

/// What the cube map did.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CubemapDetails {
    /// Texels filled: every texel of every hemicube on the GPU; one ray per texel looked up
    /// on the CPU.
    pub texels_rasterised: u64,
    /// Texels of one hemicube, `12 R²`.
    pub texels_per_hemicube: u64,
    /// Lookups (pixel, direction).
    pub lookups: u64,
    /// Lookups whose texel holds no surface within `max_distance`.
    pub escaped_lookups: u64,
}

/// What the photon methods did.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PhotonDetails {
    /// Photons in the map.
    pub photons_stored: usize,
    /// Paths traced to store them.
    pub paths_traced: u64,
    /// Stored photons whose continuation escaped the scene.
    pub escaped_photons: u64,
    /// Map bytes per photon, kd-tree included.
    pub bytes_per_photon: usize,
    /// Surface pixels that gathered no photon (NaN).
    pub holes: u64,
    /// Pixel gathers per second.
    pub gather_queries_per_s: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A report written before the parameters were an object (`hall`'s committed Fig. 11 cube
    /// map, and a photon report made from it with K under its old name `gather`) is read with
    /// its parameters by today's names, the derived values left out.
    #[test]
    fn a_report_with_the_parameters_at_the_top_level_is_read_with_them_as_an_object() {
        let dir = std::env::temp_dir().join(format!("hmdist-flat-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let committed = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/docs/paper-scale/hall/fig11_cubemap.json"
        );
        let cubemap = RenderReport::read(std::path::Path::new(committed)).unwrap();
        let expected = serde_json::json!({
            "rays": 65536, "weighting": "cosine", "cube_res": 64, "gpu_fill": "raster"
        });
        assert_eq!(serde_json::to_value(&cubemap.parameters).unwrap(), expected);
        assert_eq!(cubemap.rays, Some(65536));

        let mut photon: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(committed).unwrap()).unwrap();
        let object = photon.as_object_mut().unwrap();
        for key in ["weighting", "strata", "rounds", "cube_res"] {
            object.remove(key);
        }
        let flat = serde_json::json!({
            "method": "photon2", "rays": null, "photons": 1000, "gather": 20, "source": "light",
            "max_bounces": 1, "absorption": 0.2, "max_radius": null, "normal_filter_cos": 0.9
        });
        object.extend(flat.as_object().unwrap().clone());
        let path = dir.join("photon.json");
        std::fs::write(&path, photon.to_string()).unwrap();
        let photon = RenderReport::read(&path).unwrap();
        let expected = serde_json::json!({
            "photons": 1000, "nearest": 20, "source": "light", "max_bounces": 1,
            "absorption": 0.2f32, "max_radius": null
        });
        assert_eq!(serde_json::to_value(&photon.parameters).unwrap(), expected);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
