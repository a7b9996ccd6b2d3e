//! Where an irradiance-cache record's radius comes from (`--spacing`), and the clamps that
//! renderers put on it (`--clamp-pixels`, `--clamp-scene`).

use glam::Vec3;
use serde_json::{Map, Value};

use crate::error::{Error, Result};
use crate::estimators::{registry, DistanceClamp, Estimator, HarmonicMean, HMD_CHANNEL};

/// Where a record's radius R comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Spacing {
    /// H of the record's own gather rays (Ward 1988).
    Hmd,
    /// H from a registered estimator with its parameters, at the record's point: the paper's
    /// methods as record spacers (`hmd:gather:rays=64`, `hmd:photon2:photons=100000`).
    Estimator {
        /// The method's name.
        method: String,
        /// Its parameters, by name (the others keep their defaults).
        params: Map<String, Value>,
    },
    /// pbrt-v2: half the smallest hit distance of the record's rays.
    Min,
    /// Mitsuba 0.6: the smallest hit distance of the record's rays more than 10° above its
    /// tangent plane.
    Min10,
    /// H from a reference image of H at the record's pixel: the best any estimator could do.
    Oracle,
}

/// What `--spacing` takes, for messages.
const SOURCES: &str = "hmd, hmd:METHOD[:NAME=VALUE,...], min, min10, oracle";

impl Spacing {
    /// `hmd`, `min`, `min10`, `oracle`, or `hmd:METHOD` with optional parameters
    /// `hmd:METHOD:NAME=VALUE,...` (values read as JSON where they are, else as text). A
    /// method that does not estimate H, or a parameter it does not read, is refused by name.
    pub fn parse(text: &str) -> Result<Spacing> {
        let bad = |why: String| Error::invalid("spacing", why);
        match text {
            "hmd" => return Ok(Spacing::Hmd),
            "min" => return Ok(Spacing::Min),
            "min10" => return Ok(Spacing::Min10),
            "oracle" => return Ok(Spacing::Oracle),
            _ => {}
        }
        let Some(rest) = text.strip_prefix("hmd:") else {
            return Err(bad(format!("'{text}' is not one of {SOURCES}")));
        };
        let (method, list) = rest.split_once(':').unwrap_or((rest, ""));
        let mut params = Map::new();
        for pair in list.split(',').filter(|p| !p.is_empty()) {
            let (name, value) = pair
                .split_once('=')
                .ok_or_else(|| bad(format!("'{pair}' in '{text}' is not NAME=VALUE")))?;
            let value = serde_json::from_str(value).unwrap_or_else(|_| Value::String(value.into()));
            if params.insert(name.trim().into(), value).is_some() {
                return Err(bad(format!("'{text}' names {} twice", name.trim())));
            }
        }
        let spacing = Spacing::Estimator {
            method: method.into(),
            params,
        };
        spacing.estimator()?;
        Ok(spacing)
    }

    /// The estimator of H this spacing takes, built (`None` for the others).
    pub fn estimator(&self) -> Result<Option<Box<dyn Estimator>>> {
        let Spacing::Estimator { method, params } = self else {
            return Ok(None);
        };
        let refuse = |e: Error| self.blame(e);
        if registry::METHODS.iter().all(|m| m.name != method) {
            // The methods that estimate H: what hmd: takes (not irradiance).
            let of_h: Vec<&str> = registry::METHODS
                .iter()
                .filter(|m| {
                    m.build(&Map::new(), &[])
                        .is_ok_and(|e| e.channel() == HMD_CHANNEL)
                })
                .map(|m| m.name)
                .collect();
            let message = format!("hmd:{method}: '{method}' is not one of {}", of_h.join(", "));
            return Err(Error::invalid("spacing", message));
        }
        let estimator = registry::method(method)
            .and_then(|entry| entry.build(params, &[]))
            .map_err(refuse)?;
        if estimator.channel() != HMD_CHANNEL {
            let message = format!("hmd:{method}: {method} does not estimate H");
            return Err(Error::invalid("spacing", message));
        }
        Ok(Some(estimator))
    }

    /// `error`, from this spacing's estimator, as an error of `--spacing`: a parameter named
    /// inside it (`hmd:photon2:photon_map=...`) is no flag of the command's own. Other errors
    /// (a file's, a device's) keep their kind.
    pub fn blame(&self, error: Error) -> Error {
        let Spacing::Estimator { method, .. } = self else {
            return error;
        };
        let why = match error {
            Error::Parameter {
                name: Some(name),
                message,
            } => format!("{name} {message}"),
            Error::Parameter { name: None, message } => message,
            other => return other,
        };
        Error::invalid("spacing", format!("hmd:{method}: {why}"))
    }

