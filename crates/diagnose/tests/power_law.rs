//! The power-law candidate (issue 44 item 3): a fractional power law S(f) ~ f^alpha hidden in a
//! log is named with its slope's 95 % interval holding the truth, and clean logs of the other slow
//! types do not name it.
//!
//! Recovery logs have 2^18 samples at 100 Hz (43.7 min, octave taus 0.01-655 s); on the
//! hidden-effect suite's 2^16 (655 s, taus to 164 s) a Gauss-Markov process takes the power law's
//! place on 2 of 5 seeds, the two being alike over so few decades (docs/diagnose.md). The clean
//! logs have 2^16 samples. The ADIS16405 runs' length (1e6 samples) would cost 4 times as much
//! per seed again. The CI tests run a few seeds; the figures of docs/diagnose.md come from the
//! `#[ignore]`d versions:
//! `cargo test --release -p imudrift-diagnose --test power_law -- --ignored --nocapture`.

mod common;
use common::{base_model, GeneratedLog, SEEDS};
use diagnose::model_terms::set_term;
use diagnose::Diagnosis;
use noise::{Channel, Effect, GaussMarkov, PowerLaw, RateRandomWalk, SensorModel};

/// Clean logs: the hidden-effect suite's length.
const SAMPLES: usize = 1 << 16;
/// Recovery logs (`IMUDRIFT_PL_SAMPLES` overrides).
fn recovery_samples() -> usize {
    std::env::var("IMUDRIFT_PL_SAMPLES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1 << 18)
}
/// The hidden slope: between flicker and a random walk, an Allan deviation rising as tau^0.25.
const ALPHA: f64 = -1.5;
/// Where the hidden power law's Allan deviation crosses the white noise's, s.
const CROSSING_S: f64 = 3.0;

/// White noise only (the base of the recovery test) with a power law of slope [`ALPHA`] on ay,
/// its ideal line crossing the white noise at [`CROSSING_S`]: level^2 (tau / 1 s)^(-alpha-1) =
/// N^2 / tau there.
fn with_hidden_power_law(base: &SensorModel) -> SensorModel {
    let ch = Channel::Ay;
    let n = base
        .axis(ch.sensor(), ch.axis())
        .get::<noise::WhiteNoise>()
        .unwrap()
        .density();
    let level = n / CROSSING_S.powf((-ALPHA - 1.0 + 1.0) / 2.0);
    let mut model = base.clone();
    set_term(
        &mut model,
        ch,
        PowerLaw::with_alpha(ALPHA, level, 1.0).unwrap().into(),
    );
    model
}

/// The slope named with its 95 % interval, or what was named instead.
type Found = Result<(f64, f64, f64), String>;

/// One recovery seed: the slope named on ay with its interval (Err: not named), and what was
/// named on the other, clean channels (the rule's own false alarms, counted apart).
fn recovery(seed: u64) -> (Found, Vec<String>) {
    let base = base_model(false);
    let model = with_hidden_power_law(&base);
    let d =
        GeneratedLog::new(&model, recovery_samples(), 7000 + seed, false).diagnose(&base, SEEDS);
    let elsewhere = named_except(&d, Channel::Ay);
    let ay = &d.channels[&Channel::Ay];
    let named: Vec<&str> = ay.effects.iter().map(|e| e.effect.name()).collect();
    let Some(found) = ay.effects.iter().find(|e| e.effect == Effect::PowerLaw) else {
        let weighed: Vec<(usize, &str, i64)> = ay
            .candidates
            .iter()
            .map(|r| (r.round, r.effect.effect.name(), r.delta_bic as i64))
            .collect();
        eprintln!("seed {seed}: ay named {named:?}, candidates {weighed:?}");
        return (
            Err(format!("seed {seed}: ay named {named:?}, no power_law")),
            elsewhere,
        );
    };
    let (a, lo, hi) = (
        found.parameters["alpha"],
        found.parameters_lo["alpha"],
        found.parameters_hi["alpha"],
    );
    eprintln!(
        "seed {seed}: alpha {a:.3} [{lo:.3}, {hi:.3}], named on ay {named:?}, gap {:.2} -> {:.2}{}",
        ay.gap_initial,
        ay.gap_final,
        if elsewhere.is_empty() {
            String::new()
        } else {
            format!(", elsewhere {elsewhere:?}")
        }
    );
    (Ok((a, lo, hi)), elsewhere)
}

/// Over `seeds` seeds: in how many the named slope's interval holds [`ALPHA`], the misses, and
/// the false alarms on the clean channels.
fn recovery_count(seeds: u64) -> (u64, Vec<String>, Vec<String>) {
    let (mut misses, mut alarms) = (Vec::new(), Vec::new());
    for seed in 0..seeds {
        let (found, elsewhere) = recovery(seed);
        match found {
            Ok((_, lo, hi)) if lo <= ALPHA && ALPHA <= hi => {}
            Ok((a, lo, hi)) => misses.push(format!("seed {seed}: alpha {a} [{lo}, {hi}]")),
            Err(e) => misses.push(e),
        }
        alarms.extend(elsewhere.into_iter().map(|e| format!("seed {seed}: {e}")));
    }
    (seeds - misses.len() as u64, misses, alarms)
}

/// (channel, effect) pairs named on channels other than `except`.
fn named_except(d: &Diagnosis, except: Channel) -> Vec<String> {
    Channel::ALL
        .into_iter()
        .filter(|&c| c != except)
        .flat_map(|c| {
            d.channels[&c]
                .effects
                .iter()
                .map(move |e| format!("{} {}", c.name(), e.effect.name()))
        })
        .collect()
}

/// A clean log of one of the other slow types: white noise with flicker, with a rate random walk,
/// or with a Gauss-Markov process, on every channel (`kind` 0, 1, 2), at levels where the slow
/// term dominates the long taus.
fn clean_model(kind: u64) -> SensorModel {
    let mut m = base_model(kind == 0);
    if kind > 0 {
        for ch in Channel::ALL {
            let scale = if ch.is_gyro() { 1e-4 } else { 1e-3 };
            let term: noise::Term = if kind == 1 {
                // K^2 tau/3 crosses N^2/tau at tau = sqrt(3) N / K = 10 s.
                RateRandomWalk::new(scale * 3f64.sqrt() / 10.0)
                    .unwrap()
                    .into()
            } else {
                // ADEV peak 0.617 sigma at 1.89 T = 38 s, 4 times the white noise there.
                GaussMarkov::new(4.0 * scale / 38f64.sqrt() / 0.6174, 20.0)
                    .unwrap()
                    .into()
            };
            set_term(&mut m, ch, term);
        }
    }
    m
}

/// Logs of `n` clean models (the three kinds in turn) diagnosed with their own model: those that
/// name power_law, and those that name anything.
fn null_count(n: u64) -> (Vec<String>, Vec<String>) {
    let (mut power, mut any) = (Vec::new(), Vec::new());
    for i in 0..n {
        let m = clean_model(i % 3);
        let d = GeneratedLog::new(&m, SAMPLES, 9000 + i, false)
            .diagnose(&m, diagnose::Settings::default().seeds);
        for c in Channel::ALL {
            for e in &d.channels[&c].effects {
                let what = format!("log {i} (kind {}): {} {}", i % 3, c.name(), e.effect.name());
                if e.effect == Effect::PowerLaw {
                    power.push(what.clone());
                }
                any.push(what);
            }
        }
    }
    (power, any)
}

#[test]
fn hidden_power_law_is_named_with_its_slope() {
    // 5 seeds; each holds the truth with probability about 0.95, so all 5 do with 0.77: one miss
    // is allowed (P(2 or more misses) = 0.023 at the nominal rate). The clean channels may show
    // the rule's own false alarms (~1e-3 per log), not more than one in 5 logs.
    let (held, misses, alarms) = recovery_count(5);
    assert!(held >= 4, "{held} of 5: {}", misses.join("\n"));
    assert!(alarms.len() <= 1, "{alarms:?}");
}

#[test]
fn clean_slow_logs_do_not_name_power_law() {
    // 6 clean logs (two of each kind): at the rule's ~1e-3 false alarms per log none may name it.
    let (power, any) = null_count(6);
    eprintln!("named on 6 clean logs: {any:?}");
    assert!(power.is_empty(), "{power:?}");
}

/// The figure: of 100 seeds, how many hold alpha = -1.5 in the named power law's 95 %
/// interval. The issue asks for at least 95; an exact 95 % interval meets that in only 56 % of
/// such experiments (P(X >= 95) for X ~ Binomial(100, 0.95)), so the test asserts what a 95 %
/// interval fails with probability 1e-3 at most: at least 87 (P(X <= 86) = 4.6e-4; P(X <= 87) =
/// 1.5e-3). Measured: 100 of 100 with the correlation factor, 93 before it (docs/diagnose.md).
#[test]
#[ignore]
fn hidden_power_law_recovered_in_95_of_100_seeds() {
    let (held, misses, alarms) = recovery_count(100);
    eprintln!(
        "held in {held} of 100; misses:\n{}\nnamed on clean channels: {alarms:?}",
        misses.join("\n")
    );
    assert!(held >= 87, "{held} of 100");
}

/// The null: 50 clean logs of the other slow types. At the rule's ~1e-3 false alarms per
/// 6-channel log (docs/diagnose.md, step 4) 50 logs expect 0.05 alarms of any kind; 2 or more
/// power laws would happen with probability about 1e-3 at that rate.
#[test]
#[ignore]
fn fifty_clean_slow_logs_do_not_name_power_law() {
    let (power, any) = null_count(50);
    eprintln!(
        "power_law named on {} of 50 clean logs; anything named: {any:?}",
        power.len()
    );
    assert!(power.len() <= 1, "{power:?}");
}
