//! A sinusoidal error (docs/model.md §2: Hou 4.64 for its Allan variance).

use super::term::{ErrorTerm, GenContext, Generate, RawClock, Stage, TermKind, WriteContext};
use crate::closed_form as cf;
use crate::config::error::ConfigError;
use crate::config::read::{ReadContext, Text};
use crate::filter::FilteredAllan;
use crate::law_source::{LawSource, LawSourceContext};
use crate::model_error::{check, ModelError};
use crate::units::{Quantity, Signal};
use crate::ImuRng;
use rand::Rng;

/// Sinusoidal error `amplitude · sin(2 pi frequency_hz t + phase)`. Without a phase, one is drawn
/// uniformly per run (the phase average is what the Allan closed form describes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sinusoid {
    amplitude: f64,
    frequency_hz: f64,
    phase_rad: Option<f64>,
}

impl Sinusoid {
    /// Checks the amplitude (finite, >= 0), the frequency (finite, > 0) and the phase (finite).
    pub fn new(
        amplitude: f64,
        frequency_hz: f64,
        phase_rad: Option<f64>,
    ) -> Result<Sinusoid, ModelError> {
        check("sinusoid amplitude", amplitude, false)?;
        check("sinusoid frequency", frequency_hz, true)?;
        if let Some(p) = phase_rad {
            if !p.is_finite() {
                return Err(ModelError {
                    what: "sinusoid phase",
                    expected: "a finite angle",
                    found: p,
                });
            }
        }
        Ok(Sinusoid {
            amplitude,
            frequency_hz,
            phase_rad,
        })
    }

    /// Amplitude (signal units).
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }

    /// Frequency, Hz.
    pub fn frequency_hz(&self) -> f64 {
        self.frequency_hz
    }

    /// The fixed phase, rad; None: drawn per run.
    pub fn phase_rad(&self) -> Option<f64> {
        self.phase_rad
    }
}

/// `sinusoidal = { amplitude, frequency, phase? }` as written.
#[derive(serde::Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawSinusoid {
    amplitude: Text,
    frequency: Text,
    phase: Option<Text>,
}

impl ErrorTerm for Sinusoid {
    /// Point-sampled at the run's interval.
    fn law_sources(&self, cx: &LawSourceContext) -> Vec<LawSource> {
        vec![LawSource::Sinusoid {
            amplitude: self.amplitude,
            freq_hz: self.frequency_hz,
            phase: self.phase_rad,
            sample_interval_s: cx.dt_s,
        }]
    }

    /// The amplitude, named `amplitude` (docs/cli.md).
    fn level(&self) -> Option<(&'static str, f64)> {
        Some(("amplitude", self.amplitude))
    }

    /// The frequency, named `frequency_hz` (a fixed phase moves no Allan variance, which is the
    /// phase average: not a shape).
    fn shape(&self) -> Vec<(&'static str, f64)> {
        vec![("frequency_hz", self.frequency_hz)]
    }

    /// Phase averaged (Hou 4.64).
    fn allan_variance(&self, tau_s: f64) -> Option<f64> {
        Some(cf::sinusoid_avar(self.amplitude, self.frequency_hz, tau_s))
    }

    fn allan_variance_sampled(&self, tau_s: f64, dt_s: f64) -> Option<f64> {
        Some(cf::sinusoid_avar_sampled(
            self.amplitude,
            self.frequency_hz,
            tau_s,
            dt_s,
        ))
    }

    fn allan_variance_filtered(&self, tau_s: f64, _dt_s: f64, fa: &FilteredAllan) -> Option<f64> {
        Some(fa.sinusoid(self.amplitude, self.frequency_hz, tau_s))
    }

    fn config_value(&self, cx: &WriteContext) -> String {
        let phase = self
            .phase_rad
            .map(|p| format!(", phase = {}", cx.quoted(p, Quantity::Angle)))
            .unwrap_or_default();
        format!(
            "{{ amplitude = {}, frequency = {}{phase} }}",
            cx.quoted(self.amplitude, Quantity::Signal(cx.sig)),
            cx.quoted(self.frequency_hz, Quantity::Frequency)
        )
    }
}