    /// The files this spacing's parameters name that exist (`hmd:photon2:...,photon_map=p.map`):
    /// inputs of the cache, which no output may overwrite.
    pub fn files_read(&self) -> Vec<std::path::PathBuf> {
        let Spacing::Estimator { params, .. } = self else {
            return vec![];
        };
        params
            .values()
            .filter_map(Value::as_str)
            .map(std::path::PathBuf::from)
            .filter(|path| path.is_file())
            .collect()
    }

    /// The name `--spacing` takes for it.
    pub fn name(&self) -> String {
        match self {
            Spacing::Hmd => "hmd".into(),
            Spacing::Min => "min".into(),
            Spacing::Min10 => "min10".into(),
            Spacing::Oracle => "oracle".into(),
            Spacing::Estimator { method, params } if params.is_empty() => format!("hmd:{method}"),
            Spacing::Estimator { method, params } => {
                let list: Vec<String> = params
                    .iter()
                    .map(|(name, value)| match value {
                        Value::String(text) => format!("{name}={text}"),
                        value => format!("{name}={value}"),
                    })
                    .collect();
                format!("hmd:{method}:{}", list.join(","))
            }
        }
    }
}

/// A clamp `[lo, hi]` in some unit (pixel footprints, or fractions of `l_diag`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Range {
    /// The least value, in the unit.
    pub lo: f32,
    /// The greatest.
    pub hi: f32,
}

impl Range {
    /// `LO,HI` (0 ≤ LO ≤ HI, both finite); `name` is the parameter's, for the message.
    pub fn parse(name: &'static str, text: &str) -> Result<Range> {
        let bad = || Error::invalid(name, format!("'{text}' is not LO,HI with 0 <= LO <= HI"));
        let (lo, hi) = text.split_once(',').ok_or_else(bad)?;
        let (lo, hi): (f32, f32) = (
            lo.trim().parse().map_err(|_| bad())?,
            hi.trim().parse().map_err(|_| bad())?,
        );
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
            return Err(bad());
        }
        Ok(Range { lo, hi })
    }

    /// `r` clamped to `[lo·unit, hi·unit]`.
    pub fn apply(&self, r: f32, unit: f32) -> f32 {
        r.max(self.lo * unit).min(self.hi * unit)
    }
}

/// sin 10°: a ray whose local z is above it leaves more than 10° above the tangent plane.
const SIN_10_DEG: f32 = 0.173_648_18;

/// What a record's own gather rays say of its surroundings: their H, their smallest hit
/// distance, and the smallest of those more than 10° above the tangent plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OwnRays {
    clamp: DistanceClamp,
    mean: HarmonicMean,
    min: f32,
    min10: f32,
}

impl OwnRays {
    /// None seen yet; distances clamped as the gather clamps them.
    pub fn new(clamp: DistanceClamp) -> Self {
        OwnRays {
            clamp,
            mean: HarmonicMean::default(),
            min: f32::INFINITY,
            min10: f32::INFINITY,
        }
    }

    /// A ray in local direction `w` (z along the normal) that met a surface at `t` (`+inf`:
    /// it escaped).
    pub fn add(&mut self, t: f32, w: Vec3) {
        self.mean.add(t, self.clamp);
        self.min = self.min.min(t);
        if w.z > SIN_10_DEG {
            self.min10 = self.min10.min(t);
        }
    }

    /// The radius `spacing` takes from these rays (`None`: it takes it from elsewhere).
    pub fn radius(&self, spacing: &Spacing) -> Option<f32> {
        match spacing {
            Spacing::Hmd => Some(self.hmd()),
            Spacing::Min => Some(self.min / 2.0),
            Spacing::Min10 => Some(self.min10),
            Spacing::Oracle | Spacing::Estimator { .. } => None,
        }
    }

