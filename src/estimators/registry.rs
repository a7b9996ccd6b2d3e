//! The registry of methods: one entry per estimator, with its name, a sentence on what it is,
//! and its one parameter struct ([`MethodParams`]: [`GatherParams`], [`CubemapParams`], ...),
//! which lives beside the estimator. The CLI's method flags, Python's keywords, the experiments
//! and the tests all build estimators from here, so a parameter is one field in one struct and
//! a new estimator is one module plus one `method!` line in [`METHODS`].
//!
//! Parameters travel between the layers as a JSON object (`{"rays": 256}`): Python's keywords
//! arrive as one, a typed struct serialises to one, and each entry deserialises it into its
//! own struct, refusing by name what its method does not read.

use serde::Serialize;
use serde_json::{Map, Value};

use super::adaptive::AdaptiveParams;
use super::aov::Aov;
use super::cubemap::CubemapParams;
use super::gather::GatherParams;
use super::irradiance::IrradianceParams;
pub use super::params::{Flags, MethodParams};
use super::photon::{PhotonEstimator, PhotonMethod, PhotonParams};
use super::Estimator;
use crate::error::{Error, Result};

/// One method: what the CLI, the experiments and Python know of it. Made by `method!` below.
pub struct MethodEntry {
    /// The name `--method` takes and the report's `method`.
    pub name: &'static str,
    /// One sentence on what it is.
    pub summary: &'static str,
    defaults: fn() -> Map<String, Value>,
    from_object: fn(&Map<String, Value>, &[Aov]) -> Result<Box<dyn Estimator>>,
    #[cfg(feature = "cli")]
    flags: fn(clap::Command) -> clap::Command,
    #[cfg(feature = "cli")]
    from_flags: fn(&clap::ArgMatches, &[Aov]) -> Result<Box<dyn Estimator>>,
}

/// A registry entry: `method!("name", "summary", |p: Params| build)`, where `build` makes the
/// estimator (a `Result<Box<dyn Estimator>>`) from `p`, the parameters with their defaults
/// filled in and adjusted for the AOVs asked for ([`MethodParams::for_aovs`]).
macro_rules! method {
    ($name:literal, $summary:literal, |$p:ident: $params:ty| $build:expr) => {
        MethodEntry {
            name: $name,
            summary: $summary,
            defaults: defaults::<$params>,
            from_object: |object, aovs| {
                let mut $p: $params = from_object($name, object)?;
                $p.for_aovs(aovs);
                $build
            },
            #[cfg(feature = "cli")]
            flags: <$params as clap::Args>::augment_args,
            #[cfg(feature = "cli")]
            from_flags: |matches, aovs| {
                let mut $p: $params = from_flags(matches)?;
                $p.for_aovs(aovs);
                $build
            },
        }
    };
}

/// Every method, in the order `--help` lists them.
pub const METHODS: &[MethodEntry] = &[
    method!(
        "gather",
        "Ray-traced final gathering (docs/spec.md §3.1)",
        |p: GatherParams| Ok(Box::new(p.build()?))
    ),
    method!(
        "adaptive",
        "Final gathering in rounds until H's relative standard error is below --tolerance",
        |p: AdaptiveParams| Ok(Box::new(p.build()?))
    ),
    method!(
        "cubemap",
        "Hemicube rasterisation, looked up with gather's directions (docs/spec.md §3.2)",
        |p: CubemapParams| Ok(Box::new(p.build()?))
    ),
    method!(
        "photon1",
        "Photon map, method I: harmonic mean of the gathered photons' own distances (docs/spec.md §3.3)",
        |p: PhotonParams| Ok(Box::new(PhotonEstimator::new(PhotonMethod::StoredDistance, p)?))
    ),
    method!(
        "photon2",
        "Photon map, method II: distances from the pixel to the photons' next hits (docs/spec.md §3.3)",
        |p: PhotonParams| Ok(Box::new(PhotonEstimator::new(PhotonMethod::NextHitPoint, p)?))
    ),
    method!(
        "irradiance",
        "Not H: one-bounce indirect irradiance from the scene's spot light, gathered with --rays rays (channel E)",
        |p: IrradianceParams| Ok(Box::new(p.build()?))
    ),
];

impl MethodEntry {
    /// The method's parameters with their defaults, by name (`null`: none, or worked out at
    /// render time).
    pub fn defaults(&self) -> Map<String, Value> {
        (self.defaults)()
    }

    /// The names of the method's parameters, in its struct's order.
    pub fn parameters(&self) -> Vec<String> {
        self.defaults().keys().cloned().collect()
    }

    /// Whether the method reads parameter `name`.
    pub fn reads(&self, name: &str) -> bool {
        self.defaults().contains_key(name)
    }

