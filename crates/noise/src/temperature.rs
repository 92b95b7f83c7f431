//! The temperature profile of a run (degC over time), driving `temperature_bias` and written as a
//! generated log's `temp` column.

/// Temperature over time (degC), driving `temperature_bias` and written as the log's `temp` column.
#[derive(Clone, Debug, PartialEq)]
pub enum TemperatureProfile {
    Constant {
        temp_c: f64,
    },
    /// `start_c + rate_c_per_s · t`, held at `end_c` once reached (if given).
    Ramp {
        start_c: f64,
        rate_c_per_s: f64,
        end_c: Option<f64>,
    },
    /// Exponential warm-up `end_c + (start_c - end_c) e^{-t/time_constant_s}`.
    Warmup {
        start_c: f64,
        end_c: f64,
        time_constant_s: f64,
    },
    /// `mean_c + amplitude_c sin(2 pi t / period_s)` (temperature cycling).
    Sinusoid {
        mean_c: f64,
        amplitude_c: f64,
        period_s: f64,
    },
    /// `before_c` until `at_s`, `after_c` from then on.
    Step {
        before_c: f64,
        after_c: f64,
        at_s: f64,
    },
}

impl Default for TemperatureProfile {
    fn default() -> Self {
        TemperatureProfile::Constant { temp_c: 25.0 }
    }
}

