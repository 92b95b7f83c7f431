//! Hidden-effect tests (issue 6, the core): a log is generated from a base model plus a hidden effect on
//! some channels, with the effect's parameters drawn at random, then diagnosed with the base model.
//! The effect must be named on exactly those channels with its parameters within 25 % (or inside the
//! stated 95 % interval), and the final gap must be at most 1.5 and at most a third of the initial gap
//! (only at most 1.5 when the effect is faint: see `common::gap_closed`).
//! Logs without a hidden effect must name nothing on any of 20 seeds (with the default 16-seed band).
//!
//! Log length: 2^16 samples at 100 Hz (655 s), octave taus 0.01..164 s (15 points). Every parameter is
//! drawn as a "visibility": the tau where the hidden term crosses the base model's Allan variance, or
//! its peak ratio over the base, uniformly in log within the stated range; the physical ranges that
//! follow are in the comments (MEMS-grade values). An effect that never rises above the base curve
//! inside the analysed taus cannot be named by any Allan-based method, so the ranges start where the
//! effect is at least comparable to the base somewhere in 0.01..164 s.

mod common;
use common::{base_model, format_z, gap_closed, log_uniform, parameter_ok, run_trials};
use common::{GeneratedLog, DT_S, SEEDS};
use diagnose::candidates::level_term;
use diagnose::model_terms::set_term;
use diagnose::simulate::adev_at;
use diagnose::{Diagnosis, Settings};
use noise::{Channel, Effect, SensorModel, TemperatureProfile, Term};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

const SAMPLES: usize = 1 << 16;

/// Base model Allan variance at tau (closed form of the generator).
fn base_avar(model: &SensorModel, ch: Channel, tau_s: f64) -> f64 {
    let (sensor, axis) = (ch.sensor(), ch.axis());
    model.axis(sensor, axis).allan_variance_sampled(tau_s, DT_S)
}

/// Temperature profile of the temperature-bias test: a climatic chamber cycling 25 +- 5 degC with a
/// 120 s period. (A monotonic warm-up has an Allan signature that a rate random walk can mimic; that
/// case is the "cannot tell" test below.)
fn cycling() -> TemperatureProfile {
    TemperatureProfile::Sinusoid {
        mean_c: 25.0,
        amplitude_c: 5.0,
        period_s: 120.0,
    }
}

