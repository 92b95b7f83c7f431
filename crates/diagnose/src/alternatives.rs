//! Structures the evidence could not tell apart, and the drift band averaged over them
//! (docs/drift.md, "Structure uncertainty").
//!
//! The drift loop of `diagnose` chooses each channel's long-averaging-time term by the BIC
//! (docs/diagnose.md, "Drift in the loop"). Its candidates are scored by their BIC gain less the
//! naming rule's threshold (the prior odds against a change the rule stands for), and where
//! another structure comes within Occam's window of the kept one (a score at most 2 ln 20 = 6.0
//! lower, posterior odds 1:20; Madigan & Raftery 1994, JASA 89, 1535-1546), the data cannot tell
//! the two apart, yet they predict different drifts (a rate random walk keeps wandering, a
//! Gauss-Markov process returns). The corrected model then carries the other structures as
//! `[[alternatives]]`, each with its posterior weight exp(-d / 2) normalised over the channel's
//! structures (the BIC approximation of the posterior model probability: Schwarz 1978; Raftery
//! 1995, Sociological Methodology 25, 111-163), and `drift` averages its band over them (Bayesian
//! model averaging: Hoeting, Madigan, Raftery & Volinsky 1999, Statistical Science 14, 382-417):
//! the simulated experiments are shared out among the structures in proportion to their weights
//! (largest remainders), each structure's changed channels drawn by their own parametric
//! bootstrap.
//!
//! ```toml
//! [[alternatives]]
//! channel = "gz"
//! weight = 0.13
//! delta_bic = 3.8
//! effects = ["slow_gauss_markov"]
//! [alternatives.terms]
//! white_noise = "0.0395 deg/s/sqrt(Hz)"
//! slow_gauss_markov = { sigma = "0.016 deg/s", time_constant = "900 s" }
//! ```
//!
//! `terms` is the whole axis of the alternative structure, written as the model writes an axis.

use noise::{AxisModel, Channel, Effect, ImuChannels, SensorModel, UnitStyle};
use serde::{Serialize, Serializer};
use std::fmt::Write as _;

/// Occam's window: alternatives within 2 ln 20 of the chosen structure's score (module doc).
pub const OCCAM_DELTA_BIC: f64 = 5.991_464_547_107_979;

/// Most alternatives kept per channel (the strongest).
pub const MAX_PER_CHANNEL: usize = 3;

/// Least number of replicates a structure's bootstrap is run with: its draws are centred by their
/// mean (`bootstrap`), which a handful of replicates would pin to the fitted levels.
pub const MIN_BOOTSTRAP: usize = 16;

/// One structure of a channel other than the model's own.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Alternative {
    #[serde(serialize_with = "channel_name")]
    pub channel: Channel,
    /// Its posterior weight among the channel's structures (the model's own has the rest).
    pub weight: f64,
    /// -2 ln of its posterior odds against the chosen structure (the BIC difference, the naming
    /// rule's threshold counted as prior odds against each change; >= 0 within Occam's window).
    pub delta_bic: f64,
    /// The effects it has that the chosen structure has not, or at another level.
    pub effects: Vec<Effect>,
    /// The effects the chosen structure has that it has not.
    pub removed: Vec<Effect>,
    /// The channel's whole axis in this structure.
    #[serde(skip)]
    pub axis: AxisModel,
}

fn channel_name<S: Serializer>(c: &Channel, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(c.name())
}

/// Each structure's weight from its BIC difference to the chosen one (the chosen one first, at
/// difference 0): exp(-d / 2), normalised.
pub fn weights(delta_bic: &[f64]) -> Vec<f64> {
    let w: Vec<f64> = std::iter::once(0.0)
        .chain(delta_bic.iter().copied())
        .map(|d| (-d / 2.0).exp())
        .collect();
    let total: f64 = w.iter().sum();
    w.iter().map(|x| x / total).collect()
}

/// The effects `other` has that `chosen` has not, or at another level.
pub fn differing_effects(chosen: &AxisModel, other: &AxisModel) -> Vec<Effect> {
    Effect::ALL
        .into_iter()
        .filter(|&e| other.term(e).is_some() && other.term(e) != chosen.term(e))
        .collect()
}

/// The effects `chosen` has and `other` has not.
pub fn removed_effects(chosen: &AxisModel, other: &AxisModel) -> Vec<Effect> {
    Effect::ALL
        .into_iter()
        .filter(|&e| chosen.term(e).is_some() && other.term(e).is_none())
        .collect()
}

