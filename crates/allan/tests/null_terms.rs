//! The resolved-term rule on logs of its null model (issue 24): on white rate noise of known N,
//! no quantisation, bias instability, rate random walk or ramp term is claimed beyond the
//! family-wise rate the thresholds are drawn for (crate::null), and the white-noise reading
//! holds its interval.
//!
//! Generator: tests/common (the noise crate's white rate noise).
//!
//! Tolerances: the CI test draws its thresholds for a family of 4 claims (Q, B, K, R) per log
//! over all its logs at 1 %, so it fails falsely with probability at most 1 % (Bonferroni; the
//! seeds are fixed, so a run is reproducible). The ignored test measures the false-claim rate
//! at the command's level (1 % per log of 6 channels x 5 terms) on 200 seeds at 100 and 200 Hz
//! and fails only beyond 6 false claims in its 400 logs: at the stated per-log rate of at most
//! 4/30 % per channel, 0.53 are expected, and P(Poisson(0.53) > 6) < 1e-5.

mod common;
use allan::null::ClaimLevel;
use allan::{Estimator, Options, TauGrid};
use common::{n_true, white_analysis, white_log};

/// The false claims (Q, B, K, R resolved) on `seeds` 10-minute white-noise logs at `rate_hz`,
/// and the ARW intervals that miss the truth.
fn false_claims(rate_hz: f64, seeds: std::ops::Range<u64>, claims: ClaimLevel) -> (usize, usize) {
    let opts = Options {
        confidence: 0.999,
        claims,
        ..Options::default()
    };
    let (mut claimed, mut missed) = (0, 0);
    for seed in seeds {
        let a = white_analysis(rate_hz, 600.0, seed, &opts);
        let (terms, sheet) = (a.terms.unwrap(), a.sheet.unwrap());
        for j in [0, 2, 3, 4] {
            if terms[j].resolved {
                claimed += 1;
                eprintln!("{rate_hz} Hz seed {seed}: term {j} claimed: {:?}", terms[j]);
            }
        }
        assert!(
            sheet.bi_min.value.is_none() && sheet.rrw.value.is_none() && sheet.q.value.is_none()
        );
        let arw = &sheet.arw;
        if !(arw.value.is_some() && arw.lo <= n_true() && n_true() <= arw.hi) {
            missed += 1;
        }
    }
    (claimed, missed)
}

#[test]
fn ten_minute_white_logs_claim_no_term() {
    let seeds = 10;
    let claims = ClaimLevel {
        rate: 0.01,
        family: 4 * 2 * seeds as usize,
        ..ClaimLevel::default()
    };
    for rate in [100.0, 200.0] {
        let (claimed, _) = false_claims(rate, 100..100 + seeds, claims);
        assert_eq!(claimed, 0, "{rate} Hz: {claimed} false claims");
    }
}

#[test]
#[ignore = "400 ten-minute logs: ~15 s; run with --ignored --nocapture"]
fn false_claim_rate_over_200_seeds() {
    let mut total = 0;
    for rate in [100.0, 200.0] {
        let (claimed, missed) = false_claims(rate, 1000..1200, ClaimLevel::default());
        eprintln!(
            "{rate} Hz: {claimed} false claims (Q, B, K, R) in 200 logs; ARW interval (99.9 %) missed N in {missed}"
        );
        assert!(missed <= 3, "{rate} Hz: ARW missed {missed} of 200");
        total += claimed;
    }
    assert!(total <= 6, "{total} false claims in 400 logs");
}

/// The noise identification on white rate noise (alpha = 0): a point reads as a PM type
/// (alpha > 0, whose Greenhall EDF is larger than white FM's) only where its lag-1 ACF departs
/// from the shorter tau's type by more than 2.576 standard errors beyond the rounding band: at
/// most 0.5 % of points (one side of the two-sided 1 %), so at most 0.005 x 700 = 3.5 of the
/// ~700 points of 50 logs on average; the test fails beyond 12 (P(Poisson(3.5) > 12) < 1e-4).
/// Before the rule, the longest taus (30-120 blocks) read alpha = 1 on about a quarter of logs.
#[test]
fn white_noise_is_not_read_as_phase_noise() {
    let (dt, len) = (0.01, 60_000);
    let (mut points, mut pm, mut other) = (0, 0, 0);
    for seed in 0..50u64 {
        let data = white_log(dt, len, 7000 + seed);
        let s = allan::Series::from_rate(data, dt);
        let pts = s.deviation(
            Estimator::Overlapping,
            &TauGrid::Octave,
            &Options::default(),
        );
        points += pts.len();
        pm += pts.iter().filter(|p| p.alpha > 0).count();
        other += pts.iter().filter(|p| p.alpha < 0).count();
    }
    eprintln!("white noise: {pm} of {points} points read alpha > 0, {other} alpha < 0");
    assert!(pm <= 12, "{pm} of {points} points read as phase noise");
}