/// Draw the hidden effect's parameters for channel `ch` on top of `base`. Where a term "crosses the base
/// at tau_c", its Allan variance equals the base model's there and exceeds it beyond.
fn draw(effect: Effect, base: &SensorModel, ch: Channel, rng: &mut Xoshiro256PlusPlus) -> Term {
    // A one-level term as diagnose would put it on the base model.
    let level = |v: f64| level_term(base, ch, effect, v).unwrap();
    let (sensor, axis) = (ch.sensor(), ch.axis());
    let a = base.axis(sensor, axis);
    let n = a
        .get::<noise::WhiteNoise>()
        .map(noise::WhiteNoise::density)
        .unwrap();
    match effect {
        // Integrated-output quantisation with LSB = Q sqrt(12) of 0.85..1 times the per-sample noise of
        // the integral, N sqrt(dt): gyro LSB 8.5e-6..1e-5 rad (as a rate, 0.05..0.06 deg/s at 100 Hz, like
        // the ADIS16405's 0.05 deg/s), 3Q^2/dt^2 = 18..25 % of the white variance at dt. The closed form
        // 3Q^2/tau^2 assumes a white phase error; with an LSB several times the per-sample noise the
        // residual is correlated from sample to sample (measured: the band departs from the closed form),
        // a different effect, so the range stops at one per-sample noise. Below 0.85 the effect shows at
        // the shortest tau only and its RMS gap over the 15 taus is too small for the gap criterion.
        Effect::Quantization => {
            let lsb = log_uniform(rng, 0.85, 1.0) * n * DT_S.sqrt();
            level(lsb / 12f64.sqrt())
        }
        // White-noise level off by a factor 0.5..0.75 or 1.33..2.
        Effect::WhiteNoise => {
            let f = log_uniform(rng, 1.33, 2.0);
            level(if rng.gen::<bool>() { n * f } else { n / f })
        }
        // Flicker (base without it) crossing the white noise at 0.5..5 s:
        // gyro B = 6.7e-5..2.1e-4 rad/s (14..44 deg/h), consumer-MEMS grade.
        Effect::BiasInstability => {
            let tc = log_uniform(rng, 0.5, 5.0);
            level((n * n / tc / noise::closed_form::flicker_plateau_avar(1.0)).sqrt())
        }
        // K^2 tau/3 crosses the base at 1..8 s: gyro K = 3e-5..8e-5 rad/s/sqrt(s).
        Effect::RateRandomWalk => {
            let tc = log_uniform(rng, 1.0, 8.0);
            level((3.0 * base_avar(base, ch, tc) / tc).sqrt())
        }
        // R^2 tau^2/2 crosses the base at 3..20 s: gyro R = 3e-6..3e-5 rad/s^2.
        Effect::RateRamp => {
            let tc = log_uniform(rng, 3.0, 20.0);
            level((2.0 * base_avar(base, ch, tc)).sqrt() / tc)
        }
        // Correlation time 0.3..15 s; ADEV peak (0.6174 sigma at 1.89 T) 3..8 times the base ADEV there.
        Effect::GaussMarkov => {
            let t = log_uniform(rng, 0.3, 15.0);
            let peak_tau = noise::closed_form::GAUSS_MARKOV_ADEV_PEAK_TAU_PER_TC * t;
            let sigma = log_uniform(rng, 3.0, 8.0) * base_avar(base, ch, peak_tau).sqrt()
                / noise::closed_form::GAUSS_MARKOV_ADEV_PEAK_PER_SIGMA;
            noise::GaussMarkov::new(sigma, t).unwrap().into()
        }
        // Period 0.2..20 s; amplitude such that the first Allan lobe (ADEV 0.72 A near tau = 0.37/f0)
        // is 3..8 times the base ADEV there.
        Effect::Sinusoidal => {
            let period = log_uniform(rng, 0.2, 20.0);
            let amp = log_uniform(rng, 3.0, 8.0) * base_avar(base, ch, 0.37 * period).sqrt() / 0.72;
            noise::Sinusoid::new(amp, 1.0 / period, None)
                .unwrap()
                .into()
        }
        // Coefficient (random sign) such that the temperature term's Allan deviation peaks at 3..8 times the base
        // ADEV (gyro: about 2e-6..1e-5 rad/s/degC, 0.0001..0.0006 deg/s/degC).
        Effect::TemperatureBias => {
            let profile = cycling();
            let temp: Vec<f64> = (0..SAMPLES).map(|k| profile.at(k as f64 * DT_S)).collect();
            let grid: Vec<usize> = (0..15).map(|j| 1usize << j).collect();
            let ratio = adev_at(&temp, DT_S, &grid)
                .iter()
                .zip(&grid)
                .map(|(t, &m)| t / base_avar(base, ch, m as f64 * DT_S).sqrt())
                .fold(0.0, f64::max);
            let k = log_uniform(rng, 3.0, 8.0) / ratio;
            level(if rng.gen::<bool>() { k } else { -k })
        }
        _ => unreachable!(),
    }
}

struct Trial {
    effect: Effect,
    channels: Vec<Channel>,
    truth: Vec<Term>,
    result: Diagnosis,
}

/// Generate a log from `model` (seed `seed`, run 0) and diagnose it with `base`.
fn run(model: &SensorModel, base: &SensorModel, seed: u64, temperature: bool) -> Diagnosis {
    run_seeds(model, base, seed, temperature, SEEDS)
}

/// [`run`] with `seeds` simulated logs per band.
fn run_seeds(
    model: &SensorModel,
    base: &SensorModel,
    seed: u64,
    temperature: bool,
    seeds: usize,
) -> Diagnosis {
    GeneratedLog::new(model, SAMPLES, seed, temperature).diagnose(base, seeds)
}