/// A `[[alternatives]]` table that cannot be used; the message names the entry and key.
#[derive(Debug, thiserror::Error)]
pub enum AlternativesError {
    #[error("[[alternatives]]: {0}")]
    Syntax(String),
    #[error("[[alternatives]] entry {entry}: {key}: expected {expected}")]
    Value {
        entry: usize,
        key: &'static str,
        expected: &'static str,
    },
    #[error("[[alternatives]] entry {entry}: terms: {message}")]
    Terms { entry: usize, message: String },
    #[error("[[alternatives]]: the weights of channel {channel} add up to {total} (expected below 1: the model's own structure has the rest)")]
    Weights { channel: &'static str, total: f64 },
}

/// The alternatives as TOML, to append to the corrected model (`style`: the model's units).
pub fn to_toml(alternatives: &[Alternative], style: &UnitStyle) -> String {
    let mut s = String::new();
    for (k, a) in alternatives.iter().enumerate() {
        if k == 0 {
            s.push_str(
                "\n# Structures the evidence could not tell apart from the one above (posterior odds above 1:20):\n\
                 # `imudrift drift` averages its band over them with these weights (docs/drift.md).\n\
                 # Delete them to take the structure above as certain.\n",
            );
        }
        let mut m = SensorModel::default();
        *m.axis_mut(a.channel.sensor(), a.channel.axis()) = a.axis.clone();
        let effects: Vec<String> = a
            .effects
            .iter()
            .map(|e| format!("\"{}\"", e.name()))
            .collect();
        let _ = writeln!(s, "\n[[alternatives]]");
        let _ = writeln!(s, "channel = \"{}\"", a.channel.name());
        let _ = writeln!(s, "weight = {:?}", a.weight);
        let _ = writeln!(s, "delta_bic = {:?}", a.delta_bic);
        let _ = writeln!(s, "effects = [{}]", effects.join(", "));
        let removed: Vec<String> = a
            .removed
            .iter()
            .map(|e| format!("\"{}\"", e.name()))
            .collect();
        let _ = writeln!(s, "removed = [{}]", removed.join(", "));
        let _ = writeln!(s, "[alternatives.terms]");
        s.push_str(&m.axis_toml_styled(a.channel.sensor(), a.channel.axis(), style));
    }
    s
}

#[derive(serde::Deserialize)]
struct Document {
    alternatives: Option<Vec<toml::Table>>,
}

/// The `[[alternatives]]` of a model's TOML text (none when it has none); `source` names the file.
pub fn from_model_text(text: &str, source: &str) -> Result<Vec<Alternative>, AlternativesError> {
    let doc: Document =
        toml::from_str(text).map_err(|e| AlternativesError::Syntax(e.message().to_string()))?;
    let mut out = Vec::new();
    for (k, t) in doc.alternatives.unwrap_or_default().into_iter().enumerate() {
        out.push(entry(k + 1, &t, source)?);
    }
    let mut total = ImuChannels::from_fn(|_| 0.0);
    for a in &out {
        total[a.channel] += a.weight;
    }
    if let Some((c, &t)) = total.iter().find(|(_, &t)| t >= 1.0) {
        return Err(AlternativesError::Weights {
            channel: c.name(),
            total: t,
        });
    }
    Ok(out)
}

/// Entry `entry` (1-based) of `[[alternatives]]`.
fn entry(entry: usize, t: &toml::Table, source: &str) -> Result<Alternative, AlternativesError> {
    let bad = |key, expected| AlternativesError::Value {
        entry,
        key,
        expected,
    };
    let channel = t
        .get("channel")
        .and_then(toml::Value::as_str)
        .and_then(Channel::from_name)
        .ok_or(bad("channel", "one of gx gy gz ax ay az"))?;
    let weight = t
        .get("weight")
        .and_then(toml::Value::as_float)
        .filter(|w| *w > 0.0 && *w < 1.0)
        .ok_or(bad("weight", "a number between 0 and 1"))?;
    let delta_bic = match t.get("delta_bic") {
        None => f64::NAN,
        Some(v) => v
            .as_float()
            .ok_or(bad("delta_bic", "a number (the BIC difference)"))?,
    };
    let names = |key: &'static str| match t.get(key) {
        None => Ok(Vec::new()),
        Some(v) => v
            .as_array()
            .and_then(|a| {
                a.iter()
                    .map(|e| e.as_str().and_then(Effect::from_name))
                    .collect::<Option<Vec<Effect>>>()
            })
            .ok_or(bad(key, "a list of effect names")),
    };
    let effects = names("effects")?;
    let removed = names("removed")?;
    let terms = t
        .get("terms")
        .and_then(toml::Value::as_table)
        .ok_or(bad("terms", "a table of the channel's terms"))?;
    let mut axis_table = toml::Table::new();
    axis_table.insert(
        ["x", "y", "z"][channel.axis()].to_string(),
        toml::Value::Table(terms.clone()),
    );
    let mut doc = toml::Table::new();
    doc.insert("name".into(), "alternative".into());
    doc.insert(
        channel.sensor().name().to_string(),
        toml::Value::Table(axis_table),
    );
    let text = toml::to_string(&doc).map_err(|e| AlternativesError::Terms {
        entry,
        message: e.to_string(),
    })?;
    let m = SensorModel::from_toml_str(&text, source).map_err(|e| AlternativesError::Terms {
        entry,
        message: e.to_string(),
    })?;
    Ok(Alternative {
        channel,
        weight,
        delta_bic,
        effects,
        removed,
        axis: m.axis(channel.sensor(), channel.axis()).clone(),
    })
}

