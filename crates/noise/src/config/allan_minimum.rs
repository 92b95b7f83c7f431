//! The `allan_minimum` convention: the IEEE coefficient B solved (bisection) so that the closed-form
//! Allan deviation of the whole axis model has the stated minimum over the flicker plateau.

use crate::closed_form as cf;
use crate::model::*;
use crate::terms::bias_instability::{BiasInstability, Flicker};

/// Log-spaced averaging times inside the flicker band's plateau, [30 tau_min, tau_max / 30], where the
/// component sum is within 1.3 % of 0.664 B (`Flicker::per_decade`); nearer the band edges it falls off
/// (0.55 B at 2 tau_min), which would make a curve without a rising term take its minimum there.
fn plateau_taus(f: &Flicker) -> Vec<f64> {
    let lo = 30.0 * f.tau_min_s;
    let hi = (f.tau_max_s / 30.0).max(lo);
    let n = ((hi / lo).log10() * 40.0).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| lo * (hi / lo).powf(i as f64 / n as f64))
        .collect()
}

/// Minimum over the plateau taus of the total closed-form Allan deviation.
pub(super) fn model_adev_minimum(axis: &AxisModel, band: &Flicker) -> (f64, f64) {
    plateau_taus(band)
        .into_iter()
        .map(|tau| (axis.allan_variance(tau).sqrt(), tau))
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a })
}

/// B such that the axis' total Allan-deviation minimum equals `target`. Err(floor) when the other
/// terms alone already exceed it. The minimum grows monotonically with B, so bisection converges.
pub(super) fn solve_b_for_minimum(
    target: f64,
    others: &AxisModel,
    flicker: &dyn Fn(f64) -> Flicker,
) -> Result<f64, f64> {
    let min_with = |b: f64| {
        let mut axis = others.clone();
        axis.set_term(BiasInstability::Flicker(flicker(b)));
        model_adev_minimum(&axis, &flicker(b)).0
    };
    let floor = min_with(0.0);
    if floor >= target {
        return Err(floor);
    }
    let (mut lo, mut hi) = (0.0, 2.0 * target / cf::FLICKER_PLATEAU_PER_B);
    while min_with(hi) < target {
        hi *= 2.0;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if min_with(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}