fn hidden_trial(effect: Effect, trial: u64) -> Trial {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0xD1A6 + 97 * trial + effect as u64 * 1009);
    let base = base_model(effect != Effect::BiasInstability);
    let mut model = base.clone();
    let temperature = effect == Effect::TemperatureBias;
    if temperature {
        model.temperature = cycling();
        model.temperature_reference_c = 25.0;
    }
    // One or two channels, chosen at random.
    let pool = 6;
    let first = rng.gen_range(0..pool);
    let to_channel = |i: usize| Channel::ALL[i];
    let mut channels = vec![to_channel(first)];
    if rng.gen::<bool>() {
        let second = (first + rng.gen_range(1..pool)) % pool;
        channels.push(to_channel(second));
    }
    channels.sort_unstable();
    let truth: Vec<Term> = channels
        .iter()
        .map(|&c| draw(effect, &base, c, &mut rng))
        .collect();
    for (&c, p) in channels.iter().zip(&truth) {
        set_term(&mut model, c, p.clone());
    }
    let result = run(&model, &base, 1000 + trial, temperature);
    Trial {
        effect,
        channels,
        truth,
        result,
    }
}

fn check(trial: &Trial) -> Result<(), String> {
    let mut problems = Vec::new();
    for c in Channel::ALL {
        let name = c.name();
        let report = &trial.result.channels[&c];
        let named: Vec<&str> = report.effects.iter().map(|e| e.effect.name()).collect();
        match trial.channels.iter().position(|&h| h == c) {
            None => {
                if !named.is_empty() {
                    problems.push(format!(
                        "{name}: named {named:?} on a channel without hidden effect"
                    ));
                }
            }
            Some(j) => {
                let Some(found) = report.effects.iter().find(|e| e.effect == trial.effect) else {
                    problems.push(format!(
                        "{name}: hidden {} {:?} not named (named {named:?}; candidates {:?})",
                        trial.effect.name(),
                        trial.truth[j],
                        report
                            .candidates
                            .iter()
                            .map(|r| (r.round, r.effect, r.delta_bic as i64))
                            .collect::<Vec<_>>()
                    ));
                    continue;
                };
                if named.len() != 1 {
                    problems.push(format!(
                        "{name}: named {named:?}, expected only {}",
                        trial.effect.name()
                    ));
                }
                for (key, truth) in trial.truth[j].parameters() {
                    let truth = truth.abs();
                    let value = found.parameters[key].abs();
                    let (lo, hi) = (
                        found.parameters_lo[key].abs(),
                        found.parameters_hi[key].abs(),
                    );
                    let (lo, hi) = (lo.min(hi), lo.max(hi));
                    eprintln!(
                        "{} {name} {key}: {value:.4e} truth {truth:.4e} ({:+.1} %), 95 % [{lo:.3e}, {hi:.3e}], gap {:.2} -> {:.2}",
                        trial.effect.name(),
                        100.0 * (value / truth - 1.0),
                        report.gap_initial,
                        report.gap_final
                    );
                    if !parameter_ok(truth, value, lo, hi) {
                        problems.push(format!("{name}: {key} = {value:.4e}, truth {truth:.4e}, 95 % [{lo:.4e}, {hi:.4e}]"));
                    }
                }
                if !gap_closed(report.gap_initial, report.gap_final) {
                    problems.push(format!(
                        "{name}: gap {:.2} -> {:.2} (need <= 1.5 and <= a third)",
                        report.gap_initial, report.gap_final
                    ));
                }
            }
        }
    }
    // DIAGNOSE_DUMP=1: on a failure, also print the found effects and the z-scores before and after.
    if !problems.is_empty() && std::env::var_os("DIAGNOSE_DUMP").is_some() {
        for &c in &trial.channels {
            let r = &trial.result.channels[&c];
            eprintln!(
                "{}: truth {:?}\n  effects {:?}\n  z0 {}\n  z1 {}",
                c.name(),
                trial.truth,
                r.effects
                    .iter()
                    .map(|e| (&e.effect, &e.parameters, e.gap_before, e.gap_after))
                    .collect::<Vec<_>>(),
                format_z(&r.z_initial),
                format_z(&r.z_final)
            );
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} on {:?}: {}",
            trial.effect.name(),
            trial.channels,
            problems.join("; ")
        ))
    }
}

fn hidden_effect_test(effect: Effect, trials: u64) {
    run_trials(trials, |t| check(&hidden_trial(effect, t)));
}

#[test]
fn hidden_quantization() {
    hidden_effect_test(Effect::Quantization, 3);
}