/// One structure of the whole model: its weight, the model and what it is.
#[derive(Clone, Debug)]
pub struct Structure {
    pub weight: f64,
    pub model: SensorModel,
    /// "as fitted", or the alternatives it takes ("gz: slow_gauss_markov").
    pub label: String,
}

/// The model's structures: every combination of each channel's own structure and its
/// alternatives (channels independent), weights multiplied; the model as fitted first.
pub fn structures(model: &SensorModel, alternatives: &[Alternative]) -> Vec<Structure> {
    let mut out = vec![Structure {
        weight: 1.0,
        model: model.clone(),
        label: "as fitted".into(),
    }];
    for c in Channel::ALL {
        let alts: Vec<&Alternative> = alternatives.iter().filter(|a| a.channel == c).collect();
        if alts.is_empty() {
            continue;
        }
        let own = 1.0 - alts.iter().map(|a| a.weight).sum::<f64>();
        let mut next = Vec::new();
        for s in &out {
            next.push(Structure {
                weight: s.weight * own,
                ..s.clone()
            });
            for a in &alts {
                let mut m = s.model.clone();
                *m.axis_mut(c.sensor(), c.axis()) = a.axis.clone();
                let names: Vec<String> = a
                    .effects
                    .iter()
                    .map(|e| e.name().to_string())
                    .chain(a.removed.iter().map(|e| format!("no {}", e.name())))
                    .collect();
                let what = if names.is_empty() {
                    "other terms".to_string()
                } else {
                    names.join(", ")
                };
                let this = format!("{}: {what}", c.name());
                next.push(Structure {
                    weight: s.weight * a.weight,
                    model: m,
                    label: if s.label == "as fitted" {
                        this
                    } else {
                        format!("{}; {this}", s.label)
                    },
                });
            }
        }
        out = next;
    }
    out
}

