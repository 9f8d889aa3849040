//! Technique parameters. Each technique (and each shared pass with knobs)
//! declares its parameters once, as a typed struct, with [`declare_params!`]:
//! the macro generates the spec list that the CLI (`--param NAME=VALUE`,
//! `caustics info`), the demo overlay and the benchmarks read, and the
//! conversion from validated values ([`Params`]) to the struct, so code reads
//! `params.pcf_radius`, never a name string. Groups compose: a technique's
//! struct holds `direct: DirectParams` and its specs list the group's first.
//!
//! Each parameter says how a change takes effect ([`Apply`]): `Live` ones are
//! push constants or uniforms that the running technique takes in place
//! (`Technique::update_live`), `Rebuild` ones size resources or change
//! pipelines and rebuild the technique.
//!
//! This module sits below `passes` (which declare their own groups, e.g.
//! `passes::airlight::AirlightParams`) and imports nothing of the renderer.

use std::collections::BTreeMap;

/// How a parameter change reaches the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Apply {
    /// A push constant or uniform: the technique takes it without a rebuild.
    Live,
    /// Sizes resources or changes pipelines: the technique is rebuilt.
    Rebuild,
}

/// One tunable parameter of a technique.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ParamSpec {
    pub name: &'static str,
    pub description: &'static str,
    pub min: f32,
    pub max: f32,
    pub default: f32,
    /// Whole numbers only (resolutions, counts, switches).
    pub integer: bool,
    pub apply: Apply,
}

impl ParamSpec {
    /// Whether `v` is a value of this parameter: finite, in [min, max],
    /// whole when `integer`.
    pub fn accepts(&self, v: f32) -> bool {
        v.is_finite() && v >= self.min && v <= self.max && !(self.integer && v.fract() != 0.0)
    }

    /// What `accepts` asks, for error messages.
    fn range_text(&self) -> String {
        let kind = if self.integer {
            "a whole number"
        } else {
            "a number"
        };
        format!("must be {kind} in [{}, {}]", self.min, self.max)
    }
}

/// Parameter values by name, validated against a technique's specs: the
/// untyped form the CLI and the overlay edit. A technique turns them into
/// its typed struct with [`ParamSet::from_params`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    values: BTreeMap<String, f32>,
}

impl Params {
    /// Defaults from `specs`, overridden by `overrides` ("name=value" each).
    /// Unknown names and out-of-range values are errors naming the parameter.
    pub fn resolve(
        technique: &str,
        specs: &[ParamSpec],
        overrides: &[String],
    ) -> anyhow::Result<Params> {
        let by_name: BTreeMap<&str, &ParamSpec> = specs.iter().map(|s| (s.name, s)).collect();
        let mut values: BTreeMap<String, f32> = specs
            .iter()
            .map(|s| (s.name.to_string(), s.default))
            .collect();
        let mut given: BTreeMap<&str, &str> = BTreeMap::new();
        for o in overrides {
            let (name, value) = o
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--param {o:?}: expected NAME=VALUE"))?;
            if let Some(first) = given.insert(name, value) {
                anyhow::bail!(
                    "--param {name}: given twice ({name}={first} and {name}={value}); give it once"
                );
            }
            let spec = by_name.get(name).ok_or_else(|| {
                let known: Vec<_> = specs.iter().map(|s| s.name).collect();
                anyhow::anyhow!(
                    "--param {name}: technique `{technique}` has no such parameter (it has: {})",
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                )
            })?;
            let v: f32 = value
                .trim()
                .parse()
                .map_err(|_| anyhow::anyhow!("--param {name}: {value:?} is not a number"))?;
            if !spec.accepts(v) {
                anyhow::bail!("--param {name}={value}: {}", spec.range_text());
            }
            values.insert(name.to_string(), v);
        }
        Ok(Params { values })
    }