#[test]
fn hidden_white_noise_level() {
    hidden_effect_test(Effect::WhiteNoise, 3);
}

#[test]
fn hidden_bias_instability() {
    hidden_effect_test(Effect::BiasInstability, 3);
}

#[test]
fn hidden_rate_random_walk() {
    hidden_effect_test(Effect::RateRandomWalk, 3);
}

#[test]
fn hidden_rate_ramp() {
    hidden_effect_test(Effect::RateRamp, 3);
}

#[test]
fn hidden_gauss_markov() {
    hidden_effect_test(Effect::GaussMarkov, 3);
}

#[test]
fn hidden_sinusoid() {
    hidden_effect_test(Effect::Sinusoidal, 3);
}

#[test]
fn hidden_temperature_bias() {
    hidden_effect_test(Effect::TemperatureBias, 3);
}

/// No hidden effect: nothing may be named on at least 95 % of 20 seeds (at most 1 of 20 logs).
/// (With the default BIC threshold the expected false-alarm rate is about 1e-3 per log; measured 0 of 60
/// extra white-noise-only logs while tuning.)
#[test]
fn no_hidden_effect_names_nothing() {
    let mut named = Vec::new();
    for seed in 0..20 {
        // Both bases: white noise + flicker, and white noise only.
        let base = base_model(seed % 2 == 0);
        // With the command's default band (16 seeds): at 12, one of the 20 (seed 12) names a
        // bias-instability level (dBIC 22), the band's seed spread being estimated from fewer logs.
        let d = run_seeds(&base, &base, 5000 + seed, false, Settings::default().seeds);
        let found: Vec<String> = d
            .channels
            .iter()
            .flat_map(|(ch, r)| r.effects.iter().map(move |e| format!("{ch}:{}", e.effect)))
            .collect();
        if !found.is_empty() {
            named.push(format!("seed {seed}: {found:?}"));
        }
    }
    eprintln!("clean logs with an effect named: {} of 20", named.len());
    assert!(
        named.is_empty(),
        "effects named on clean logs:\n{}",
        named.join("\n")
    );
}

/// "Cannot tell A from B": a temperature bias driven by a linear temperature ramp is a rate ramp of
/// slope coefficient x (degC/s) in every respect the log shows (Allan signature R^2 tau^2/2, Hou 4.56, and
/// the same least-squares slope), so diagnose must name one of the two and say it cannot tell it from the
/// other, and still close the gap.
#[test]
fn temperature_ramp_cannot_be_told_from_rate_ramp() {
    let base = base_model(true);
    let mut model = base.clone();
    // 20 degC over the 655 s log; gyro y coefficient 5e-5 rad/s/degC (0.003 deg/s/degC): the bias moves by
    // 1e-3 rad/s, a ramp R = 1.5e-6 rad/s^2 crossing the base model near 15 s.
    model.temperature = TemperatureProfile::Ramp {
        start_c: 15.0,
        rate_c_per_s: 20.0 / 655.36,
        end_c: None,
    };
    model.temperature_reference_c = 25.0;
    set_term(
        &mut model,
        Channel::Gy,
        noise::TemperatureBias::new(5e-5).unwrap().into(),
    );
    let d = run(&model, &base, 31, true);
    let gy = &d.channels[&noise::Channel::Gy];
    assert_eq!(gy.effects.len(), 1, "{:?}", gy.effects);
    let e = &gy.effects[0];
    let (named, other) = match e.effect.name() {
        "temperature_bias" => ("temperature_bias", "rate_ramp"),
        "rate_ramp" => ("rate_ramp", "temperature_bias"),
        x => panic!("named {x}, expected temperature_bias or rate_ramp"),
    };
    assert!(
        e.cannot_tell_from.iter().any(|c| c.name() == other),
        "{named} named without saying it cannot be told from {other}: {:?}",
        e.cannot_tell_from
    );
    assert!(
        gap_closed(gy.gap_initial, gy.gap_final),
        "gap {} -> {}",
        gy.gap_initial,
        gy.gap_final
    );
    for (ch, r) in &d.channels {
        if *ch != Channel::Gy {
            assert!(r.effects.is_empty(), "{ch}: {:?}", r.effects);
        }
    }
}
