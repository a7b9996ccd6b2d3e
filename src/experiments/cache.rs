//! The image cache under `OUT/cache`: each image named by its render key
//! ([`crate::report::RenderKey::digest`]), images of many rays rendered in row parts each
//! cached when done, and the images of earlier versions' keys adopted.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::estimators::{Aov, AovImage, Estimator};
use crate::image::{exr, write_atomically, HmdImage};
use crate::progress::Silent;
use crate::render::{render, RenderOptions};
use crate::report::{RenderKey, RenderReport};
use crate::shard::Shard;

use super::presets::PARTS;
use super::runner::Runner;

impl Runner<'_> {
    /// [`Runner::image`] with `aovs`: they are part of the cache key, and stored as channels
    /// of the cached EXR.
    pub(super) fn image_with(
        &self,
        estimator: &dyn Estimator,
        seed: u64,
        aovs: &[Aov],
    ) -> Result<(HmdImage, RenderReport, Vec<HmdImage>)> {
        crate::interrupt::check()?;
        let size = self.params.size;
        let stem = self.stem(estimator, seed, aovs);
        let (exr_path, json_path) = self.cache_paths(&stem);
        let request = self.shard.as_ref().map(|s| {
            let i = s.requests.get();
            s.requests.set(i + 1);
            (s, i % s.shard.count as u64 == s.shard.index as u64)
        });
        let cached = read_cached(&exr_path, &json_path, aovs);
        if let Some(plan) = &self.plan {
            return self.plan_image(plan, estimator, seed, aovs, stem, cached);
        }
        if let Some(cached) = cached {
            self.first_look(&stem, Some(cached.1.seconds.total));
            return Ok(cached);
        }
        if let Some((s, false)) = request {
            // Another shard's image: a stand-in of the right size.
            s.stand_ins.set(s.stand_ins.get() + 1);
            return Ok(self.stand_in(aovs));
        }
        let options = self.render_options(seed, aovs);
        let rendered = self
            .render_in_parts(estimator, &options, &stem)
            .inspect_err(|_| {
                if let Some((s, _)) = request {
                    s.render_failed.set(true);
                }
            })?;
        if let Some((s, _)) = request {
            s.rendered.set(s.rendered.get() + 1);
        }
        self.cache_image(&stem, &rendered)?;
        self.first_look(&stem, None);
        self.progress.advance(1);
        let channels = rendered
            .aovs
            .into_iter()
            .map(|a| HmdImage::new(size, size, a.data))
            .collect();
        Ok((rendered.image, rendered.report, channels))
    }

    /// Creates the output folder and its cache, which the runner leaves alone until it has
    /// something to write (a run refused for a bad flag creates nothing).
    pub(super) fn make_cache(&self) -> Result<()> {
        if self.cache.exists() && !self.cache.is_dir() {
            let message = "is not a folder: the experiments keep their image cache there (move it away, or take another --out)";
            return Err(Error::file(&self.cache, message));
        }
        std::fs::create_dir_all(&self.cache)
            .map_err(|e| Error::io(&self.cache, "create the image cache folder of", e))
    }

    /// How many parts an image is rendered in: [`PARTS`] where it casts at least
    /// [`PART_RAYS`] rays (or what [`Runner::with_part_rays`] set), else 1.
    pub(super) fn parts(&self, estimator: &dyn Estimator) -> u32 {
        let pixels = self.params.size as u64 * self.params.size as u64;
        if estimator.expected_rays(pixels) >= self.part_rays {
            PARTS
        } else {
            1
        }
    }

    /// The cache stem of part `k` of `parts` of the image `stem`.
    pub(super) fn part_stem(stem: &str, k: u32, parts: u32) -> String {
        format!("{stem}.part-{k}-of-{parts}")
    }

    /// Of the `parts` parts of the image `stem`, those already cached (none for a whole
    /// image).
    pub(super) fn parts_cached(&self, stem: &str, parts: u32) -> u32 {
        if parts == 1 {
            return 0;
        }
        (0..parts)
            .filter(|&k| {
                let part = Self::part_stem(stem, k, parts);
                self.cache.join(format!("{part}.json")).exists()
            })
            .count() as u32
    }

    /// Renders the image `stem` with `options`: see [`Runner::render_outputs_in_parts`].
    pub(super) fn render_in_parts(
        &self,
        estimator: &dyn Estimator,
        options: &RenderOptions,
        stem: &str,
    ) -> Result<crate::render::Rendered> {
        let pass =
            |options: &RenderOptions| render(&self.scene, estimator, options, &Silent).map(|r| vec![r]);
        let mut rendered = self.render_outputs_in_parts(&[estimator], &[stem.to_string()], options, &pass)?;
        Ok(rendered.remove(0))
    }

    /// Renders the images `stems` of `estimators` with `options` by `pass`: whole, or (see
    /// [`Runner::parts`]: the estimator that casts the most decides) as row shards, each
    /// shard's images cached as soon as they are done (an interrupted run keeps the parts it
    /// finished, and the next one renders only the others), then merged (bit for bit the
    /// whole images: [`crate::shard::merge`]) and the parts removed.
    pub(super) fn render_outputs_in_parts(
        &self,
        estimators: &[&dyn Estimator],
        stems: &[String],
        options: &RenderOptions,
        pass: &dyn Fn(&RenderOptions) -> Result<Vec<crate::render::Rendered>>,
    ) -> Result<Vec<crate::render::Rendered>> {
        let count = estimators.iter().map(|e| self.parts(*e)).max().unwrap_or(1);
        if count == 1 {
            return pass(options);
        }
        self.make_cache()?;
        let mut parts: Vec<Vec<crate::shard::Part>> = stems.iter().map(|_| vec![]).collect();
        let mut files = vec![];
        for k in 0..count {
            let paths: Vec<(PathBuf, PathBuf)> = stems
                .iter()
                .map(|stem| {
                    let part = Self::part_stem(stem, k, count);
                    self.cache_paths(&part)
                })
                .collect();
            let cached: Option<Vec<_>> = paths
                .iter()
                .map(|(exr_path, json_path)| read_cached(exr_path, json_path, &options.aovs))
                .collect();
            let outputs = match cached {
                Some(cached) => {
                    let mut earlier = self.earlier_parts.borrow_mut();
                    for (stem, (_, report, _)) in stems.iter().zip(&cached) {
                        *earlier.entry(stem.clone()).or_insert(0.0) += report.seconds.total;
                    }
                    cached
                }
                None => {
                    let options = RenderOptions {
                        shard: Some(Shard::new(k, count)?),
                        ..options.clone()
                    };
                    let mut outputs = vec![];
                    for (rendered, (exr_path, json_path)) in pass(&options)?.into_iter().zip(&paths) {
                        let bytes = rendered.exr(exr_path)?;
                        write_atomically(exr_path, &bytes)?;
                        write_atomically(json_path, rendered.report.to_json().as_bytes())?;
                        let (width, height) = (options.width, options.height);
                        let aovs = rendered
                            .aovs
                            .into_iter()
                            .map(|a| HmdImage::new(width, height, a.data));
                        outputs.push((rendered.image, rendered.report, aovs.collect()));
                    }
                    outputs
                }
            };
            for ((image, report, aovs), output) in outputs.into_iter().zip(&mut parts) {
                let aovs = options
                    .aovs
                    .iter()
                    .zip(aovs)
                    .map(|(&aov, image)| AovImage {
                        aov,
                        data: image.data,
                    })
                    .collect();
                output.push(crate::shard::Part {
                    image,
                    aovs,
                    report,
                    guide: None,
                });
            }
            files.extend(paths.into_iter().flat_map(|(exr, json)| [exr, json]));
        }
        let merged = parts
            .into_iter()
            .map(crate::shard::merge)
            .collect::<Result<Vec<_>>>()?;
        for file in files {
            // The whole images are written next; a part left behind only costs disk.
            let _ = std::fs::remove_file(file);
        }
        Ok(merged)
    }

    /// Where the cache keeps the image `stem`: its EXR and its JSON report.
    pub(super) fn cache_paths(&self, stem: &str) -> (PathBuf, PathBuf) {
        (
            self.cache.join(format!("{stem}.exr")),
            self.cache.join(format!("{stem}.json")),
        )
    }

    /// The cache stem of the image `estimator` renders with `seed` and `aovs` at the preset's
    /// size: the method and the [`RenderKey::digest`] of the image's key as this run asks for
    /// it (the backend and BVH preset as requested: `auto` stays `auto`), the key `merge`
    /// compares and photon maps are checked by. An image cached under the key of earlier
    /// versions ([`Runner::legacy_stems`]) is renamed to this one when first asked for, so
    /// caches on disk stay usable.
    pub(super) fn stem(&self, estimator: &dyn Estimator, seed: u64, aovs: &[Aov]) -> String {
        let key = self.key(estimator, seed, aovs);
        let stem = format!("{}-{:016x}", estimator.method(), key.digest());
        // Only a cache an earlier run left can hold images under the old keys.
        if self.cache.is_dir() {
            for legacy in self.legacy_stems(estimator, &key) {
                self.adopt_legacy(&legacy, &stem);
            }
        }
        stem
    }

    /// The key of the image `estimator` renders with `seed` and `aovs` at the preset's size,
    /// as this run asks for it (the backend and BVH preset as requested: `auto` stays `auto`).
    pub(super) fn key(&self, estimator: &dyn Estimator, seed: u64, aovs: &[Aov]) -> RenderKey {
        let options = self.render_options(seed, aovs);
        let backend = serde_json::to_value(self.backend)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        RenderKey::new(
            (&self.scene.name, self.scene_content),
            (estimator.method(), estimator.parameters()),
            options.bvh_quality.name(),
            options.key_image(),
        )
        .on(&backend, None)
    }

    /// Renames the cached files of `legacy` (the image, and any of its parts) to `stem`'s,
    /// where `stem` has none: the EXR first, then the JSON that marks it cached.
    pub(super) fn adopt_legacy(&self, legacy: &str, stem: &str) {
        let names = std::iter::once((legacy.to_string(), stem.to_string()))
            .chain((0..PARTS).map(|k| (Self::part_stem(legacy, k, PARTS), Self::part_stem(stem, k, PARTS))));
        for (old, new) in names {
            let ((old_exr, old_json), (new_exr, new_json)) = (self.cache_paths(&old), self.cache_paths(&new));
            if old_json.exists() && !new_json.exists() {
                let _ = std::fs::rename(&old_exr, &new_exr);
                let _ = std::fs::rename(&old_json, &new_json);
            }
        }
    }

    /// Writes a rendered image and its report into the cache as `stem`: the JSON last, so
    /// that an image counts as cached only once both files are in place.
    pub(super) fn cache_image(&self, stem: &str, rendered: &crate::render::Rendered) -> Result<()> {
        self.make_cache()?;
        let (exr_path, json_path) = self.cache_paths(stem);
        write_atomically(&exr_path, &rendered.exr(&exr_path)?)?;
        write_atomically(&json_path, rendered.report.to_json().as_bytes())
    }
}

