//! Tones from the spectrum (docs/real-effects.md, "Measured on the real logs"; issue 23 item 4):
//! a tone the runs' spectrum shows is named as a sinusoid at the frequency the spectrum measures,
//! to the runs' resolution, its amplitude fitted; on any channel, between the bins of the
//! spectrum the lines are sought in.

mod common;

use common::{base_model, GeneratedLog};
use diagnose::diagnose_runs;
use noise::{Channel, Effect, RateRandomWalk, Sinusoid};

/// Samples per run (1311 s at 100 Hz): the lines are measured on segments of 2^17 samples.
const SAMPLES: usize = 1 << 17;

/// Three runs of white noise, flicker and a slow rate random walk (accelerometers K = 1e-5
/// m/s^2/sqrt(s), gyros 1e-6 rad/s/sqrt(s): crossing the flicker plateau near 300 s), the model
/// diagnosed with, and a tone the model lacks on ax at 0.5737 Hz and on gz at 3.2104 Hz: each
/// halfway between the bins of the 4096-sample spectrum the lines are sought in (resolution
/// 0.0244 Hz), where that spectrum's own interpolation is least certain; amplitudes 5e-3 m/s^2 and
/// 1.6e-3 rad/s (the first Allan lobe 2.9 and 3.9 times the base's deviation there), a random
/// phase in each run. Each tone is named on its channel only, not a stand-in, its frequency within
/// a tenth of the runs' resolution (100 Hz / 2^17 = 0.00076 Hz; the interpolation's bias is at
/// most 0.016 of it, `spectrum.rs` tests) and its amplitude within 25 % or inside its 95 %
/// interval.
#[test]
fn tones_between_bins_are_named_at_the_spectrum_frequency() {
    let coarse = 1.0 / (4096.0 * common::DT_S);
    let tones = [
        (Channel::Ax, 23.5 * coarse, 5e-3),
        (Channel::Gz, 131.5 * coarse, 1.6e-3),
    ];
    let mut base = base_model(true);
    for c in Channel::ALL {
        let k = if c.is_gyro() { 1e-6 } else { 1e-5 };
        base.axis_mut(c.sensor(), c.axis())
            .set_term(RateRandomWalk::new(k).unwrap());
    }
    let mut model = base.clone();
    for &(c, f, a) in &tones {
        model
            .axis_mut(c.sensor(), c.axis())
            .set_term(Sinusoid::new(a, f, None).unwrap());
    }
    let logs: Vec<GeneratedLog> = (0..3)
        .map(|r| GeneratedLog::new(&model, SAMPLES, 7300 + r, false))
        .collect();
    let d = diagnose_runs(
        &common::run_inputs(&logs),
        &base,
        &common::pooled_settings(false),
        &(),
    )
    .expect("diagnose runs");
    let resolution = 1.0 / (SAMPLES as f64 * common::DT_S);
    for c in Channel::ALL {
        let report = &d.channels[&c];
        let sinusoid = report
            .effects
            .iter()
            .find(|e| e.effect == Effect::Sinusoidal);
        let Some(&(_, f_true, a_true)) = tones.iter().find(|t| t.0 == c) else {
            assert!(sinusoid.is_none(), "{}: a sinusoid named", c.name());
            continue;
        };
        let e = sinusoid.unwrap_or_else(|| {
            panic!(
                "{}: no sinusoid named ({:?}; candidates {:?})",
                c.name(),
                report.effects.iter().map(|e| e.effect).collect::<Vec<_>>(),
                report
                    .candidates
                    .iter()
                    .map(|r| (r.round, r.effect, r.delta_bic as i64))
                    .collect::<Vec<_>>()
            )
        });
        let (f, a) = (e.parameters["frequency_hz"], e.parameters["amplitude"]);
        let (lo, hi) = (e.parameters_lo["amplitude"], e.parameters_hi["amplitude"]);
        eprintln!(
            "{}: {f} Hz (truth {f_true}, {:+.4} of the resolution), amplitude {a:.3e} [{lo:.3e}, {hi:.3e}] (truth {a_true:.1e})",
            c.name(),
            (f - f_true) / resolution
        );
        assert!(!e.stand_in, "{}: a stand-in", c.name());
        assert!(
            (f - f_true).abs() < 0.1 * resolution,
            "{}: {f} Hz, truth {f_true}",
            c.name()
        );
        assert!(
            common::parameter_ok(a_true, a, lo, hi),
            "{}: amplitude {a} [{lo}, {hi}], truth {a_true}",
            c.name()
        );
    }
}