    /// The estimator with `params` (any subset of [`MethodEntry::parameters`]; the others
    /// keep their defaults), for an image with `aovs`. A name the method does not read, or a
    /// value of the wrong type, is an [`Error::Parameter`] that names it.
    pub fn build(&self, params: &Map<String, Value>, aovs: &[Aov]) -> Result<Box<dyn Estimator>> {
        (self.from_object)(params, aovs)
    }

    /// The estimator with the method flags of a command line that [`flags`] made, for an image
    /// with `aovs`. A flag given on the command line that this method does not read (`--rays`
    /// with `photon2`) is refused by name.
    #[cfg(feature = "cli")]
    pub fn build_from_flags(&self, matches: &clap::ArgMatches, aovs: &[Aov]) -> Result<Box<dyn Estimator>> {
        let own = (self.flags)(clap::Command::new(self.name));
        let own_ids: Vec<&clap::Id> = own.get_arguments().map(|a| a.get_id()).collect();
        let spell = |arg: &clap::Arg| format!("--{}", arg.get_long().unwrap_or(arg.get_id().as_str()));
        let unread: Vec<String> = every_flag()
            .iter()
            .filter(|(arg, _)| !own_ids.contains(&arg.get_id()))
            .filter(|(arg, _)| {
                matches.value_source(arg.get_id().as_str()) == Some(clap::parser::ValueSource::CommandLine)
            })
            .map(|(arg, _)| spell(arg))
            .collect();
        if !unread.is_empty() {
            let reads: Vec<String> = own.get_arguments().map(spell).collect();
            let message = format!(
                "{} does not read {} (its flags: {})",
                self.name,
                unread.join(", "),
                reads.join(", ")
            );
            return Err(Error::invalid("method", message));
        }
        (self.from_flags)(matches, aovs)
    }
}

/// Every method's flags, each once (in registry order), with the methods that read it.
#[cfg(feature = "cli")]
fn every_flag() -> Vec<(clap::Arg, Vec<&'static str>)> {
    let mut flags: Vec<(clap::Arg, Vec<&'static str>)> = vec![];
    for entry in METHODS {
        for arg in (entry.flags)(clap::Command::new(entry.name)).get_arguments() {
            match flags.iter_mut().find(|(a, _)| a.get_id() == arg.get_id()) {
                Some((_, readers)) => readers.push(entry.name),
                None => flags.push((arg.clone(), vec![entry.name])),
            }
        }
    }
    flags
}

/// The ids of every method's flags (`photon_map`, `rays`, ...): which of a command's matches
/// are the methods'.
#[cfg(feature = "cli")]
pub fn flag_ids() -> Vec<String> {
    every_flag()
        .iter()
        .map(|(arg, _)| arg.get_id().to_string())
        .collect()
}

/// `cmd` with every method's flags, each once; a flag's help ends with the methods that read
/// it. [`MethodEntry::build_from_flags`] takes the matches.
#[cfg(feature = "cli")]
pub fn flags(cmd: clap::Command) -> clap::Command {
    every_flag().into_iter().fold(cmd, |cmd, (arg, readers)| {
        let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
        let help = format!("{help} [--method {}]", readers.join(", "));
        // Listed where they are added, after the command's own flags declared before them.
        cmd.arg(arg.help(help).display_order(None))
    })
}

/// The method called `name`.
pub fn method(name: &str) -> Result<&'static MethodEntry> {
    METHODS.iter().find(|m| m.name == name).ok_or_else(|| {
        let names: Vec<&str> = METHODS.iter().map(|m| m.name).collect();
        Error::invalid("method", format!("'{name}' is not one of {}", names.join(", ")))
    })
}

/// Method `name` with `params` (a method's parameter struct, or any value that serialises to
/// an object naming some of its parameters, such as `serde_json::json!({"rays": 16})`), for
/// an image with `aovs`: see [`MethodEntry::build`].
pub fn build(name: &str, params: &impl Serialize, aovs: &[Aov]) -> Result<Box<dyn Estimator>> {
    method(name)?.build(&object(params)?, aovs)
}

/// `params` as a JSON object.
pub fn object(params: &impl Serialize) -> Result<Map<String, Value>> {
    match serde_json::to_value(params) {
        Ok(Value::Object(map)) => Ok(map),
        Ok(Value::Null) => Ok(Map::new()),
        Ok(other) => Err(Error::parameter(format!(
            "method parameters must be named, not {other}"
        ))),
        Err(e) => Err(Error::parameter(format!("method parameters: {e}"))),
    }
}

/// `P`'s defaults as a JSON object.
fn defaults<P: MethodParams>() -> Map<String, Value> {
    match serde_json::to_value(P::default()) {
        Ok(Value::Object(map)) => map,
        _ => unreachable!("a parameter struct serialises to an object"),
    }
}

