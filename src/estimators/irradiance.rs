//! `irradiance`: one-bounce indirect irradiance from the scene's spot light, the quantity an
//! irradiance cache stores and H spaces (docs/guide.md, "Irradiance").
//!
//! The light: the scene's spot light, a point of radiant intensity 1 (per steradian, in scene
//! units) inside its cone and 0 outside, with a hard edge: it lights a point `y` whose
//! direction from the light is within the cone's half angle of its axis (the cone the photon
//! tracer emits into, uniformly over its solid angle).
//!
//! The surfaces: every one Lambertian and two-sided, with reflectance `ρ = 1 − absorption`
//! (the photon tracer's `--absorption`, 0.2 by default as the paper's).
//!
//! - Direct irradiance at `y`, on the side its normal `n_y` faces: `E_d(y) = cos θ_y / r²`
//!   where the light is on that side within the cone and a shadow ray from `y` reaches it
//!   unblocked (`cos θ_y = n_y · (light − y) / r`), else 0. `y` then leaves radiance
//!   `L(y) = ρ / π · E_d(y)` on that side.
//! - Indirect irradiance at a pixel's point `x`: the gather of that radiance over the
//!   hemisphere, `E(x) = 1/M Σ L(y_k) cos θ_k / p(ω_k)` over the gather's M rays (its
//!   directions, sampler, robust origins and `--max-distance`: the rays of `gather` with the
//!   same parameters and seed), `y_k` the ray's first hit seen from its side; an escaped ray
//!   adds 0. With cosine weighting (`p = cos θ / π`) that is `ρ/M Σ E_d(y_k)`.
//!
//! The image's channel is `E`; the AOV `E_direct` is `E_d(x)`, the direct irradiance at the
//! pixel's own point. The report's `rays_cast` counts the gather rays and the shadow rays.

use glam::Vec3;

use super::{
    Aov, AovSample, EstimateContext, Estimator, GBuffer, Gather, PixelJob, PixelPass, PixelWorker, Prepared,
    Tally,
};
use crate::accel::{GatherStart, Hit, RayCaster};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::report::{Details, DeviceDetails, Parameters};
use crate::sampling::{Sampler, Weighting};
use crate::scene::SpotLight;

use super::gather::DEFAULT_RAYS;
use super::photon::DEFAULT_ABSORPTION;

/// The EXR channel of an irradiance image, where an image of H has `Y`.
pub const CHANNEL: &str = "E";

/// The PNG's default scale for an irradiance image of a scene with bounding-box diagonal
/// `l_diag` (grey = clamp(scale · E)). E has units of 1/length² (the light's intensity is 1),
/// so the scale is a multiple of `l_diag²`: white at E = 1.6 / l_diag², about the 99th
/// percentile of `cube`'s and `hall`'s images (1.7 and 1.2 / l_diag²).
pub fn display_scale(l_diag: f32) -> f32 {
    l_diag * l_diag / 1.6
}

/// `irradiance`'s parameters: the gather's rays, weighting and sampler, and the surfaces'
/// absorption (the CLI's flags, Python's keywords).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct IrradianceParams {
    /// Gather rays M per pixel (per record, for `hmdist cache`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = DEFAULT_RAYS))]
    pub rays: u32,
    /// Direction weighting over the hemisphere.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Weighting::Cosine))]
    pub weighting: Weighting,
    /// How the directions fill the hemisphere.
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Sampler::Sobol))]
    pub sampler: Sampler,
    /// Absorption of every surface: its reflectance is ρ = 1 − absorption.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = DEFAULT_ABSORPTION))]
    pub absorption: f32,
}

impl Default for IrradianceParams {
    fn default() -> Self {
        IrradianceParams {
            rays: DEFAULT_RAYS,
            weighting: Weighting::default(),
            sampler: Sampler::default(),
            absorption: DEFAULT_ABSORPTION,
        }
    }
}

impl super::params::MethodParams for IrradianceParams {}