    /// Sets the value of `spec`'s parameter (the overlay's sliders: a
    /// typed value, validated as `resolve` validates, no "name=value"
    /// string on the way); an error when these values were resolved
    /// against other specs or `value` is out of its range.
    pub fn set(&mut self, spec: &ParamSpec, value: f32) -> anyhow::Result<()> {
        let slot = self.values.get_mut(spec.name).ok_or_else(|| {
            anyhow::anyhow!(
                "parameter `{}` has no value (resolved for another technique?)",
                spec.name
            )
        })?;
        if !spec.accepts(value) {
            anyhow::bail!("parameter {} = {value}: {}", spec.name, spec.range_text());
        }
        *slot = value;
        Ok(())
    }

    /// The value of `name`; an error (not a panic) when these values were
    /// resolved against specs that do not declare it.
    pub fn value(&self, name: &str) -> anyhow::Result<f32> {
        self.values.get(name).copied().ok_or_else(|| {
            anyhow::anyhow!("parameter `{name}` has no value (resolved for another technique?)")
        })
    }

    pub fn iter(&self) -> impl Iterator<Item = (&String, &f32)> {
        self.values.iter()
    }

    /// The names whose values differ between `self` and `other`.
    pub fn changed<'a>(&'a self, other: &'a Params) -> impl Iterator<Item = &'a str> + 'a {
        let names: std::collections::BTreeSet<&str> = self
            .values
            .keys()
            .chain(other.values.keys())
            .map(String::as_str)
            .collect();
        names
            .into_iter()
            .filter(|n| self.values.get(*n) != other.values.get(*n))
    }
}

/// A typed parameter struct (made by [`declare_params!`]).
pub trait ParamSet: Sized {
    /// Every parameter, groups first, in declaration order.
    fn specs() -> &'static [ParamSpec];
    /// The typed values of validated `params`.
    fn from_params(params: &Params) -> anyhow::Result<Self>;

    /// Defaults overridden by `overrides` ("name=value" each), validated as
    /// the CLI does; `technique` names the owner in error messages.
    fn parse(technique: &str, overrides: &[String]) -> anyhow::Result<Self> {
        Self::from_params(&Params::resolve(technique, Self::specs(), overrides)?)
    }
}

/// A field type of a parameter struct.
pub trait ParamValue: Copy {
    const INTEGER: bool;
    fn from_f32(v: f32) -> Self;
}

impl ParamValue for f32 {
    const INTEGER: bool = false;
    fn from_f32(v: f32) -> Self {
        v
    }
}

impl ParamValue for u32 {
    const INTEGER: bool = true;
    fn from_f32(v: f32) -> Self {
        v as u32
    }
}

impl ParamValue for i32 {
    const INTEGER: bool = true;
    fn from_f32(v: f32) -> Self {
        v as i32
    }
}

/// A 0/1 switch.
impl ParamValue for bool {
    const INTEGER: bool = true;
    fn from_f32(v: f32) -> Self {
        v != 0.0
    }
}

