//! Drift requirements (`spec --require "pos_horizontal_m < 10 m @ 300 s"`): a statistic of the
//! absolute error of one navigation-error quantity ([`NavQuantity`]) at one time, compared with a threshold, with the Monte
//! Carlo uncertainty of the statistic so a verdict near the threshold says so.
//!
//! Grammar: `[STAT] CHANNEL (<|<=) VALUE [UNIT] @ TIME [UNIT]`, where STAT is `p50`, `p68`, `p95`,
//! `p99`, `rms` or `mean` (default `p95`: a requirement usually bounds what 95 % of runs stay
//! under), CHANNEL a quantity's name (`heading_rad`, `pos_horizontal_m`, ...), VALUE in the
//! quantity's SI unit unless a unit is given (angles: rad, mrad, deg, arcmin, arcsec; positions:
//! m, km, cm, mm, ft, nmi; velocities: m/s, mm/s, cm/s, km/h, ft/s, kn), and TIME in s, ms, min
//! or h. Statistics are of |error| over the runs.

use crate::nav_quantity::NavQuantity;
use ::stats::quantile;
use serde::Serialize;

/// Two-sided 95 % standard normal quantile (Monte Carlo interval of a statistic).
const Z_95: f64 = 1.959_963_984_540_054;

/// Why a requirement string could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("requirement \"{text}\": {problem}; expected `[p50|p68|p95|p99|rms|mean] CHANNEL < VALUE [UNIT] @ TIME`, e.g. \"pos_horizontal_m < 10 m @ 300 s\" or \"p50 heading_rad < 2 deg @ 10 min\"")]
pub struct RequirementError {
    pub text: String,
    pub problem: String,
}

/// The statistic a requirement bounds, of |error| over the runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Statistic {
    Mean,
    Rms,
    P50,
    P68,
    P95,
    P99,
}

impl Statistic {
    fn from_name(s: &str) -> Option<Statistic> {
        Some(match s.to_ascii_lowercase().as_str() {
            "mean" => Statistic::Mean,
            "rms" => Statistic::Rms,
            "p50" | "median" => Statistic::P50,
            "p68" => Statistic::P68,
            "p95" => Statistic::P95,
            "p99" => Statistic::P99,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Statistic::Mean => "mean",
            Statistic::Rms => "rms",
            Statistic::P50 => "p50",
            Statistic::P68 => "p68",
            Statistic::P95 => "p95",
            Statistic::P99 => "p99",
        }
    }

    fn probability(self) -> Option<f64> {
        match self {
            Statistic::P50 => Some(0.50),
            Statistic::P68 => Some(0.68),
            Statistic::P95 => Some(0.95),
            Statistic::P99 => Some(0.99),
            Statistic::Mean | Statistic::Rms => None,
        }
    }
}

/// A parsed requirement (SI).
#[derive(Debug, Clone, PartialEq)]
pub struct Requirement {
    pub text: String,
    pub statistic: Statistic,
    pub quantity: NavQuantity,
    /// `<=` rather than `<`.
    pub inclusive: bool,
    pub threshold_si: f64,
    pub t_s: f64,
}

fn unit_scale(quantity: NavQuantity, unit: &str) -> Option<f64> {
    let name = quantity.name();
    let u = unit.trim();
    if name.ends_with("_rad") {
        Some(match u {
            "rad" => 1.0,
            "mrad" => 1e-3,
            "urad" | "µrad" => 1e-6,
            "deg" | "°" | "º" => std::f64::consts::PI / 180.0,
            "arcmin" | "'" => std::f64::consts::PI / 180.0 / 60.0,
            "arcsec" | "\"" => std::f64::consts::PI / 180.0 / 3600.0,
            _ => return None,
        })
    } else if name.ends_with("_mps") {
        Some(match u {
            "m/s" => 1.0,
            "mm/s" => 1e-3,
            "cm/s" => 1e-2,
            "km/h" => 1.0 / 3.6,
            "ft/s" => 0.3048,
            "kn" | "kt" => 1852.0 / 3600.0,
            _ => return None,
        })
    } else {
        Some(match u {
            "m" => 1.0,
            "km" => 1e3,
            "cm" => 1e-2,
            "mm" => 1e-3,
            "ft" => 0.3048,
            "nmi" => 1852.0,
            _ => return None,
        })
    }
}

fn time_s(text: &str) -> Option<f64> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == 'E' || c == '+'))
        .unwrap_or(t.len());
    // "1e3s" keeps its exponent; a unit starting with 'e' does not exist here.
    let (num, unit) = t.split_at(split);
    let v: f64 = num.trim().parse().ok()?;
    let scale = match unit.trim() {
        "" | "s" | "sec" => 1.0,
        "ms" => 1e-3,
        "min" => 60.0,
        "h" | "hr" => 3600.0,
        _ => return None,
    };
    let s = v * scale;
    (s.is_finite() && s > 0.0).then_some(s)
}