impl IrradianceParams {
    /// The estimator these parameters name, checked: at least 1 ray, absorption in [0, 1].
    pub fn build(&self) -> Result<Irradiance> {
        if !(0.0..=1.0).contains(&self.absorption) {
            let message = format!("must be in [0, 1], not {}", self.absorption);
            return Err(Error::invalid("absorption", message));
        }
        let gather = Gather::new(self.rays, self.weighting)?.with_sampler(self.sampler)?;
        Ok(Irradiance {
            params: self.clone(),
            gather,
        })
    }
}

/// One-bounce indirect irradiance from the scene's spot light.
pub struct Irradiance {
    params: IrradianceParams,
    /// The gather whose rays it casts.
    gather: Gather,
}

impl Irradiance {
    /// The surfaces' reflectance ρ.
    pub fn reflectance(&self) -> f32 {
        1.0 - self.params.absorption
    }

    /// The indirect irradiance at `hit` (its normal facing the side gathered over) from
    /// `light`, with the random numbers of `key`: E, and the rays cast (gather and shadow).
    /// `observe` sees each gather ray's hit distance (`+inf` for an escape), its local
    /// direction (z along the normal) and its term of E (E is their mean): what an irradiance
    /// cache's record spaces itself by and takes its gradients from.
    pub(crate) fn at<R: RayCaster>(
        &self,
        accel: &R,
        light: &Spot,
        hit: &Hit,
        (seed, key): (u64, u64),
        t_max: f32,
        mut observe: impl FnMut(f32, Vec3, f32),
    ) -> (f32, Tally) {
        let start = GatherStart::at_hit(hit);
        let rho = self.reflectance() as f64;
        let mut tally = Tally::default();
        let mut sum = 0.0f64;
        for (j, w) in self.gather.directions(seed, key).enumerate() {
            // A point of millions of rays still stops soon after an interruption (its E is
            // never seen: the pass or the cache ends with Error::Interrupted).
            if j % INTERRUPT_POLL == INTERRUPT_POLL - 1 && crate::interrupt::requested() {
                break;
            }
            let direction = start.frame.to_world(w);
            tally.rays += 1;
            let hit = accel.closest_hit(start.origin, direction, t_max, start.leaving);
            let Some(mut y) = hit else {
                tally.escaped += 1;
                observe(f32::INFINITY, w, 0.0);
                continue;
            };
            if y.normal.dot(direction) > 0.0 {
                y.normal = -y.normal;
            }
            let (direct, shadow_rays) = direct_irradiance(accel, light, &y);
            tally.rays += shadow_rays;
            // cos θ / p(ω): 1/π for cosine weighting, 2 cos θ for uniform (times π/π).
            let weight = match self.params.weighting {
                Weighting::Cosine => 1.0,
                Weighting::Uniform => 2.0 * w.z as f64,
            };
            let term = direct as f64 * weight;
            observe(y.t, w, (rho * term) as f32);
            sum += term;
        }
        let e = rho * sum / self.params.rays as f64;
        (e as f32, tally)
    }
}

/// Gather rays between two looks at the interruption flag within one point.
const INTERRUPT_POLL: usize = 4096;

/// A spot light as the direct irradiance reads it, its cone's cosine worked out once (not per
/// ray).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Spot {
    position: Vec3,
    direction: Vec3,
    /// Cosine of the cone's half angle: a direction from the light lies inside when its cosine
    /// with the axis is at least this.
    cone_cos: f32,
}

impl From<SpotLight> for Spot {
    fn from(light: SpotLight) -> Spot {
        Spot {
            position: light.position,
            direction: light.direction,
            cone_cos: light.cone_half_angle_deg.to_radians().cos(),
        }
    }
}

