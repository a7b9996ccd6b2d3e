//! Helpers shared by the integration tests.
#![allow(dead_code)]

use hmdist::estimators::Gather;
use hmdist::image::HmdImage;
use hmdist::progress::Silent;
use hmdist::render::{render, RenderOptions};
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

/// Renders `scene` with `rays` cosine- or uniform-weighted gather rays at `width × height`.
pub fn gather(
    scene: &Scene,
    width: u32,
    height: u32,
    rays: u32,
    weighting: Weighting,
    threads: Option<usize>,
) -> (HmdImage, serde_json::Value) {
    let estimator = Gather::new(rays, weighting).unwrap();
    let options = RenderOptions {
        width,
        height,
        threads,
        ..RenderOptions::default()
    };
    let rendered = render(scene, &estimator, &options, 0.0, &Silent).unwrap();
    (rendered.image, rendered.report)
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[v.len() / 2]
}