/// `object` as method `name`'s parameters: each key is checked alone first, so that an
/// unknown name or a bad value is an error that names it.
fn from_object<P: MethodParams>(name: &str, object: &Map<String, Value>) -> Result<P> {
    let defaults = defaults::<P>();
    for (key, value) in object {
        let alone = Value::Object(Map::from_iter([(key.clone(), value.clone())]));
        if let Err(e) = serde_json::from_value::<P>(alone) {
            let known: Vec<&str> = defaults.keys().map(String::as_str).collect();
            let message = if defaults.contains_key(key) || !e.to_string().starts_with("unknown field") {
                format!("{key}: {e}")
            } else {
                format!(
                    "unknown parameter '{key}' for method {name} (its parameters: {})",
                    known.join(", ")
                )
            };
            return Err(Error::parameter(message));
        }
    }
    serde_json::from_value(Value::Object(object.clone()))
        .map_err(|e| Error::parameter(format!("{name}: {e}")))
}

/// `P` from the flags in `matches`.
#[cfg(feature = "cli")]
fn from_flags<P: MethodParams>(matches: &clap::ArgMatches) -> Result<P> {
    P::from_arg_matches(matches).map_err(|e| Error::parameter(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_builds_with_the_defaults_and_reports_its_name() {
        for entry in METHODS {
            let estimator = entry.build(&Map::new(), &[]).unwrap();
            assert_eq!(estimator.method(), entry.name);
        }
    }

    #[test]
    fn an_unknown_method_is_a_bad_parameter_named_method() {
        let err = build("raymarch", &Map::new(), &[]).err().unwrap();
        assert!(matches!(
            err,
            Error::Parameter {
                name: Some("method"),
                ..
            }
        ));
    }

    #[test]
    fn a_parameter_another_method_reads_is_refused_by_name() {
        let err = build("photon2", &serde_json::json!({"rays": 16}), &[])
            .err()
            .unwrap();
        let message = err.to_string();
        assert!(
            message.contains("unknown parameter 'rays' for method photon2"),
            "{message}"
        );
        assert!(message.contains("photons"), "{message}");
        let err = build("gather", &serde_json::json!({"rays": "many"}), &[])
            .err()
            .unwrap();
        assert!(err.to_string().contains("rays: invalid type"), "{err}");
    }

    #[test]
    fn an_alias_is_read_as_its_parameter() {
        let new = build("photon1", &serde_json::json!({"nearest": 32}), &[]).unwrap();
        let old = build("photon1", &serde_json::json!({"gather": 32}), &[]).unwrap();
        assert_eq!(new.parameters(), old.parameters());
        assert_eq!(new.parameters().number("nearest"), Some(32.0));
    }

    #[test]
    fn a_parameter_two_methods_read_has_one_type_and_default() {
        let mut seen: Vec<(String, Value, &str)> = vec![];
        for entry in METHODS {
            for (key, value) in entry.defaults() {
                match seen.iter().find(|(k, _, _)| *k == key) {
                    Some((_, first, by)) => assert_eq!(
                        first, &value,
                        "{key}: {by} and {} differ in its default",
                        entry.name
                    ),
                    None => seen.push((key, value, entry.name)),
                }
            }
        }
        assert!(seen.iter().any(|(k, _, _)| k == "rays"));
    }

    #[cfg(feature = "cli")]
    #[test]
    fn every_method_builds_from_the_flags_and_refuses_another_methods_flags() {
        let command = || flags(clap::Command::new("render").arg(clap::Arg::new("method").long("method")));
        command().debug_assert();
        for entry in METHODS {
            let matches = command().get_matches_from(["render"]);
            let estimator = entry.build_from_flags(&matches, &[]).unwrap();
            let defaults = entry.build(&Map::new(), &[]).unwrap();
            assert_eq!(estimator.parameters(), defaults.parameters(), "{}", entry.name);
        }
        let matches = command().get_matches_from(["render", "--rays", "16", "--photons", "9"]);
        let err = method("photon2")
            .unwrap()
            .build_from_flags(&matches, &[])
            .err()
            .unwrap();
        assert!(
            err.to_string()
                .contains("photon2 does not read --rays (its flags:"),
            "{err}"
        );
        let err = method("gather")
            .unwrap()
            .build_from_flags(&matches, &[])
            .err()
            .unwrap();
        assert!(
            err.to_string().contains("gather does not read --photons"),
            "{err}"
        );
        let matches = command().get_matches_from(["render", "--rays", "16", "--cube-res", "8"]);
        let cubemap = method("cubemap")
            .unwrap()
            .build_from_flags(&matches, &[])
            .unwrap();
        assert_eq!(cubemap.parameters().number("rays"), Some(16.0));
        assert_eq!(cubemap.parameters().number("cube_res"), Some(8.0));
    }

    #[test]
    fn the_photon_entries_are_named_as_their_methods() {
        // PhotonMethod::name is the one mapping the CLI and the experiments use; the registry's
        // entries must agree with it.
        for m in PhotonMethod::ALL {
            let built = method(m.name()).unwrap().build(&Map::new(), &[]).unwrap();
            assert_eq!(built.method(), m.name());
        }
    }
}
