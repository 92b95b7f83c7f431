//! Names of the sensors and error effects (the docs/cli.md names), and the `--only` / `--without`
//! term filter used for ablation by `generate`, `simulate` and `spec`.

pub use crate::terms::Effect;
use std::collections::BTreeSet;
use std::fmt;

/// Which triad.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Sensor {
    Gyro,
    Accel,
}

impl Sensor {
    pub const ALL: [Sensor; 2] = [Sensor::Gyro, Sensor::Accel];
    /// `"gyro"` / `"accel"`.
    pub fn name(self) -> &'static str {
        match self {
            Sensor::Gyro => "gyro",
            Sensor::Accel => "accel",
        }
    }
    pub fn from_name(name: &str) -> Option<Sensor> {
        Sensor::ALL.into_iter().find(|s| s.name() == name)
    }
}

impl fmt::Display for Sensor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl serde::Serialize for Effect {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl Effect {
    pub fn from_name(name: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.name() == name)
    }

    /// Index used to derive the term's random sub-stream (stable: never reorder).
    pub(crate) fn stream_index(self) -> u64 {
        self as u64
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A bad `--only` / `--without` item.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{option}: cannot read term `{item}`: {reason} (terms are `gyro.<effect>`, `accel.<effect>`, `<effect>` for both, or `gyro` / `accel`; effects: {effects})", effects = Effect::ALL.map(|e| e.name()).join(", "))]
pub struct FilterError {
    pub option: &'static str,
    pub item: String,
    pub reason: String,
}

/// Which (sensor, effect) terms are switched on. Default: all.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TermFilter {
    only: Option<BTreeSet<(Sensor, Effect)>>,
    without: BTreeSet<(Sensor, Effect)>,
}

impl TermFilter {
    /// Everything on.
    pub fn all() -> TermFilter {
        TermFilter::default()
    }

    /// Parse `--only` and `--without` lists such as `"gyro.white_noise,accel.constant_bias"`.
    /// An item may also be a bare effect (`white_noise`: both sensors) or a bare sensor (`gyro`: all its terms).
    /// A term both in `only` and in `without` is off.
    pub fn parse(only: Option<&str>, without: Option<&str>) -> Result<TermFilter, FilterError> {
        let only = only.map(|s| parse_list("--only", s)).transpose()?;
        let without = without
            .map(|s| parse_list("--without", s))
            .transpose()?
            .unwrap_or_default();
        Ok(TermFilter { only, without })
    }

    /// Is this term on?
    pub fn allows(&self, sensor: Sensor, effect: Effect) -> bool {
        self.only
            .as_ref()
            .is_none_or(|set| set.contains(&(sensor, effect)))
            && !self.without.contains(&(sensor, effect))
    }

    /// The terms `--only` keeps (`None`: no `--only` list), in order.
    pub fn only_terms(&self) -> Option<Vec<(Sensor, Effect)>> {
        self.only.as_ref().map(|set| set.iter().copied().collect())
    }

    /// True when nothing is filtered.
    pub fn is_all(&self) -> bool {
        self.only.is_none() && self.without.is_empty()
    }

    /// The filter written back as CLI options (for reports), e.g. `--without gyro.white_noise`.
    pub fn describe(&self) -> String {
        let list = |set: &BTreeSet<(Sensor, Effect)>| {
            set.iter()
                .map(|(s, e)| format!("{s}.{e}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        let mut parts = Vec::new();
        if let Some(only) = &self.only {
            parts.push(format!("--only {}", list(only)));
        }
        if !self.without.is_empty() {
            parts.push(format!("--without {}", list(&self.without)));
        }
        parts.join(" ")
    }
}

fn parse_list(option: &'static str, text: &str) -> Result<BTreeSet<(Sensor, Effect)>, FilterError> {
    let mut set = BTreeSet::new();
    for raw in text.split(',') {
        let item = raw.trim();
        let err = |reason: &str| FilterError {
            option,
            item: item.to_string(),
            reason: reason.to_string(),
        };
        if item.is_empty() {
            return Err(err("empty item"));
        }
        let (sensors, effect): (Vec<Sensor>, Option<&str>) = match item.split_once('.') {
            Some((s, e)) => (
                vec![Sensor::from_name(s).ok_or_else(|| err(&format!("unknown sensor `{s}`")))?],
                Some(e),
            ),
            None => match Sensor::from_name(item) {
                Some(s) => (vec![s], None),
                None => (Sensor::ALL.to_vec(), Some(item)),
            },
        };
        let effects: Vec<Effect> = match effect {
            Some(e) => {
                vec![Effect::from_name(e).ok_or_else(|| err(&format!("unknown effect `{e}`")))?]
            }
            None => Effect::ALL.to_vec(),
        };
        for s in sensors {
            for &e in &effects {
                set.insert((s, e));
            }
        }
    }
    Ok(set)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for e in Effect::ALL {
            assert_eq!(Effect::from_name(e.name()), Some(e));
        }
        for s in Sensor::ALL {
            assert_eq!(Sensor::from_name(s.name()), Some(s));
        }
    }

    #[test]
    fn only_and_without_lists() {
        let f = TermFilter::parse(Some("gyro.white_noise, accel.constant_bias"), None).unwrap();
        assert!(f.allows(Sensor::Gyro, Effect::WhiteNoise));
        assert!(f.allows(Sensor::Accel, Effect::ConstantBias));
        assert!(!f.allows(Sensor::Accel, Effect::WhiteNoise));
        assert!(!f.allows(Sensor::Gyro, Effect::BiasInstability));

        let f = TermFilter::parse(None, Some("white_noise,accel")).unwrap();
        assert!(!f.allows(Sensor::Gyro, Effect::WhiteNoise));
        assert!(!f.allows(Sensor::Accel, Effect::ScaleFactor));
        assert!(f.allows(Sensor::Gyro, Effect::BiasInstability));

        let f = TermFilter::parse(Some("gyro"), Some("gyro.white_noise")).unwrap();
        assert!(!f.allows(Sensor::Gyro, Effect::WhiteNoise));
        assert!(f.allows(Sensor::Gyro, Effect::Quantization));
        // Every gyro effect in registry order (`Effect::ALL`), then the exclusion.
        let every: Vec<String> = Effect::ALL
            .iter()
            .map(|e| format!("gyro.{}", e.name()))
            .collect();
        assert!(every[..2] == ["gyro.quantization", "gyro.white_noise"]);
        assert_eq!(
            f.describe(),
            format!("--only {} --without gyro.white_noise", every.join(","))
        );
        assert!(TermFilter::all().is_all());
    }

    #[test]
    fn bad_items_name_the_option_and_item() {
        let e = TermFilter::parse(Some("gyro.whte_noise"), None).unwrap_err();
        assert_eq!(e.option, "--only");
        assert!(e.to_string().contains("whte_noise"), "{e}");
        let e = TermFilter::parse(None, Some("magneto.white_noise")).unwrap_err();
        assert!(e.to_string().contains("unknown sensor `magneto`"), "{e}");
        assert!(TermFilter::parse(None, Some("gyro.white_noise,,")).is_err());
    }
}