impl TermKind for Sinusoid {
    const STOCHASTIC: bool = false;
    const LONG_TERM: bool = false;
    const FREE_PARAMETERS: usize = 2;
    const SHOWS_IN_STATIC_LOG: bool = true;
    type Raw = RawSinusoid;

    /// The frequency and phase kept.
    fn with_level(&self, level: f64) -> Result<Sinusoid, ModelError> {
        Sinusoid::new(level, self.frequency_hz, self.phase_rad)
    }

    fn from_raw(raw: &RawSinusoid, cx: &ReadContext) -> Result<Sinusoid, ConfigError> {
        let amplitude =
            cx.sub_value("amplitude", &raw.amplitude, Quantity::Signal(cx.sig), true)?;
        let frequency_hz = cx.sub_positive("frequency", &raw.frequency, Quantity::Frequency)?;
        let phase_rad = raw
            .phase
            .as_ref()
            .map(|p| cx.sub_value("phase", p, Quantity::Angle, false))
            .transpose()?;
        Sinusoid::new(amplitude, frequency_hz, phase_rad).map_err(|e| cx.refused(&cx.key, e))
    }

    /// None: a written config has never taken its units from this table.
    fn note_units(
        _value: &toml::Value,
        _sig: Signal,
        _note: &mut dyn FnMut(Quantity, &toml::Value),
    ) {
    }

    type Generator = SinusoidGenerator;

    /// Without a phase, this run's is the term's one draw (uniform on [0, 2 pi)). Behind an output
    /// filter the sinusoid is added after it, at the output rate: a linear filter turns
    /// A sin(w t + p) into A |H| sin(w t + p + arg H), H = sum_j h_j e^{-i w j dt_i} (exact once the
    /// pre-roll has filled the filter), so it is not generated at the internal rate.
    fn generator(&self, cx: &GenContext, rng: &dyn Fn() -> ImuRng) -> SinusoidGenerator {
        let phase = self
            .phase_rad
            .unwrap_or_else(|| rng().gen_range(0.0..std::f64::consts::TAU));
        let (amplitude, omega) = (self.amplitude, std::f64::consts::TAU * self.frequency_hz);
        match cx.filter_response {
            None => SinusoidGenerator {
                amplitude,
                omega,
                phase,
                after_filter: false,
            },
            Some(response) => {
                let (mut re, mut im) = (0.0f64, 0.0f64);
                for (j, h) in response.iter().enumerate() {
                    let arg = omega * j as f64 * cx.dt_raw_s;
                    re += h * arg.cos();
                    im -= h * arg.sin();
                }
                SinusoidGenerator {
                    amplitude: amplitude * re.hypot(im),
                    omega,
                    phase: phase + im.atan2(re),
                    after_filter: true,
                }
            }
        }
    }
}

/// amplitude sin(omega t + phase), in the raw samples or (behind a filter, with the filter's gain
/// and phase) in the output samples.
#[derive(Clone, Copy, Debug)]
pub struct SinusoidGenerator {
    amplitude: f64,
    /// rad/s.
    omega: f64,
    phase: f64,
    after_filter: bool,
}

impl Generate for SinusoidGenerator {
    fn stage(&self) -> Stage {
        if self.after_filter {
            Stage::Output
        } else {
            Stage::Raw
        }
    }

    #[inline]
    fn add_raw(&mut self, clock: RawClock, out: &mut [f64], _scratch: &mut Vec<f64>) {
        self.add(clock.k0, clock.dt_s, clock.offset_s, out);
    }

    fn output(&mut self, k0: u64, dt_s: f64, out: &mut [f64]) {
        self.add(k0, dt_s, 0.0, out);
    }
}