impl TemperatureProfile {
    /// Temperature at time `t_s`, degC.
    pub fn at(&self, t_s: f64) -> f64 {
        match *self {
            TemperatureProfile::Constant { temp_c } => temp_c,
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            } => {
                let t = start_c + rate_c_per_s * t_s;
                match end_c {
                    Some(e) if rate_c_per_s >= 0.0 => t.min(e),
                    Some(e) => t.max(e),
                    None => t,
                }
            }
            TemperatureProfile::Warmup {
                start_c,
                end_c,
                time_constant_s,
            } => end_c + (start_c - end_c) * (-t_s / time_constant_s).exp(),
            TemperatureProfile::Sinusoid {
                mean_c,
                amplitude_c,
                period_s,
            } => mean_c + amplitude_c * (std::f64::consts::TAU * t_s / period_s).sin(),
            TemperatureProfile::Step {
                before_c,
                after_c,
                at_s,
            } => {
                if t_s < at_s {
                    before_c
                } else {
                    after_c
                }
            }
        }
    }

    /// The k-fold integral (k = 1..=3) from 0 to `t_s` of the excursion T(s) - `reference_c`, in
    /// degC s^k: what a temperature-bias coefficient turns into angle or velocity (k = 1), position
    /// (k = 2) or, through tilt, position (k = 3, times g). Exact, by Cauchy's formula
    /// I_k = int_0^t (t-s)^{k-1}/(k-1)! f(s) ds applied to each profile:
    /// a constant c gives c t^k/k!; a ramp r s held from t_e on gives r (t^{k+1} - (t - t_e)_+^{k+1})/(k+1)!;
    /// e^{-s/tau} gives tau^k sum_{n>=k} (-1)^{n-k} x^n/n! (x = t/tau); sin(w s) gives
    /// (1 - cos wt)/w, t/w - sin(wt)/w^2, t^2/(2w) - (1 - cos wt)/w^3. (Derived; not in docs/model.md.)
    /// `None` for k outside 1..=3.
    pub fn excursion_integral(&self, reference_c: f64, t_s: f64, k: i32) -> Option<f64> {
        if !(1..=3).contains(&k) {
            return None;
        }
        let fact = |n: i32| (1..=n).map(f64::from).product::<f64>();
        let constant = |c: f64| c * t_s.powi(k) / fact(k);
        Some(match *self {
            TemperatureProfile::Constant { temp_c } => constant(temp_c - reference_c),
            TemperatureProfile::Ramp {
                start_c,
                rate_c_per_s,
                end_c,
            } => {
                let held_after = match end_c {
                    Some(e) if rate_c_per_s != 0.0 => ((e - start_c) / rate_c_per_s).max(0.0),
                    _ => f64::INFINITY,
                };
                let past = (t_s - held_after).max(0.0);
                constant(start_c - reference_c)
                    + rate_c_per_s * (t_s.powi(k + 1) - past.powi(k + 1)) / fact(k + 1)
            }
            TemperatureProfile::Warmup {
                start_c,
                end_c,
                time_constant_s,
            } => {
                let x = t_s / time_constant_s;
                // tau^k [sum_{j<k} (-1)^{k-1-j} x^j/j! + (-1)^k e^{-x}], summed as its series for small x.
                let e = if x < 1.0 {
                    (k..k + 30)
                        .map(|n| {
                            let sign = if (n - k) % 2 == 0 { 1.0 } else { -1.0 };
                            sign * x.powi(n) / fact(n)
                        })
                        .sum::<f64>()
                } else {
                    let sign = |p: i32| if p % 2 == 0 { 1.0 } else { -1.0 };
                    (0..k)
                        .map(|j| sign(k - 1 - j) * x.powi(j) / fact(j))
                        .sum::<f64>()
                        + sign(k) * (-x).exp()
                };
                constant(end_c - reference_c) + (start_c - end_c) * time_constant_s.powi(k) * e
            }
            TemperatureProfile::Sinusoid {
                mean_c,
                amplitude_c,
                period_s,
            } => {
                let w = std::f64::consts::TAU / period_s;
                let one_minus_cos = 2.0 * (0.5 * w * t_s).sin().powi(2);
                let sine = match k {
                    1 => one_minus_cos / w,
                    2 => t_s / w - (w * t_s).sin() / (w * w),
                    _ => t_s * t_s / (2.0 * w) - one_minus_cos / w.powi(3),
                };
                constant(mean_c - reference_c) + amplitude_c * sine
            }
            // (after - before) times the k-fold integral of the unit step at t_e: (t - t_e)_+^k / k!.
            TemperatureProfile::Step {
                before_c,
                after_c,
                at_s,
            } => {
                constant(before_c - reference_c)
                    + (after_c - before_c) * (t_s - at_s.max(0.0)).max(0.0).powi(k) / fact(k)
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temperature_excursion_integrals_match_numerical_integration() {
        // Rectangle-rule integrals of the profile on a 1e-4 s grid: agreement to 1e-3 relative (the
        // rule's O(dt/t) error) for each profile, k = 1..3, before, at and after the ramp's hold.
        let profiles = [
            TemperatureProfile::Constant { temp_c: 31.0 },
            TemperatureProfile::Ramp {
                start_c: 20.0,
                rate_c_per_s: 2.0,
                end_c: Some(30.0),
            },
            TemperatureProfile::Ramp {
                start_c: 30.0,
                rate_c_per_s: -0.5,
                end_c: None,
            },
            TemperatureProfile::Warmup {
                start_c: 10.0,
                end_c: 40.0,
                time_constant_s: 3.0,
            },
            TemperatureProfile::Sinusoid {
                mean_c: 26.0,
                amplitude_c: 4.0,
                period_s: 2.5,
            },
            TemperatureProfile::Step {
                before_c: 22.0,
                after_c: 30.0,
                at_s: 5.0,
            },
        ];
        let dt = 1e-4;
        for profile in &profiles {
            let (mut i1, mut i2, mut i3) = (0.0, 0.0, 0.0);
            let n = 120_000; // 12 s
            for j in 0..n {
                let t = (j as f64 + 0.5) * dt;
                i1 += (profile.at(t) - 25.0) * dt;
                i2 += i1 * dt;
                i3 += i2 * dt;
                if (j + 1) % 20_000 == 0 {
                    let t_end = (j + 1) as f64 * dt;
                    for (k, num) in [(1, i1), (2, i2), (3, i3)] {
                        let exact = profile.excursion_integral(25.0, t_end, k).unwrap();
                        assert!(
                            (exact - num).abs() <= 1e-3 * exact.abs().max(1e-3 * t_end.powi(k)),
                            "{profile:?} t {t_end} k {k}: exact {exact} vs numerical {num}"
                        );
                    }
                }
            }
        }
    }
}