    /// H of the rays.
    pub fn hmd(&self) -> f32 {
        self.mean.value()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_source_parses_and_names_itself_back() {
        for text in [
            "hmd",
            "min",
            "min10",
            "oracle",
            "hmd:gather",
            "hmd:gather:rays=16",
            "hmd:photon2:nearest=32,photons=5000",
        ] {
            assert_eq!(Spacing::parse(text).unwrap().name(), text);
        }
        let Spacing::Estimator { params, .. } =
            Spacing::parse("hmd:photon1:photons=5000,source=camera").unwrap()
        else {
            panic!("an estimator");
        };
        assert_eq!(params["photons"], 5000);
        assert_eq!(params["source"], "camera");
    }

    #[test]
    fn a_bad_source_is_refused_by_name() {
        for (text, says) in [
            ("nearest", "is not one of"),
            (
                "hmd:magic",
                "'magic' is not one of gather, adaptive, cubemap, photon1, photon2",
            ),
            ("hmd:irradiance", "does not estimate H"),
            ("hmd:gather:photons=9", "photons"),
            ("hmd:gather:rays", "NAME=VALUE"),
            ("hmd:gather:rays=64,rays=32", "names rays twice"),
        ] {
            let err = Spacing::parse(text).err().unwrap();
            let message = err.to_string();
            assert!(message.contains(says), "{text}: {message}");
            assert!(
                matches!(
                    err,
                    Error::Parameter {
                        name: Some("spacing"),
                        ..
                    }
                ),
                "{text}"
            );
        }
    }

    #[test]
    fn ranges_parse_and_clamp() {
        let range = Range::parse("clamp_pixels", "2.5,15").unwrap();
        assert_eq!(range.apply(1.0, 2.0), 5.0);
        assert_eq!(range.apply(100.0, 2.0), 30.0);
        assert_eq!(range.apply(10.0, 2.0), 10.0);
        for bad in ["3", "5,2", "-1,2", "a,b", "1,inf"] {
            assert!(Range::parse("clamp_pixels", bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn min_and_min10_under_a_low_ceiling_beside_a_wall_are_the_wall_and_its_ten_degree_distance() {
        use crate::accel::{Accel, BuildQuality, Hit};
        use crate::estimators::IrradianceParams;
        use crate::scene::{Mesh, SpotLight};
        // A floor point at the origin, a ceiling 1 above it and a wall 0.2 beside it (x = 0.2),
        // each 400 wide. The nearest hit is the wall, straight along the floor: 0.2 (min: 0.1).
        // Above 10° of the floor, the nearest is the wall at 10°: 0.2 / cos 10° (the ceiling is
        // 1 / sin 10° = 5.8 away there).
        let mut mesh = Mesh::new();
        let mut quad = |corners: [[f32; 3]; 4]| {
            let first = mesh.add_vertices(corners.map(Vec3::from));
            mesh.add_triangle(first, first + 1, first + 2);
            mesh.add_triangle(first, first + 2, first + 3);
        };
        let w = 200.0;
        quad([[-w, -w, 0.0], [w, -w, 0.0], [w, w, 0.0], [-w, w, 0.0]]);
        quad([[-w, -w, 1.0], [w, -w, 1.0], [w, w, 1.0], [-w, w, 1.0]]);
        quad([[0.2, -w, -w], [0.2, w, -w], [0.2, w, w], [0.2, -w, w]]);
        let accel = Accel::build(&mesh, BuildQuality::High);
        let irradiance = IrradianceParams {
            rays: 65_536,
            ..IrradianceParams::default()
        }
        .build()
        .unwrap();
        let light = SpotLight {
            position: Vec3::new(-0.5, 0.0, 0.5),
            direction: Vec3::Z,
            cone_half_angle_deg: 180.0,
        };
        let hit = Hit {
            t: 1.0,
            triangle: 0,
            point: Vec3::ZERO,
            point_error: Vec3::ZERO,
            normal: Vec3::Z,
        };
        let mut own = OwnRays::new(DistanceClamp::for_diagonal(400.0, None));
        irradiance.at(&accel, &light.into(), &hit, (1, 7), f32::INFINITY, |t, w, _| {
            own.add(t, w)
        });
        let min = own.radius(&Spacing::Min).unwrap();
        assert!((0.1 * 0.9999..0.1 * 1.01).contains(&min), "min {min}");
        let limit = 0.2 / 10f32.to_radians().cos();
        let min10 = own.radius(&Spacing::Min10).unwrap();
        assert!(
            (limit * 0.9999..limit * 1.02).contains(&min10),
            "min10 {min10}, limit {limit}"
        );
    }

    #[test]
    fn own_rays_give_h_the_minimum_and_the_minimum_above_ten_degrees() {
        let mut own = OwnRays::new(DistanceClamp::for_diagonal(10.0, None));
        own.add(1.0, Vec3::new(0.99, 0.0, 0.1)); // 5.7° above the plane
        own.add(2.0, Vec3::Z);
        own.add(f32::INFINITY, Vec3::Z);
        assert_eq!(own.radius(&Spacing::Min), Some(0.5));
        assert_eq!(own.radius(&Spacing::Min10), Some(2.0));
        // H = 3 / (1 + 1/2 + 0).
        assert_eq!(own.radius(&Spacing::Hmd), Some(2.0));
        assert_eq!(own.radius(&Spacing::Oracle), None);
    }
}