impl std::str::FromStr for Requirement {
    type Err = RequirementError;

    fn from_str(text: &str) -> Result<Requirement, RequirementError> {
        let fail = |problem: String| RequirementError {
            text: text.to_string(),
            problem,
        };
        let (lhs_rhs, time) = text
            .split_once('@')
            .ok_or_else(|| fail("no `@ TIME`".into()))?;
        let t_s = time_s(time).ok_or_else(|| {
            fail(format!(
                "`{}` is not a time > 0 (s, ms, min or h)",
                time.trim()
            ))
        })?;
        let (lhs, rhs, inclusive) = if let Some((l, r)) = lhs_rhs.split_once("<=") {
            (l, r, true)
        } else if let Some((l, r)) = lhs_rhs.split_once('<') {
            (l, r, false)
        } else {
            return Err(fail("no `<` or `<=`".into()));
        };
        let words: Vec<&str> = lhs.split_whitespace().collect();
        let (statistic, quantity_name) = match words.as_slice() {
            [name] => (Statistic::P95, *name),
            [st, name] => (
                Statistic::from_name(st).ok_or_else(|| {
                    fail(format!(
                        "unknown statistic `{st}` (p50, p68, p95, p99, rms or mean)"
                    ))
                })?,
                *name,
            ),
            _ => return Err(fail("expected a channel name before `<`".into())),
        };
        let quantity = NavQuantity::from_name(quantity_name).ok_or_else(|| {
            fail(format!(
                "unknown channel `{quantity_name}` (one of {}; `yaw_rad` is accepted for heading_rad)",
                NavQuantity::ALL.map(|c| c.label()).join(", ")
            ))
        })?;
        let rhs = rhs.trim();
        let split = rhs
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '+' | '-' | 'e' | 'E')))
            .unwrap_or(rhs.len());
        let (num, unit) = rhs.split_at(split);
        let value: f64 = num
            .trim()
            .parse()
            .map_err(|_| fail(format!("`{rhs}` does not start with a number")))?;
        let scale = if unit.trim().is_empty() {
            1.0
        } else {
            unit_scale(quantity, unit).ok_or_else(|| {
                fail(format!(
                    "unit `{}` does not fit channel {}",
                    unit.trim(),
                    quantity.label()
                ))
            })?
        };
        let threshold_si = value * scale;
        if !(threshold_si.is_finite() && threshold_si > 0.0) {
            return Err(fail(format!("threshold {value} is not a number > 0")));
        }
        Ok(Requirement {
            text: text.trim().to_string(),
            statistic,
            quantity,
            inclusive,
            threshold_si,
            t_s,
        })
    }
}

/// The verdict of a requirement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The statistic is under the threshold and so is its 95 % Monte Carlo upper bound.
    Pass,
    /// The statistic is over the threshold and so is its 95 % Monte Carlo lower bound.
    Fail,
    /// The threshold lies inside the statistic's 95 % Monte Carlo interval: more runs decide it.
    Undecided,
    /// The model has no error term that drives this quantity (e.g. attitude without gyro terms).
    NotInformed,
}

