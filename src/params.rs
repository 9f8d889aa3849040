//! Technique parameters. Each technique (and each shared pass with knobs)
//! declares its parameters once, as a typed struct, with [`declare_params!`]:
//! the macro generates the spec list that the CLI (`--param NAME=VALUE`,
//! `caustics info`), the demo overlay and the benchmarks read, and the
//! conversion from validated values ([`Params`], one per spec, by position)
//! to the struct, so code reads `params.pcf_radius`, never a name string;
//! names are read only where a user types them (`Params::resolve`). Groups compose: a technique's
//! struct holds `direct: DirectParams` and its specs list the group's first.
//!
//! Each parameter says how a change takes effect ([`Apply`]): `Live` ones are
//! push constants or uniforms that the running technique takes in place
//! (`TechniqueBuild::update_live`, typed), `Rebuild` ones size resources or change
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
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
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

/// Parameter values validated against a technique's specs, one per spec in
/// the specs' order: the untyped form the CLI (`resolve`, the one place a
/// name is read) and the overlay (`set`, by position) edit. A technique
/// turns them into its typed struct with [`ParamSet::from_params`], which
/// reads them by position, never by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    specs: &'static [ParamSpec],
    values: Vec<f32>,
}

impl Params {
    /// Defaults from `specs`, overridden by `overrides` ("name=value" each).
    /// Unknown names and out-of-range values are errors naming the parameter.
    pub fn resolve(
        technique: &str,
        specs: &'static [ParamSpec],
        overrides: &[String],
    ) -> anyhow::Result<Params> {
        let mut values: Vec<f32> = specs.iter().map(|s| s.default).collect();
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
            let index = specs.iter().position(|s| s.name == name).ok_or_else(|| {
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
            if !specs[index].accepts(v) {
                anyhow::bail!("--param {name}={value}: {}", specs[index].range_text());
            }
            values[index] = v;
        }
        Ok(Params { specs, values })
    }

    /// The specs these values belong to, in their order.
    pub fn specs(&self) -> &'static [ParamSpec] {
        self.specs
    }

    /// The values, one per spec, in the specs' order.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Sets the value of the `index`-th spec (the overlay's sliders: a
    /// typed value, validated as `resolve` validates, no "name=value"
    /// string on the way); an error when `index` is past the specs or
    /// `value` is out of its range.
    pub fn set(&mut self, index: usize, value: f32) -> anyhow::Result<()> {
        let spec = self.specs.get(index).ok_or_else(|| {
            anyhow::anyhow!("parameter #{index}: these values have {}", self.specs.len())
        })?;
        if !spec.accepts(value) {
            anyhow::bail!("parameter {} = {value}: {}", spec.name, spec.range_text());
        }
        self.values[index] = value;
        Ok(())
    }

    /// Each spec with its value, in the specs' order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static ParamSpec, f32)> + '_ {
        self.specs.iter().zip(self.values.iter().copied())
    }

    /// The specs whose values differ between `self` and `other`; every
    /// spec of both when they were resolved against different specs.
    pub fn changed(&self, other: &Params) -> Vec<&'static ParamSpec> {
        if self.specs != other.specs {
            return self.specs.iter().chain(other.specs).collect();
        }
        self.iter()
            .zip(&other.values)
            .filter(|((_, a), b)| a != *b)
            .map(|((s, _), _)| s)
            .collect()
    }
}

/// A typed parameter struct (made by [`declare_params!`]).
pub trait ParamSet: Sized {
    /// Every parameter, groups first, in declaration order.
    fn specs() -> &'static [ParamSpec];
    /// The typed values of validated `values`, one per spec of `specs()`
    /// in its order (groups read their own run of it).
    fn from_values(values: &[f32]) -> Self;

    /// The typed values of validated `params`; an error when they were
    /// resolved against other specs (another technique's).
    fn from_params(params: &Params) -> anyhow::Result<Self> {
        if params.specs() != Self::specs() {
            anyhow::bail!(
                "parameters resolved against other specs ({}) than this set's ({})",
                names(params.specs()),
                names(Self::specs())
            );
        }
        Ok(Self::from_values(params.values()))
    }

    /// Defaults overridden by `overrides` ("name=value" each), validated as
    /// the CLI does; `technique` names the owner in error messages.
    fn parse(technique: &str, overrides: &[String]) -> anyhow::Result<Self> {
        Self::from_params(&Params::resolve(technique, Self::specs(), overrides)?)
    }
}

/// `specs`' names, comma-separated (error messages).
fn names(specs: &[ParamSpec]) -> String {
    let names: Vec<_> = specs.iter().map(|s| s.name).collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
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

            // Fields in declaration order, as `specs` lists them: a struct
            // expression evaluates its fields in the order written.
            #[allow(unused_assignments, unused_mut, unused_variables)]
            fn from_values(values: &[f32]) -> Self {
                let mut at = 0usize;
                Self {
                    $($group: {
                        let group = <$gty as $crate::params::ParamSet>::from_values(&values[at..]);
                        at += <$gty as $crate::params::ParamSet>::specs().len();
                        group
                    },)*
                    $($field: {
                        let v = <$ty as $crate::params::ParamValue>::from_f32(values[at]);
                        at += 1;
                        v
                    },)*
                }
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
        let e = Outer::from_params(&Params::default())
            .err()
            .unwrap()
            .to_string();
        assert_eq!(
            e,
            "parameters resolved against other specs (none) than this set's (size, scale, on)"
        );
        let inner = Params::resolve("t", Inner::specs(), &["size=3".into()]).unwrap();
        assert!(Outer::from_params(&inner).is_err());
        assert_eq!(Inner::from_params(&inner).unwrap().size, 3);
        assert_eq!(Outer::default(), Outer::parse("t", &[]).unwrap());
    }

    /// `set` takes a typed value by position with `resolve`'s checks.
    #[test]
    fn set_validates_like_resolve() {
        let specs = Outer::specs();
        let mut p = Params::resolve("t", specs, &[]).unwrap();
        p.set(1, 1.5).unwrap();
        assert_eq!(
            p,
            Params::resolve("t", specs, &["scale=1.5".into()]).unwrap()
        );
        let e = p.set(0, 2.5).unwrap_err().to_string();
        assert_eq!(e, "parameter size = 2.5: must be a whole number in [1, 64]");
        assert!(p.set(1, f32::NAN).is_err());
        assert!(p.set(1, 3.0).is_err());
        assert!(p.set(3, 1.0).is_err());
        assert!(Params::default().set(0, 1.0).is_err());
        assert_eq!(p.values(), [8.0, 1.5, 1.0]);
        assert_eq!(Outer::from_params(&p).unwrap().scale, 1.5);
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
        let changed: Vec<_> = a.changed(&b).iter().map(|s| s.name).collect();
        assert_eq!(changed, ["scale"]);
    }
}
