//! Names of the sensors and error effects (the docs/cli.md names), the items of a term switch
//! ([`TermSelector`]) and the term filter they make (`only` / `without`), used for ablation by
//! `generate`, `simulate` and `spec`.

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

/// A term-switch item that names no term: the item as written and why. The message names no
/// setting: the caller knows where the item was written (a scenario key, a command-line option).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cannot read term `{item}`: {reason} (terms are `gyro.<effect>`, `accel.<effect>`, `<effect>` for both, or `gyro` / `accel`; effects: {effects})", effects = Effect::ALL.map(|e| e.name()).join(", "))]
pub struct TermSelectorError {
    pub item: String,
    pub reason: String,
}

/// One item of a term switch (the `only` / `without` lists of a scenario's `[terms]` and of the
/// front ends): `gyro.<effect>`, `accel.<effect>`, a bare `<effect>` (both sensors) or a bare
/// `gyro` / `accel` (all of that sensor's terms). Parsed once; keeps its text as written, which
/// reports repeat (docs/cli.md), and (de)serialises as that text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TermSelector {
    text: String,
    terms: BTreeSet<(Sensor, Effect)>,
}

impl TermSelector {
    /// Parse one item (surrounding blanks ignored; the text kept as given).
    pub fn parse(text: &str) -> Result<TermSelector, TermSelectorError> {
        let item = text.trim();
        let err = |reason: String| TermSelectorError {
            item: item.to_string(),
            reason,
        };
        if item.is_empty() {
            return Err(err("empty item".into()));
        }
        let (sensors, effect): (Vec<Sensor>, Option<&str>) = match item.split_once('.') {
            Some((s, e)) => (
                vec![Sensor::from_name(s).ok_or_else(|| err(format!("unknown sensor `{s}`")))?],
                Some(e),
            ),
            None => match Sensor::from_name(item) {
                Some(s) => (vec![s], None),
                None => (Sensor::ALL.to_vec(), Some(item)),
            },
        };
        let effects: Vec<Effect> = match effect {
            Some(e) => {
                vec![Effect::from_name(e).ok_or_else(|| err(format!("unknown effect `{e}`")))?]
            }
            None => Effect::ALL.to_vec(),
        };
        let terms = sensors
            .iter()
            .flat_map(|&s| effects.iter().map(move |&e| (s, e)))
            .collect();
        Ok(TermSelector {
            text: text.to_string(),
            terms,
        })
    }

    /// The one term `sensor.effect`.
    pub fn term(sensor: Sensor, effect: Effect) -> TermSelector {
        TermSelector {
            text: format!("{sensor}.{effect}"),
            terms: BTreeSet::from([(sensor, effect)]),
        }
    }

    /// The item as written.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The (sensor, effect) terms it names, in order.
    pub fn terms(&self) -> impl Iterator<Item = (Sensor, Effect)> + '_ {
        self.terms.iter().copied()
    }
}

impl std::str::FromStr for TermSelector {
    type Err = TermSelectorError;
    fn from_str(text: &str) -> Result<TermSelector, TermSelectorError> {
        TermSelector::parse(text)
    }
}

impl fmt::Display for TermSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

impl serde::Serialize for TermSelector {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.text)
    }
}

impl<'de> serde::Deserialize<'de> for TermSelector {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<TermSelector, D::Error> {
        let text = String::deserialize(d)?;
        TermSelector::parse(&text).map_err(serde::de::Error::custom)
    }
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

    /// The terms `only` names (`None`: every term) less those `without` names: a term in both
    /// is off.
    pub fn new(only: Option<&[TermSelector]>, without: &[TermSelector]) -> TermFilter {
        let set = |items: &[TermSelector]| items.iter().flat_map(TermSelector::terms).collect();
        TermFilter {
            only: only.map(set),
            without: set(without),
        }
    }

    /// Is this term on?
    pub fn allows(&self, sensor: Sensor, effect: Effect) -> bool {
        self.only
            .as_ref()
            .is_none_or(|set| set.contains(&(sensor, effect)))
            && !self.without.contains(&(sensor, effect))
    }

    /// The terms the `only` list keeps (`None`: no `only` list), in order.
    pub fn only_terms(&self) -> Option<Vec<(Sensor, Effect)>> {
        self.only.as_ref().map(|set| set.iter().copied().collect())
    }

    /// The terms the `without` list switches off, in order.
    pub fn without_terms(&self) -> Vec<(Sensor, Effect)> {
        self.without.iter().copied().collect()
    }

    /// True when nothing is filtered.
    pub fn is_all(&self) -> bool {
        self.only.is_none() && self.without.is_empty()
    }
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

    fn items(text: &str) -> Vec<TermSelector> {
        text.split(',')
            .map(|s| TermSelector::parse(s).unwrap())
            .collect()
    }

    #[test]
    fn only_and_without_lists() {
        let f = TermFilter::new(Some(&items("gyro.white_noise, accel.constant_bias")), &[]);
        assert!(f.allows(Sensor::Gyro, Effect::WhiteNoise));
        assert!(f.allows(Sensor::Accel, Effect::ConstantBias));
        assert!(!f.allows(Sensor::Accel, Effect::WhiteNoise));
        assert!(!f.allows(Sensor::Gyro, Effect::BiasInstability));

        let f = TermFilter::new(None, &items("white_noise,accel"));
        assert!(!f.allows(Sensor::Gyro, Effect::WhiteNoise));
        assert!(!f.allows(Sensor::Accel, Effect::ScaleFactor));
        assert!(f.allows(Sensor::Gyro, Effect::BiasInstability));

        let f = TermFilter::new(Some(&items("gyro")), &items("gyro.white_noise"));
        assert!(!f.allows(Sensor::Gyro, Effect::WhiteNoise));
        assert!(f.allows(Sensor::Gyro, Effect::Quantization));
        assert_eq!(f.only_terms().unwrap().len(), Effect::ALL.len());
        assert_eq!(f.without_terms(), vec![(Sensor::Gyro, Effect::WhiteNoise)]);
        assert!(TermFilter::all().is_all());
    }

    #[test]
    fn selectors_keep_their_text_and_round_trip() {
        let s = TermSelector::parse(" white_noise").unwrap();
        assert_eq!(s.text(), " white_noise");
        assert_eq!(
            s.terms().collect::<Vec<_>>(),
            vec![
                (Sensor::Gyro, Effect::WhiteNoise),
                (Sensor::Accel, Effect::WhiteNoise)
            ]
        );
        let one = TermSelector::term(Sensor::Accel, Effect::ConstantBias);
        assert_eq!(one.to_string(), "accel.constant_bias");
        assert_eq!(TermSelector::parse(one.text()).unwrap(), one);
    }

    #[test]
    fn bad_items_name_the_item_and_why() {
        let e = TermSelector::parse("gyro.whte_noise").unwrap_err();
        assert_eq!(e.item, "gyro.whte_noise");
        assert!(e.to_string().contains("unknown effect `whte_noise`"), "{e}");
        let e = TermSelector::parse("magneto.white_noise").unwrap_err();
        assert!(e.to_string().contains("unknown sensor `magneto`"), "{e}");
        assert!(TermSelector::parse(" ").is_err());
    }
}
