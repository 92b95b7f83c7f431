//! Several runs of one sensor in one diagnosis (docs/diagnose.md, "Several runs"): what is per
//! run stays per run (the turn-on bias, removed with each run's mean; the warm-up transient, the
//! temperature regression and the outliers, found by step 0 on each run), and the model takes one
//! term from the runs' findings. The Allan pooling is in `measure` and `simulate`.

use crate::detect::Finding;
use crate::input::LogInput;
use noise::{Channel, Effect};

/// Two-sided 95 % normal quantile.
const Z_95: f64 = 1.959_963_984_540_054;

/// The model's term from the step-0 findings of every run (`per_run[r]` the findings of run r on one
/// channel, `hours[r]` its length): one finding per effect, in the order first found. One run:
/// its findings unchanged. Several: outliers as one rate over all the runs' hours (count-weighted
/// size); a temperature coefficient as the inverse-variance weighted mean of the runs' (their
/// standard errors from the 95 % bounds); a warm-up transient as a per-run term (`per_run`: the
/// amplitude drawn per turn-on) whose amplitude is the RMS of the runs' that show one, its time
/// constant their geometric mean. The evidence (delta BIC) of independent runs adds up.
pub(crate) fn pooled_findings(per_run: &[&[Finding]], hours: &[f64]) -> Vec<Finding> {
    if per_run.len() == 1 {
        return per_run[0].to_vec();
    }
    let mut effects: Vec<Effect> = Vec::new();
    for f in per_run.iter().flat_map(|f| f.iter()) {
        if !effects.contains(&f.term.effect()) {
            effects.push(f.term.effect());
        }
    }
    effects
        .into_iter()
        .map(|effect| {
            let found: Vec<&Finding> = per_run
                .iter()
                .flat_map(|f| f.iter())
                .filter(|f| f.term.effect() == effect)
                .collect();
            let mut pooled = match effect {
                Effect::Outliers => outliers(&found, hours.iter().sum()),
                Effect::TemperatureBias => temperature(&found),
                Effect::WarmupTransient => transient(&found),
                _ => found[0].clone(),
            };
            pooled.delta_bic = found.iter().map(|f| f.delta_bic).sum();
            pooled.cannot_tell_from = found
                .iter()
                .flat_map(|f| f.cannot_tell_from.iter().copied())
                .fold(Vec::new(), |mut v, e| {
                    if !v.contains(&e) {
                        v.push(e);
                    }
                    v
                });
            pooled
        })
        .collect()
}

/// A named parameter's value of a finding (NaN when absent).
fn value(f: &Finding, name: &str) -> f64 {
    f.parameters
        .iter()
        .find(|p| p.0 == name)
        .map_or(f64::NAN, |p| p.1)
}

fn outliers(found: &[&Finding], hours: f64) -> Finding {
    let counts: Vec<f64> = found.iter().map(|f| value(f, "count")).collect();
    let count: f64 = counts.iter().sum();
    let sizes: Vec<f64> = found.iter().map(|f| value(f, "size")).collect();
    let size = stats::weighted_mean(&sizes, &counts);
    let rate = count / hours;
    // Poisson 95 % bounds on the rate (normal approximation with continuity), as for one run.
    let (lo, hi) = (
        (count - Z_95 * count.sqrt()).max(0.0) / hours,
        (count + Z_95 * count.sqrt() + 1.0) / hours,
    );
    let threshold = found
        .iter()
        .map(|f| value(f, "threshold_sigma"))
        .fold(f64::NEG_INFINITY, f64::max);
    let n_without: Vec<f64> = found.iter().map(|f| value(f, "n_without")).collect();
    let n_without = stats::mean(&n_without);
    Finding {
        // A rate or size the constructor refuses keeps the first run's (validated) term.
        term: noise::Outliers::new(rate, size).map_or_else(|_| found[0].term.clone(), Into::into),
        cannot_tell_from: vec![],
        parameters: vec![
            ("count", count, count, count),
            ("rate_per_hour", rate, lo, hi),
            ("size", size, size, size),
            ("threshold_sigma", threshold, threshold, threshold),
            ("n_without", n_without, n_without, n_without),
        ],
        delta_bic: 0.0,
    }
}

fn temperature(found: &[&Finding]) -> Finding {
    // Inverse-variance weights (1 where a run gave no interval).
    let (values, weights): (Vec<f64>, Vec<f64>) = found
        .iter()
        .map(|f| {
            let p = f.parameters[0];
            let sd = (p.3 - p.2) / (2.0 * Z_95);
            (p.1, if sd > 0.0 { 1.0 / (sd * sd) } else { 1.0 })
        })
        .unzip();
    let c = stats::weighted_mean(&values, &weights);
    let sd = weights.iter().sum::<f64>().recip().sqrt();
    Finding {
        // A coefficient that is not a finite number keeps the first run's (validated) term.
        term: noise::TemperatureBias::new(c).map_or_else(|_| found[0].term.clone(), Into::into),
        cannot_tell_from: vec![],
        parameters: vec![("coefficient", c, c - Z_95 * sd, c + Z_95 * sd)],
        delta_bic: 0.0,
    }
}

fn transient(found: &[&Finding]) -> Finding {
    let amplitudes: Vec<f64> = found.iter().map(|f| value(f, "amplitude")).collect();
    let amplitude = stats::rms(&amplitudes);
    let ln_tau: Vec<f64> = found.iter().map(|f| value(f, "tau_s").ln()).collect();
    let tau_s = stats::mean(&ln_tau).exp();
    let bound = |name: &str, j: usize, pick: fn(f64, f64) -> f64, start: f64| {
        found
            .iter()
            .filter_map(|f| f.parameters.iter().find(|p| p.0 == name))
            .map(|p| if j == 2 { p.2 } else { p.3 })
            .fold(start, pick)
    };
    let (a_lo, a_hi) = amplitudes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), a| {
            (lo.min(a.abs()), hi.max(a.abs()))
        });
    Finding {
        // Values the constructor refuses keep the first run's (validated) term.
        term: noise::WarmupTransient::new(amplitude, tau_s, true)
            .map_or_else(|_| found[0].term.clone(), Into::into),
        cannot_tell_from: vec![],
        parameters: vec![
            ("amplitude", amplitude, a_lo, a_hi),
            (
                "tau_s",
                tau_s,
                bound("tau_s", 2, f64::min, f64::INFINITY),
                bound("tau_s", 3, f64::max, f64::NEG_INFINITY),
            ),
        ],
        delta_bic: 0.0,
    }
}

/// The rate-ramp level of channel `c` over the runs (`trials`: a ramp's level is the log's
/// least-squares slope): one run's slope; several runs' RMS slope weighted by their lengths (each
/// run's slope adds its square to the pooled Allan variance, R^2 tau^2 / 2), signed as their
/// weighted mean.
pub(crate) fn ramp_slope(logs: &[LogInput], c: Channel) -> f64 {
    let slopes: Vec<(f64, f64)> = logs
        .iter()
        .filter_map(|l| l.channels[c].map(|x| (x.len() as f64, crate::stats::slope(x, l.dt_s))))
        .collect();
    if let [(_, r)] = slopes[..] {
        return r;
    }
    let (lengths, rates): (Vec<f64>, Vec<f64>) = slopes.into_iter().unzip();
    let mean = stats::weighted_mean(&rates, &lengths);
    let rms = stats::weighted_mean_square(&rates, &lengths).sqrt();
    if lengths.iter().sum::<f64>() > 0.0 {
        rms.copysign(mean)
    } else {
        0.0
    }
}