/// Samples between exact evaluations of the sinusoid (absolute sample indices that are multiples
/// of it); in between it is rotated one sample at a time.
const ANCHOR: u64 = 64;

impl SinusoidGenerator {
    /// Add amplitude sin(omega ((k0 + i) dt - offset) + phase) to `out[i]`. The value at absolute
    /// sample k is computed exactly (sin, cos) at the anchor k - k mod 64 and rotated from there
    /// by the angle-addition formulas, sin(x + d) = sin x cos d + cos x sin d, cos(x + d) = cos x
    /// cos d - sin x sin d, with d = omega dt: at most 63 rotations, each adding about one
    /// rounding (relative error below 1e-14), and the value is a function of k alone, so the same
    /// for any split into blocks. One sin/cos per 64 samples instead of a sin per sample.
    ///
    /// Whole windows of 64 samples go [`WINDOWS`] at a time ([`Self::add_windows`]): a window's
    /// rotations are a chain of dependent multiply-adds, and the windows' chains are independent,
    /// so several side by side take about the time of one (the same operations on each value:
    /// the same bits as one window at a time, tested below).
    fn add(&self, k0: u64, dt_s: f64, offset_s: f64, out: &mut [f64]) {
        let rot = Rotation::new(self, dt_s, offset_s);
        // The first, partial window: up to the next anchor.
        let head = ((ANCHOR - k0 % ANCHOR) % ANCHOR).min(out.len() as u64) as usize;
        let (first, rest) = out.split_at_mut(head);
        rot.window(self.amplitude, k0, first);
        let w = ANCHOR as usize;
        let mut groups = rest.chunks_exact_mut(WINDOWS * w);
        let mut k = k0 + head as u64;
        for group in groups.by_ref() {
            rot.windows(self.amplitude, k, group);
            k += (WINDOWS * w) as u64;
        }
        for window in groups.into_remainder().chunks_mut(w) {
            rot.window(self.amplitude, k, window);
            k += w as u64;
        }
    }

    /// [`Self::add`] one window at a time, as before the windows went side by side: the
    /// reference the fast path is tested against.
    #[cfg(test)]
    fn add_one_window_at_a_time(&self, k0: u64, dt_s: f64, offset_s: f64, out: &mut [f64]) {
        let rot = Rotation::new(self, dt_s, offset_s);
        let mut i = 0usize;
        while i < out.len() {
            let k = k0 + i as u64;
            let end = ((k - k % ANCHOR + ANCHOR - k0) as usize).min(out.len());
            rot.window(self.amplitude, k, &mut out[i..end]);
            i = end;
        }
    }
}

/// Windows of [`ANCHOR`] samples rotated side by side by [`SinusoidGenerator::add`]: eight keep
/// their sines and cosines in sixteen 2-wide (SSE2) registers' worth, and make one output block of
/// `process.rs` (512 samples).
const WINDOWS: usize = 8;

/// The exact values and the one-sample rotation of a sinusoid at a raw clock.
struct Rotation {
    omega: f64,
    phase: f64,
    dt_s: f64,
    offset_s: f64,
    /// sin and cos of omega dt.
    sd: f64,
    cd: f64,
}

impl Rotation {
    fn new(g: &SinusoidGenerator, dt_s: f64, offset_s: f64) -> Rotation {
        let (sd, cd) = (g.omega * dt_s).sin_cos();
        Rotation {
            omega: g.omega,
            phase: g.phase,
            dt_s,
            offset_s,
            sd,
            cd,
        }
    }

    /// (sin, cos) of the angle at absolute sample k, exactly.
    #[inline(always)]
    fn exact(&self, k: u64) -> (f64, f64) {
        (self.omega * (k as f64 * self.dt_s - self.offset_s) + self.phase).sin_cos()
    }

    /// (sin, cos) one sample later, by the angle-addition formulas.
    #[inline(always)]
    fn rotate(&self, (s, c): (f64, f64)) -> (f64, f64) {
        (s * self.cd + c * self.sd, c * self.cd - s * self.sd)
    }

