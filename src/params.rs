//! Technique parameters: each declared once (`ParamSpec`) so the CLI, the
//! demo overlay and the benchmarks read the same list. Below `passes`, which
//! declare their own (`passes::airlight::PARAMS`).

use std::collections::BTreeMap;

/// One tunable parameter of a technique.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ParamSpec {
    pub name: &'static str,
    pub description: &'static str,
    pub min: f32,
    pub max: f32,
    pub default: f32,
    /// Whole numbers only (resolutions, counts).
    pub integer: bool,
}

/// Parameter values by name, validated against a technique's specs.
#[derive(Clone, Debug, Default)]
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
        let mut values: BTreeMap<String, f32> = specs
            .iter()
            .map(|s| (s.name.to_string(), s.default))
            .collect();
        for o in overrides {
            let (name, value) = o
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--param {o:?}: expected NAME=VALUE"))?;
            let spec = specs.iter().find(|s| s.name == name).ok_or_else(|| {
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
            if !v.is_finite() || v < spec.min || v > spec.max || (spec.integer && v.fract() != 0.0)
            {
                anyhow::bail!(
                    "--param {name}={value}: must be {} in [{}, {}]",
                    if spec.integer {
                        "a whole number"
                    } else {
                        "a number"
                    },
                    spec.min,
                    spec.max
                );
            }
            values.insert(name.to_string(), v);
        }
        Ok(Params { values })
    }

    pub fn get(&self, name: &str) -> f32 {
        *self
            .values
            .get(name)
            .unwrap_or_else(|| panic!("parameter {name} was not declared"))
    }

    pub fn iter(&self) -> impl Iterator<Item = (&String, &f32)> {
        self.values.iter()
    }
}