/// The scene's spot light, which irradiance needs: a scene without one is refused by name.
pub(crate) fn light_of(scene: &crate::scene::Scene) -> Result<Spot> {
    scene.light.map(Spot::from).ok_or_else(|| {
        let message = format!(
            "'{}' has no spot light, and irradiance needs one: {}",
            scene.name,
            crate::scene::procedural::light_advice(scene)
        );
        Error::invalid("scene", message)
    })
}

/// The direct irradiance at `hit` from `light` on the side its normal faces (the module's
/// `E_d`), and the shadow rays cast for it (0 or 1).
pub(crate) fn direct_irradiance<R: RayCaster>(accel: &R, light: &Spot, hit: &Hit) -> (f32, u64) {
    let to_light = light.position - hit.point;
    let r2 = to_light.length_squared();
    if r2 == 0.0 || !r2.is_finite() {
        return (0.0, 0);
    }
    let l = to_light / r2.sqrt();
    let cos_y = hit.normal.dot(l);
    if cos_y <= 0.0 || (-l).dot(light.direction) < light.cone_cos {
        return (0.0, 0);
    }
    let origin = hit.spawn_origin(l);
    let reach = (light.position - origin).length();
    let blocked = accel
        .hit_distance(origin, l, reach, Some(hit.triangle))
        .is_finite();
    (if blocked { 0.0 } else { cos_y / r2 }, 1)
}

impl Estimator for Irradiance {
    fn method(&self) -> &'static str {
        "irradiance"
    }

    fn channel(&self) -> &'static str {
        CHANNEL
    }

    fn display_scale(&self, scene: &crate::scene::Scene) -> f32 {
        display_scale(scene.bounds().diagonal())
    }

    fn parameters(&self) -> Parameters {
        Parameters::of(&self.params, &[])
    }

    fn aovs(&self) -> &'static [Aov] {
        &[Aov::EDirect]
    }

    fn samples(&self) -> super::Samples {
        super::Samples::Unsuited("it filters H's mean of 1/d, and this image is irradiance, not H")
    }

    fn expected_rays(&self, pixels: u64) -> u64 {
        // Gather rays, and a shadow ray from each that hits.
        2 * pixels * self.params.rays as u64
    }

    fn prepare<'a>(
        &'a self,
        context: &'a EstimateContext<'a>,
        _: &'a GBuffer,
        _: &dyn Progress,
    ) -> Result<Prepared<'a>> {
        let light = light_of(context.scene)?;
        Ok(Prepared::Pixels {
            job: Box::new(IrradiancePixels {
                irradiance: self,
                context,
                light,
            }),
            phases: Default::default(),
            rays: None,
        })
    }
}

/// `irradiance` on one image.
struct IrradiancePixels<'a> {
    irradiance: &'a Irradiance,
    context: &'a EstimateContext<'a>,
    light: Spot,
}

impl PixelJob for IrradiancePixels<'_> {
    fn label(&self) -> &'static str {
        "irradiance"
    }

    fn casts_rays(&self) -> bool {
        true
    }

    fn worker<'w>(&'w self, _: &'w dyn Progress) -> Box<dyn PixelWorker + 'w> {
        Box::new(IrradianceWorker { pixels: self })
    }

    fn details(&self, _: &PixelPass) -> Details {
        Details {
            device: Some(DeviceDetails::cpu()),
            ..Details::default()
        }
    }
}

struct IrradianceWorker<'w> {
    pixels: &'w IrradiancePixels<'w>,
}

impl PixelWorker for IrradianceWorker<'_> {
    fn pixel(&mut self, hit: &Hit, pixel: u64, tally: &mut Tally, aov: &mut AovSample) -> f32 {
        let (c, light) = (self.pixels.context, &self.pixels.light);
        let (e, cast) =
            self.pixels
                .irradiance
                .at(c.accel, light, hit, (c.seed, pixel), c.clamp.max, |_, _, _| {});
        *tally = *tally + cast;
        if c.aovs.contains(&Aov::EDirect) {
            let (direct, shadow_rays) = direct_irradiance(c.accel, light, hit);
            aov.e_direct = direct;
            tally.rays += shadow_rays;
        }
        e
    }
}