/// A requirement evaluated for one sensor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RequirementResult {
    pub requirement: String,
    pub statistic: Statistic,
    /// The quantity's name (JSON key `channel`, docs/cli.md).
    #[serde(rename = "channel")]
    pub quantity: &'static str,
    pub t_s: f64,
    pub threshold: f64,
    /// The statistic of |error| over the runs (SI).
    pub value: Option<f64>,
    /// Its 95 % Monte Carlo interval (order statistics for quantiles, normal for mean and rms).
    pub value_lo: Option<f64>,
    pub value_hi: Option<f64>,
    pub pass: Option<bool>,
    pub verdict: Verdict,
    /// threshold - value (SI): positive when the requirement is met.
    pub margin: Option<f64>,
    /// margin / threshold.
    pub margin_fraction: Option<f64>,
    pub runs: usize,
}

/// Evaluate `req` on the per-run signed errors `values` of its quantity at its time.
/// `informed` is false when the model has no term that drives the quantity.
pub fn evaluate(req: &Requirement, values: &[f64], informed: bool) -> RequirementResult {
    let mut abs: Vec<f64> = values.iter().map(|v| v.abs()).collect();
    abs.sort_unstable_by(f64::total_cmp);
    let n = abs.len();
    let (value, lo, hi) = if n == 0 || !informed {
        (None, None, None)
    } else {
        match req.statistic.probability() {
            Some(p) => {
                // Distribution-free interval of a quantile: the order statistics at
                // n p -+ z sqrt(n p (1 - p)) (normal approximation to the binomial count of
                // runs below the quantile; e.g. Hahn & Meeker, Statistical Intervals, 1991, 5.2).
                let half = Z_95 * (n as f64 * p * (1.0 - p)).sqrt();
                let idx = |k: f64| abs[(k.round().max(0.0) as usize).min(n - 1)];
                (
                    Some(quantile(&abs, p)),
                    Some(idx(n as f64 * p - half - 1.0)),
                    Some(idx(n as f64 * p + half)),
                )
            }
            None => {
                let mean = ::stats::mean(&abs);
                let sq: Vec<f64> = abs.iter().map(|v| v * v).collect();
                let mean_sq = ::stats::mean(&sq);
                match req.statistic {
                    Statistic::Mean => {
                        let se = (::stats::sample_variance(&abs) / n as f64).sqrt();
                        (Some(mean), Some(mean - Z_95 * se), Some(mean + Z_95 * se))
                    }
                    _ => {
                        // rms = sqrt(mean of x^2): interval of the mean of x^2, then the root.
                        let se = (::stats::sample_variance(&sq) / n as f64).sqrt();
                        (
                            Some(mean_sq.sqrt()),
                            Some((mean_sq - Z_95 * se).max(0.0).sqrt()),
                            Some((mean_sq + Z_95 * se).sqrt()),
                        )
                    }
                }
            }
        }
    };
    let under = |v: f64| {
        if req.inclusive {
            v <= req.threshold_si
        } else {
            v < req.threshold_si
        }
    };
    let verdict = match (value, lo, hi) {
        (Some(_), Some(lo), Some(hi)) => {
            if under(hi) {
                Verdict::Pass
            } else if !under(lo) {
                Verdict::Fail
            } else {
                Verdict::Undecided
            }
        }
        _ => Verdict::NotInformed,
    };
    RequirementResult {
        requirement: req.text.clone(),
        statistic: req.statistic,
        quantity: req.quantity.name(),
        t_s: req.t_s,
        threshold: req.threshold_si,
        value,
        value_lo: lo,
        value_hi: hi,
        pass: value.map(under),
        verdict,
        margin: value.map(|v| req.threshold_si - v),
        margin_fraction: value.map(|v| (req.threshold_si - v) / req.threshold_si),
        runs: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_forms() {
        let r: Requirement = "pos_horizontal_m < 10 @ 300s".parse().unwrap();
        assert_eq!(r.statistic, Statistic::P95);
        assert_eq!(r.quantity, NavQuantity::PosHorizontal);
        assert_eq!((r.threshold_si, r.t_s, r.inclusive), (10.0, 300.0, false));
        let r: Requirement = "p50 yaw_rad <= 2 deg @ 10 min".parse().unwrap();
        assert_eq!(r.statistic, Statistic::P50);
        assert!(r.inclusive);
        assert!((r.threshold_si - 2f64.to_radians()).abs() < 1e-15);
        assert_eq!(r.t_s, 600.0);
        let r: Requirement = "rms vel_horizontal_mps < 3.6 km/h @ 1 h".parse().unwrap();
        assert!((r.threshold_si - 1.0).abs() < 1e-12);
        assert_eq!(r.t_s, 3600.0);
        let r: Requirement = "pos_horizontal_m < 1e3 @ 1e2".parse().unwrap();
        assert_eq!((r.threshold_si, r.t_s), (1000.0, 100.0));
    }

    #[test]
    fn heading_has_one_name_and_the_old_ones_still_work() {
        for text in [
            "p50 heading_rad < 2 deg @ 10 min",
            "p50 yaw_rad < 2 deg @ 10 min",
            "p50 heading < 2 deg @ 10 min",
        ] {
            let r: Requirement = text.parse().unwrap();
            assert_eq!(r.quantity, NavQuantity::Yaw, "{text}");
            assert_eq!(r.quantity.label(), "heading_rad");
        }
    }

    #[test]
    fn bad_strings_name_the_problem_and_show_the_form() {
        for (text, needle) in [
            ("pos_horizontal_m < 10", "no `@ TIME`"),
            ("pos_horizontal_m = 10 @ 300", "no `<`"),
            ("p97 pos_horizontal_m < 10 @ 300", "unknown statistic"),
            ("bearing < 10 @ 300", "unknown channel"),
            ("pos_horizontal_m < 10 deg @ 300", "does not fit"),
            ("pos_horizontal_m < -1 @ 300", "> 0"),
            ("pos_horizontal_m < 10 @ 0 s", "time > 0"),
            ("pos_horizontal_m < 10 @ 5 fortnights", "time > 0"),
        ] {
            let e = text.parse::<Requirement>().unwrap_err().to_string();
            assert!(e.contains(needle), "{text}: {e}");
            assert!(
                e.contains("e.g. \"pos_horizontal_m < 10 m @ 300 s\""),
                "{e}"
            );
        }
    }

    #[test]
    fn verdicts_follow_the_monte_carlo_interval() {
        // |x| uniform on 1..=1000 (1000 runs): p95 = 950.05; its 95 % order-statistic interval
        // is about +-1.96 sqrt(1000 * 0.95 * 0.05) = +-13.5 ranks.
        let values: Vec<f64> = (1..=1000)
            .map(|k| if k % 2 == 0 { k as f64 } else { -(k as f64) })
            .collect();
        let req = |t: f64| Requirement {
            text: String::new(),
            statistic: Statistic::P95,
            quantity: NavQuantity::PosHorizontal,
            inclusive: false,
            threshold_si: t,
            t_s: 1.0,
        };
        let r = evaluate(&req(1000.0), &values, true);
        assert!((r.value.unwrap() - 950.05).abs() < 1e-9);
        assert!(r.value_lo.unwrap() < 950.0 && r.value_hi.unwrap() > 951.0);
        assert!(r.value_hi.unwrap() - r.value_lo.unwrap() < 30.0);
        assert_eq!(r.verdict, Verdict::Pass);
        assert!((r.margin.unwrap() - 49.95).abs() < 1e-9);
        assert_eq!(evaluate(&req(900.0), &values, true).verdict, Verdict::Fail);
        assert_eq!(
            evaluate(&req(951.0), &values, true).verdict,
            Verdict::Undecided
        );
        let r = evaluate(&req(951.0), &values, false);
        assert_eq!((r.verdict, r.value), (Verdict::NotInformed, None));
    }
}