    /// Add `a` sin to `out`, samples k .. k + out.len(), all in one window (k's anchor's).
    #[inline(always)]
    fn window(&self, a: f64, k: u64, out: &mut [f64]) {
        let anchor = k - k % ANCHOR;
        let mut sc = self.exact(anchor);
        for _ in anchor..k {
            sc = self.rotate(sc);
        }
        for v in out {
            *v += a * sc.0;
            sc = self.rotate(sc);
        }
    }

    /// [`Self::window`] for the [`WINDOWS`] whole windows of `out` (k a multiple of [`ANCHOR`]),
    /// their samples of the same offset in the window together: the same operations on each value.
    #[inline(always)]
    fn windows(&self, a: f64, k: u64, out: &mut [f64]) {
        let w = ANCHOR as usize;
        let mut s = [0.0; WINDOWS];
        let mut c = [0.0; WINDOWS];
        for j in 0..WINDOWS {
            (s[j], c[j]) = self.exact(k + (j * w) as u64);
        }
        for i in 0..w {
            for j in 0..WINDOWS {
                out[j * w + i] += a * s[j];
                (s[j], c[j]) = self.rotate((s[j], c[j]));
            }
        }
    }
}

/// A valid term of the effect, for the registry's tests (`terms::samples`).
#[cfg(test)]
pub(crate) fn sample() -> Sinusoid {
    Sinusoid::new(8e-3, 9.0, Some(0.1)).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_from_anchors_matches_sin_in_any_blocks() {
        let g = SinusoidGenerator {
            amplitude: 2.5,
            omega: std::f64::consts::TAU * 0.564,
            phase: 1.1,
            after_filter: false,
        };
        let (dt, offset, n) = (0.0025, 0.01, 100_000usize);
        let mut whole = vec![0.0; n];
        g.add(7, dt, offset, &mut whole);
        for (i, v) in whole.iter().enumerate() {
            let angle = g.omega * ((7 + i as u64) as f64 * dt - offset) + g.phase;
            let exact = 2.5 * angle.sin();
            // 63 rotations at most, each about one rounding of a unit value, and the angle itself
            // (in both) rounded to about |angle| eps: a few eps times (64 + |angle|).
            let bound = 2.5 * 4.0 * f64::EPSILON * (64.0 + angle.abs());
            assert!((v - exact).abs() < bound, "sample {i}: {v} vs {exact}");
        }
        // The same bits in uneven blocks.
        let mut parts = vec![0.0; n];
        let mut start = 0;
        for len in [1usize, 63, 64, 65, 200, 3].iter().cycle() {
            if start >= n {
                break;
            }
            let end = (start + len).min(n);
            g.add(7 + start as u64, dt, offset, &mut parts[start..end]);
            start = end;
        }
        assert!(whole
            .iter()
            .zip(&parts)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    /// The windows side by side give the bits of one window at a time, from any start, in blocks
    /// that hold several groups of windows and partial ones at both ends.
    #[test]
    fn windows_side_by_side_equal_one_window_at_a_time() {
        let g = SinusoidGenerator {
            amplitude: 8.6e-3,
            omega: std::f64::consts::TAU * 0.5641,
            phase: -2.3,
            after_filter: false,
        };
        for (k0, n) in [
            (0u64, 512usize),
            (7, 5000),
            (64, 1536),
            (999_937, 4096),
            (3, 40),
        ] {
            let base: Vec<f64> = (0..n).map(|i| (i as f64).sqrt() - 3.0).collect();
            let (mut fast, mut simple) = (base.clone(), base);
            g.add(k0, 0.01, 0.0025, &mut fast);
            g.add_one_window_at_a_time(k0, 0.01, 0.0025, &mut simple);
            assert!(
                fast.iter()
                    .zip(&simple)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "k0 {k0}, {n} samples"
            );
        }
    }
}