/// Declares a parameter struct:
///
/// ```ignore
/// declare_params! {
///     /// doc
///     pub struct ImageSpaceParams {
///         @group direct: DirectParams;
///         search_steps: u32 [4, 256] = 32, live, "linear steps of the search";
///     }
/// }
/// ```
///
/// Each field: type (`u32`, `i32`, `f32` or `bool`), `[min, max]`, default,
/// `live` or `rebuild` ([`Apply`]), description. Generates the struct (all
/// fields public), [`ParamSet`] and `Default` (the declared defaults).
#[macro_export]
macro_rules! declare_params {
    (@apply live) => { $crate::params::Apply::Live };
    (@apply rebuild) => { $crate::params::Apply::Rebuild };
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(@group $group:ident : $gty:ty;)*
            $($field:ident : $ty:ident [$min:expr, $max:expr] = $default:expr, $apply:ident, $desc:expr;)*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq)]
        $vis struct $name {
            $(pub $group: $gty,)*
            $(pub $field: $ty,)*
        }

        impl $name {
            /// This struct's own parameters (without its groups).
            const OWN: &'static [$crate::params::ParamSpec] = &[$(
                $crate::params::ParamSpec {
                    name: stringify!($field),
                    description: $desc,
                    min: $min as f32,
                    max: $max as f32,
                    default: $default as f32,
                    integer: <$ty as $crate::params::ParamValue>::INTEGER,
                    apply: $crate::declare_params!(@apply $apply),
                },
            )*];
        }

        impl $crate::params::ParamSet for $name {
            fn specs() -> &'static [$crate::params::ParamSpec] {
                static SPECS: std::sync::OnceLock<Vec<$crate::params::ParamSpec>> =
                    std::sync::OnceLock::new();
                SPECS.get_or_init(|| {
                    #[allow(unused_mut)]
                    let mut v: Vec<$crate::params::ParamSpec> = Vec::new();
                    $(v.extend_from_slice(<$gty as $crate::params::ParamSet>::specs());)*
                    v.extend_from_slice(Self::OWN);
                    v
                })
            }

            fn from_params(_params: &$crate::params::Params) -> anyhow::Result<Self> {
                Ok(Self {
                    $($group: <$gty as $crate::params::ParamSet>::from_params(_params)?,)*
                    $($field: <$ty as $crate::params::ParamValue>::from_f32(
                        _params.value(stringify!($field))?,
                    ),)*
                })
            }
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    $($group: Default::default(),)*
                    $($field: <$ty as $crate::params::ParamValue>::from_f32($default as f32),)*
                }
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    declare_params! {
        /// A group.
        struct Inner {
            size: u32 [1, 64] = 8, rebuild, "a size";
        }
    }

    declare_params! {
        /// A struct with a group.
        struct Outer {
            @group inner: Inner;
            scale: f32 [0.5, 2] = 1, live, "a scale";
            on: bool [0, 1] = 1, live, "a switch";
        }
    }

    #[test]
    fn specs_list_groups_first_and_convert_typed() {
        let names: Vec<_> = Outer::specs().iter().map(|s| s.name).collect();
        assert_eq!(names, ["size", "scale", "on"]);
        assert_eq!(Outer::specs()[0].apply, Apply::Rebuild);
        assert!(!Outer::specs()[1].integer);
        let o = Outer::parse("t", &["size=16".into(), "on=0".into()]).unwrap();
        assert_eq!(o.inner.size, 16);
        assert_eq!(o.scale, 1.0);
        assert!(!o.on);
        assert_eq!(
            Outer::from_params(&Params::default())
                .err()
                .unwrap()
                .to_string(),
            "parameter `size` has no value (resolved for another technique?)"
        );
        assert_eq!(Outer::default(), Outer::parse("t", &[]).unwrap());
    }

    /// `set` takes a typed value with `resolve`'s checks.
    #[test]
    fn set_validates_like_resolve() {
        let specs = Outer::specs();
        let mut p = Params::resolve("t", specs, &[]).unwrap();
        p.set(&specs[1], 1.5).unwrap();
        assert_eq!(
            p,
            Params::resolve("t", specs, &["scale=1.5".into()]).unwrap()
        );
        let e = p.set(&specs[0], 2.5).unwrap_err().to_string();
        assert_eq!(e, "parameter size = 2.5: must be a whole number in [1, 64]");
        assert!(p.set(&specs[1], f32::NAN).is_err());
        assert!(p.set(&specs[1], 3.0).is_err());
        assert!(Params::default().set(&specs[1], 1.0).is_err());
        assert_eq!(p.value("scale").unwrap(), 1.5);
    }

    #[test]
    fn bad_values_are_errors_naming_the_parameter() {
        let e = Outer::parse("t", &["size=0".into()])
            .unwrap_err()
            .to_string();
        assert_eq!(e, "--param size=0: must be a whole number in [1, 64]");
        let e = Outer::parse("t", &["sise=3".into()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("technique `t` has no such parameter (it has: size, scale, on)"),
            "{e}"
        );
        let a = Params::resolve("t", Outer::specs(), &["scale=2".into()]).unwrap();
        let b = Params::resolve("t", Outer::specs(), &[]).unwrap();
        assert_eq!(a.changed(&b).collect::<Vec<_>>(), ["scale"]);
    }
}