/// The cached image at `exr_path` with its report at `json_path` and its `aovs`, where both
/// files are there and the report is this version's.
pub(super) fn read_cached(
    exr_path: &Path,
    json_path: &Path,
    aovs: &[Aov],
) -> Option<(HmdImage, RenderReport, Vec<HmdImage>)> {
    let image = exr::read(exr_path).ok()?;
    let report = RenderReport::read(json_path).ok()?;
    // The version is in the key; a report that says otherwise was not ours.
    if report.hmdist_version != env!("CARGO_PKG_VERSION") {
        return None;
    }
    let channels = aovs
        .iter()
        .map(|a| exr::read_channel(exr_path, a.name()).ok())
        .collect::<Option<Vec<_>>>()?;
    Some((image, report, channels))
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;

    use super::*;
    use crate::estimators::Backend;
    use crate::estimators::GatherParams;
    use crate::experiments::presets::Preset;

    fn gather_params(rays: u32) -> GatherParams {
        GatherParams {
            rays,
            sampler: crate::sampling::Sampler::Grid,
            ..GatherParams::default()
        }
    }

    /// The parts of an image that an interrupted run cached count, in the run that finishes
    /// the image, with the seconds their reports give; the parts this run renders do not.
    #[test]
    fn parts_an_earlier_run_left_count_with_their_reports_seconds() {
        let out = std::env::temp_dir().join(format!("hmdist-earlier-parts-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let runner = Runner::new("slab", Preset::Quick, &out, &Silent)
            .unwrap()
            .with_size(Some(32))
            .unwrap()
            .with_backend(Backend::Cpu)
            .with_part_rays(1);
        let estimator = runner
            .method_estimator("gather", &gather_params(16), &[])
            .unwrap();
        let stem = runner.stem(estimator.as_ref(), 1, &[]);
        let options = runner.render_options(1, &[]);
        let one = |options: &RenderOptions| {
            render(&runner.scene, estimator.as_ref(), options, &Silent).map(|r| vec![r])
        };
        // The first run stops after three parts.
        let started = Cell::new(0);
        let stopping = |options: &RenderOptions| {
            started.set(started.get() + 1);
            if started.get() > 3 {
                return Err(Error::Interrupted);
            }
            one(options)
        };
        let stems = [stem.clone()];
        assert!(runner
            .render_outputs_in_parts(&[estimator.as_ref()], &stems, &options, &stopping)
            .is_err());
        let left: f64 = (0..3)
            .map(|k| {
                let (exr_path, json_path) = runner.cache_paths(&Runner::part_stem(&stem, k, PARTS));
                read_cached(&exr_path, &json_path, &[]).unwrap().1.seconds.total
            })
            .sum();
        assert!(left > 0.0);
        assert!(
            runner.earlier_parts.borrow().is_empty(),
            "the first run found nothing cached"
        );
        // The next run renders the other parts, takes those three from the cache, and counts them.
        runner.image(estimator.as_ref(), 1).unwrap();
        assert_eq!(runner.first_looks.borrow()[&stem], Some(left));
        // An image rendered whole by this run owes nothing to an earlier one.
        runner.first_look("another", None);
        assert_eq!(runner.first_looks.borrow()["another"], None);
        let _ = std::fs::remove_dir_all(&out);
    }

    /// An image cached under either key of earlier versions is found, not rendered again,
    /// and takes the new key's name.
    #[test]
    fn an_image_cached_under_an_old_key_is_found() {
        let out = std::env::temp_dir().join(format!("hmdist-legacy-key-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let runner = || {
            Runner::new("slab", Preset::Quick, &out, &Silent)
                .unwrap()
                .with_size(Some(16))
                .unwrap()
                .with_backend(Backend::Cpu)
        };
        let first = runner();
        let estimator = first.method_estimator("gather", &gather_params(8), &[]).unwrap();
        let (_, report) = first.image(estimator.as_ref(), 1).unwrap();
        let stem = first.stem(estimator.as_ref(), 1, &[]);
        let key = first.key(estimator.as_ref(), 1, &[]);
        for legacy in first.legacy_stems(estimator.as_ref(), &key) {
            assert_ne!(stem, legacy, "the key changed");
            // As an earlier version would have left it: the image under the old name.
            let (new_exr, new_json) = first.cache_paths(&stem);
            let (old_exr, old_json) = first.cache_paths(&legacy);
            std::fs::rename(&new_exr, &old_exr).unwrap();
            std::fs::rename(&new_json, &old_json).unwrap();
            let (_, found) = runner().image(estimator.as_ref(), 1).unwrap();
            // A render again would have taken other seconds. (Within an ulp or two: the
            // cached report's seconds come back through JSON, whose parse is not always the
            // nearest double.)
            let (a, b) = (found.seconds.total, report.seconds.total);
            assert!((a - b).abs() <= 1e-12 * b, "{a} against {b}: rendered again");
            assert!(new_json.exists() && !old_json.exists(), "renamed to the new key");
        }
        let _ = std::fs::remove_dir_all(&out);
    }
}