/// `n` replicates shared out in proportion to `weights` by largest remainders (Hamilton's
/// method): each gets floor(n w), the rest one each to the largest fractional parts, ties to the
/// earlier. The counts add up to `n`.
pub fn allocate(weights: &[f64], n: usize) -> Vec<usize> {
    let total: f64 = weights.iter().sum();
    if weights.is_empty() || total.is_nan() || total <= 0.0 {
        return vec![0; weights.len()];
    }
    let quota: Vec<f64> = weights.iter().map(|w| n as f64 * w / total).collect();
    let mut counts: Vec<usize> = quota.iter().map(|q| q.floor() as usize).collect();
    let mut order: Vec<usize> = (0..weights.len()).collect();
    order.sort_by(|&a, &b| {
        let (fa, fb) = (quota[a] - quota[a].floor(), quota[b] - quota[b].floor());
        fb.total_cmp(&fa).then(a.cmp(&b))
    });
    let mut left = n.saturating_sub(counts.iter().sum());
    for &i in order.iter().cycle() {
        if left == 0 {
            break;
        }
        counts[i] += 1;
        left -= 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_follow_the_bic_differences() {
        let w = weights(&[2.0 * 2f64.ln()]);
        // exp(-ln 2) = 1/2 against 1: 2/3 and 1/3.
        assert!((w[0] - 2.0 / 3.0).abs() < 1e-12 && (w[1] - 1.0 / 3.0).abs() < 1e-12);
        assert!((OCCAM_DELTA_BIC - 2.0 * 20f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn allocation_adds_up_and_follows_the_quotas() {
        assert_eq!(allocate(&[0.87, 0.13], 40), vec![35, 5]);
        assert_eq!(allocate(&[0.61, 0.39], 40), vec![24, 16]);
        assert_eq!(allocate(&[1.0], 40), vec![40]);
        let c = allocate(&[0.5, 0.3, 0.2], 7);
        assert_eq!(c.iter().sum::<usize>(), 7);
        assert_eq!(c, vec![4, 2, 1]);
        assert_eq!(allocate(&[0.0, 0.0], 5), vec![0, 0]);
    }

    fn model() -> SensorModel {
        SensorModel::from_toml_str(
            "name = \"m\"\n[gyro.z]\nwhite_noise = \"0.04 deg/s/sqrt(Hz)\"\nrate_random_walk = \"100 deg/h/sqrt(h)\"\n",
            "m.toml",
        )
        .unwrap()
    }

    fn alternative() -> Alternative {
        let mut alt = model();
        let axis = alt.axis_mut(noise::Sensor::Gyro, 2);
        axis.remove(Effect::RateRandomWalk);
        let gm = SensorModel::from_toml_str(
            "name = \"g\"\n[gyro.z]\nslow_gauss_markov = { sigma = \"0.016 deg/s\", time_constant = \"900 s\" }\n",
            "g.toml",
        )
        .unwrap();
        let term = gm
            .axis(noise::Sensor::Gyro, 2)
            .term(Effect::SlowGaussMarkov)
            .unwrap()
            .clone();
        axis.set_term(term);
        let axis = axis.clone();
        Alternative {
            channel: Channel::Gz,
            weight: 0.25,
            delta_bic: 2.0 * 3f64.ln(),
            effects: differing_effects(model().axis(noise::Sensor::Gyro, 2), &axis),
            removed: removed_effects(model().axis(noise::Sensor::Gyro, 2), &axis),
            axis,
        }
    }

    #[test]
    fn alternatives_round_trip_through_the_model_text() {
        let m = model();
        let a = alternative();
        assert_eq!(a.effects, vec![Effect::SlowGaussMarkov]);
        let main = m.to_toml_string_styled(&UnitStyle::default());
        let text = main.clone() + &to_toml(std::slice::from_ref(&a), &UnitStyle::default());
        // The noise crate reads the model and skips the table.
        assert_eq!(
            SensorModel::from_toml_str(&text, "t.toml").unwrap(),
            SensorModel::from_toml_str(&main, "t.toml").unwrap()
        );
        let back = from_model_text(&text, "t.toml").unwrap();
        assert_eq!(back.len(), 1);
        let b = &back[0];
        assert_eq!(
            (b.channel, b.weight, b.delta_bic),
            (a.channel, a.weight, a.delta_bic)
        );
        assert_eq!(b.effects, a.effects);
        assert_eq!(b.removed, vec![Effect::RateRandomWalk]);
        // Written to five digits: the terms agree to that.
        let sigma = |ax: &AxisModel| match ax.term(Effect::SlowGaussMarkov) {
            Some(t) => t.level().unwrap().1,
            None => f64::NAN,
        };
        assert!((sigma(&b.axis) / sigma(&a.axis) - 1.0).abs() < 1e-4);
        assert!(b.axis.term(Effect::RateRandomWalk).is_none());
    }

    #[test]
    fn bad_alternatives_name_the_entry_and_key() {
        let base = "name = \"m\"\n";
        let e = from_model_text(
            &format!(
                "{base}[[alternatives]]\nchannel = \"gq\"\nweight = 0.2\n[alternatives.terms]\n"
            ),
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("entry 1") && e.contains("channel"), "{e}");
        let e = from_model_text(
            &format!(
                "{base}[[alternatives]]\nchannel = \"gz\"\nweight = 1.5\n[alternatives.terms]\n"
            ),
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("weight"), "{e}");
        let e = from_model_text(
            &format!("{base}[[alternatives]]\nchannel = \"gz\"\nweight = 0.2\n[alternatives.terms]\nwhite_noise = \"-1 deg/s/sqrt(Hz)\"\n"),
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("terms") && e.contains("white_noise"), "{e}");
        let two = format!(
            "{base}[[alternatives]]\nchannel = \"gz\"\nweight = 0.6\n[alternatives.terms]\n\
             [[alternatives]]\nchannel = \"gz\"\nweight = 0.5\n[alternatives.terms]\n"
        );
        let e = from_model_text(&two, "t.toml").unwrap_err().to_string();
        assert!(e.contains("add up"), "{e}");
    }

    #[test]
    fn structures_combine_channels_and_weights() {
        let m = model();
        let a = alternative();
        let mut b = a.clone();
        b.channel = Channel::Gx;
        b.weight = 0.5;
        let s = structures(&m, &[a, b]);
        assert_eq!(s.len(), 4);
        let w: Vec<f64> = s.iter().map(|s| s.weight).collect();
        for (got, want) in w.iter().zip([0.375, 0.125, 0.375, 0.125]) {
            assert!((got - want).abs() < 1e-12, "{w:?}");
        }
        assert_eq!(s[0].label, "as fitted");
        assert_eq!(
            s[3].label,
            "gx: slow_gauss_markov, no rate_random_walk; gz: slow_gauss_markov, no rate_random_walk"
        );
        assert!(s[1]
            .model
            .axis(noise::Sensor::Gyro, 2)
            .term(Effect::SlowGaussMarkov)
            .is_some());
    }
}