/// The indirect irradiance at a floor point straight below a point light of intensity 1
/// at height `h` between an infinite floor (z = 0) and an infinite ceiling (z = `c`), both
/// of reflectance `rho`: only the ceiling is seen, lit at radius `s` by `(c − h) / (s² +
/// (c − h)²)^{3/2}`, so with `s = c·tan φ`
/// `E = 2 ρ (c − h) ∫₀^{π/2} sin φ cos φ / ((c − h)² + c² tan² φ)^{3/2} dφ`
/// (Simpson's rule, `steps` even).
#[cfg(test)]
pub(crate) fn between_planes(rho: f64, c: f64, h: f64, steps: usize) -> f64 {
    let a = c - h;
    let f = |phi: f64| {
        let t = phi.tan();
        phi.sin() * phi.cos() / (a * a + c * c * t * t).powf(1.5)
    };
    let end = std::f64::consts::FRAC_PI_2;
    let step = end / steps as f64;
    let inner: f64 = (1..steps)
        .map(|i| f(i as f64 * step) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    // f(π/2) is 0 in the limit (tan φ grows without bound).
    let integral = step / 3.0 * (f(0.0) + inner);
    2.0 * rho * a * integral
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Accel, BuildQuality};
    use crate::scene::Mesh;

    /// A square of half-width `w` at height `z`.
    fn square(mesh: &mut Mesh, w: f32, z: f32) {
        let first = mesh.add_vertices([
            Vec3::new(-w, -w, z),
            Vec3::new(w, -w, z),
            Vec3::new(w, w, z),
            Vec3::new(-w, w, z),
        ]);
        mesh.add_triangle(first, first + 1, first + 2);
        mesh.add_triangle(first, first + 2, first + 3);
    }

    /// Floor and ceiling (1 apart, 400 wide: "infinite" to 1e-9), and what is asked.
    fn planes(extra: impl FnOnce(&mut Mesh)) -> Accel {
        let mut mesh = Mesh::new();
        square(&mut mesh, 200.0, 0.0);
        square(&mut mesh, 200.0, 1.0);
        extra(&mut mesh);
        Accel::build(&mesh, BuildQuality::High)
    }

    fn floor_point(x: f32, y: f32) -> Hit {
        Hit {
            t: 1.0,
            triangle: 0,
            point: Vec3::new(x, y, 0.0),
            point_error: Vec3::ZERO,
            normal: Vec3::Z,
        }
    }

    fn light_at(h: f32) -> SpotLight {
        SpotLight {
            position: Vec3::new(0.0, 0.0, h),
            direction: Vec3::Z,
            cone_half_angle_deg: 180.0,
        }
    }

    fn estimator(rays: u32, weighting: Weighting) -> Irradiance {
        IrradianceParams {
            rays,
            weighting,
            ..IrradianceParams::default()
        }
        .build()
        .unwrap()
    }

    #[test]
    fn the_quadrature_agrees_with_itself_and_a_limit() {
        // Converged: halving the step changes nothing at 1e-10.
        let (coarse, fine) = (
            between_planes(0.8, 1.0, 0.5, 20_000),
            between_planes(0.8, 1.0, 0.5, 40_000),
        );
        assert!((coarse - fine).abs() < 1e-10 * fine, "{coarse} {fine}");
        // A light at the floor (h → 0) over a ceiling at c: E → 2ρ c ∫ sin cos / (c sec φ)³
        // = 2ρ/c² ∫ sin φ cos⁴ φ dφ = 2ρ / (5 c²).
        let low = between_planes(1.0, 1.0, 1e-9, 40_000);
        assert!((low - 0.4).abs() < 1e-6, "{low}");
    }

    #[test]
    fn a_point_light_between_two_planes_gives_the_closed_form() {
        let accel = planes(|_| {});
        for (h, weighting, rays) in [
            (0.5, Weighting::Cosine, 16_384),
            (0.25, Weighting::Cosine, 16_384),
            (0.5, Weighting::Uniform, 65_536),
        ] {
            let expected = between_planes(0.8, 1.0, h as f64, 40_000);
            let irradiance = estimator(rays, weighting);
            let keys = 8;
            let mean: f64 = (0..keys)
                .map(|key| {
                    let (e, tally) = irradiance.at(
                        &accel,
                        &light_at(h).into(),
                        &floor_point(0.0, 0.0),
                        (1, key),
                        f32::INFINITY,
                        |_, _, _| {},
                    );
                    assert!(tally.rays >= rays as u64 && tally.rays <= 2 * rays as u64);
                    e as f64
                })
                .sum::<f64>()
                / keys as f64;
            let error = (mean - expected).abs() / expected;
            assert!(
                error < 0.005,
                "h {h}, {weighting:?}: {mean} against {expected} ({error})"
            );
        }
    }

    #[test]
    fn a_light_the_point_cannot_see_by_one_bounce_gives_zero() {
        // Above the ceiling: its lower side, all the floor point sees, is dark.
        let accel = planes(|_| {});
        let irradiance = estimator(1_024, Weighting::Cosine);
        let (e, _) = irradiance.at(
            &accel,
            &light_at(1.5).into(),
            &floor_point(0.0, 0.0),
            (1, 0),
            f32::INFINITY,
            |_, _, _| {},
        );
        assert_eq!(e, 0.0);
        // Between the planes, but its cone turned away from the ceiling (a hard edge at 80°
        // around -z lights only the floor, which the floor point does not see).
        let down = SpotLight {
            direction: -Vec3::Z,
            cone_half_angle_deg: 80.0,
            ..light_at(0.5)
        };
        let (e, _) = irradiance.at(
            &accel,
            &down.into(),
            &floor_point(0.0, 0.0),
            (1, 0),
            f32::INFINITY,
            |_, _, _| {},
        );
        assert_eq!(e, 0.0);
        // Gathered only within a max distance shorter than the ceiling's: nothing is met.
        let (e, tally) = irradiance.at(
            &accel,
            &light_at(0.5).into(),
            &floor_point(0.0, 0.0),
            (1, 0),
            0.9,
            |_, _, _| {},
        );
        assert_eq!((e, tally.escaped), (0.0, 1_024));
    }

    #[test]
    fn direct_irradiance_is_the_inverse_square_law_unless_shadowed() {
        let light = Spot::from(light_at(0.5));
        let open = planes(|_| {});
        let (e, rays) = direct_irradiance(&open, &light, &floor_point(0.0, 0.0));
        assert_eq!((e, rays), (1.0 / 0.25, 1));
        // At (0.5, 0): r² = 0.5, cos θ = 0.5 / √0.5.
        let (e, _) = direct_irradiance(&open, &light, &floor_point(0.5, 0.0));
        let expected = (0.5 / 0.5f32.sqrt()) / 0.5;
        assert!((e - expected).abs() < 1e-6 * expected, "{e} {expected}");
        // A small square between the light and the point shadows it.
        let shaded = planes(|mesh| square(mesh, 0.05, 0.25));
        let (e, rays) = direct_irradiance(&shaded, &light, &floor_point(0.0, 0.0));
        assert_eq!((e, rays), (0.0, 1));
        // Seen from below, the floor is dark: no shadow ray is cast.
        let mut below = floor_point(0.0, 0.0);
        below.normal = -Vec3::Z;
        assert_eq!(direct_irradiance(&open, &light, &below), (0.0, 0));
    }

    #[test]
    fn absorption_outside_zero_to_one_is_refused_by_name() {
        for absorption in [-0.1, 1.5, f32::NAN] {
            let err = IrradianceParams {
                absorption,
                ..IrradianceParams::default()
            }
            .build()
            .err()
            .unwrap();
            assert!(err.to_string().contains("absorption"), "{err}");
        }
    }
}
