//! Run-to-run variation of term levels (docs/model.md §2.3): an axis may state, per term with a
//! level, the spread s of the natural log of that level between power-ons. The listed terms of
//! one axis and one group move together: per run and axis two independent standard normal draws,
//! from a stream of their own, one for the long-term terms (`Effect::is_long_term`: the slow
//! wander) and one for the others (the short-term levels: white noise, quantisation, ...), scale
//! each listed level L to `L exp(s z - s^2)` with its group's z.
//!
//! Convention: the level written in the model is the root-mean-square over power-ons,
//! E[(L exp(s z - s^2))^2] = L^2 exp(-2 s^2) E[exp(2 s z)] = L^2 (the moment generating function
//! of the standard normal, E[exp(t z)] = exp(t^2 / 2)). Allan variances and the mean-square growth
//! laws are quadratic in the levels, so their mean over power-ons is the model's without spread;
//! only the spread of one run about them grows.

use crate::discrete::normal;
use crate::{run_to_run_rng, ImuRng};

/// The largest spread a model may state (sd of ln level; exp(2) = 7.4: one run's level a factor
/// 7.4 from the median per standard deviation, beyond which a "level" says little).
pub const MAX_SPREAD: f64 = 2.0;

/// The factor a run's draw `z` puts on a level of spread `spread`: `exp(s z - s^2)`, exactly 1
/// for a spread of 0.
pub fn level_factor(spread: f64, z: f64) -> f64 {
    if spread == 0.0 {
        return 1.0;
    }
    (spread * z - spread * spread).exp()
}

/// The standard normal draw of the long-term group of run `run`, channel index `channel` (0..6,
/// `Channel::index`) of `seed`: the first normal of the channel's run-to-run stream, which no
/// other draw uses.
pub fn run_draw(seed: u64, run: u64, channel: usize) -> f64 {
    run_draws(seed, run, channel)[LONG]
}

/// Index of the long-term group's draw in [`run_draws`].
pub const LONG: usize = 0;
/// Index of the short-term group's draw in [`run_draws`].
pub const SHORT: usize = 1;

/// Both draws of run `run`, channel index `channel` of `seed`: `[long, short]`, the first and the
/// second normal of the channel's run-to-run stream (the long-term draw is the one a model of
/// long-term spreads alone has always used, so its runs keep their bits).
pub fn run_draws(seed: u64, run: u64, channel: usize) -> [f64; 2] {
    let mut rng: ImuRng = run_to_run_rng(seed, run, channel as u64);
    let long = normal(&mut rng);
    [long, normal(&mut rng)]
}

/// A chi-square draw of `df` (whole) degrees of freedom: the sum of `df` squared standard normals of
/// `rng` (its definition, exact).
pub fn chi_square<R: rand::Rng + ?Sized>(rng: &mut R, df: usize) -> f64 {
    (0..df).map(|_| normal(rng).powi(2)).sum()
}

/// The group of a term's spread: [`LONG`] for a long-term term, [`SHORT`] otherwise.
pub fn group_of(effect: crate::Effect) -> usize {
    if effect.is_long_term() {
        LONG
    } else {
        SHORT
    }
}

/// Gauss-Hermite quadrature for the standard normal (probabilists' Hermite polynomials):
/// `n` nodes z_i and weights w_i with sum_i w_i f(z_i) = E f(z) exactly for polynomials of degree
/// up to 2n - 1. Golub & Welsch (1969), "Calculation of Gauss quadrature rules", Math. Comp. 23,
/// 221-230: the nodes are the eigenvalues of the symmetric Jacobi matrix of the recurrence
/// He_{k+1} = z He_k - k He_{k-1} (zero diagonal, off-diagonal sqrt(k)), the weights the squared
/// first components of the unit eigenvectors (the measure's total mass is 1). Sorted by node.
pub fn gauss_hermite_normal(n: usize) -> Vec<(f64, f64)> {
    assert!(n >= 1, "at least one node");
    let mut j = nalgebra::DMatrix::<f64>::zeros(n, n);
    for k in 1..n {
        let b = (k as f64).sqrt();
        j[(k - 1, k)] = b;
        j[(k, k - 1)] = b;
    }
    let eig = j.symmetric_eigen();
    let mut out: Vec<(f64, f64)> = (0..n)
        .map(|i| (eig.eigenvalues[i], eig.eigenvectors[(0, i)].powi(2)))
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Symmetric rule: average each node with its mirror (removes the eigen-solver's rounding).
    let sym: Vec<(f64, f64)> = (0..n)
        .map(|i| {
            let (a, b) = (out[i], out[n - 1 - i]);
            (0.5 * (a.0 - b.0), 0.5 * (a.1 + b.1))
        })
        .collect();
    let total: f64 = sym.iter().map(|p| p.1).sum();
    sym.into_iter().map(|(z, w)| (z, w / total)).collect()
}

/// The most models `SensorModel::run_to_run_quadrature` returns (its product rule over the axes
/// with a spread).
pub const QUADRATURE_BUDGET: usize = 4096;

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates the normal's moments (E z^2k = (2k-1)!!) exactly to degree 2n - 1,
    /// and E exp(t z) = exp(t^2/2) (the convention's identity) to the accuracy stated in
    /// docs/model.md §2.3 for the node counts the laws use.
    #[test]
    fn gauss_hermite_moments_and_mgf() {
        for n in [1usize, 2, 5, 12, 20] {
            let r = gauss_hermite_normal(n);
            let moment = |k: i32| r.iter().map(|&(z, w)| w * z.powi(k)).sum::<f64>();
            let mut double_fact = 1.0;
            for k in 0..n as i32 {
                if k > 0 {
                    double_fact *= (2 * k - 1) as f64;
                }
                assert!(
                    (moment(2 * k) - double_fact).abs() <= 1e-9 * double_fact,
                    "n {n} k {k}"
                );
                assert!(moment(2 * k + 1).abs() <= 1e-9 * double_fact.max(1.0));
            }
        }
        // E[level^2] / L^2 = E exp(2 s z - 2 s^2) = 1 for the spreads of a model.
        for (n, s, tol) in [(20usize, 0.5, 1e-12), (20, 1.0, 1e-9), (12, 0.5, 1e-9)] {
            let r = gauss_hermite_normal(n);
            let ms: f64 = r.iter().map(|&(z, w)| w * level_factor(s, z).powi(2)).sum();
            assert!((ms - 1.0).abs() < tol, "n {n} s {s}: {ms}");
        }
    }

    #[test]
    fn zero_spread_is_exactly_one_and_draws_repeat() {
        assert_eq!(level_factor(0.0, 3.7).to_bits(), 1f64.to_bits());
        assert_eq!(run_draw(7, 3, 2).to_bits(), run_draw(7, 3, 2).to_bits());
        assert_ne!(run_draw(7, 3, 2), run_draw(7, 3, 1));
        assert_ne!(run_draw(7, 3, 2), run_draw(7, 4, 2));
        let [long, short] = run_draws(7, 3, 2);
        assert_eq!(long.to_bits(), run_draw(7, 3, 2).to_bits());
        assert_ne!(long, short);
    }

    /// The two groups' draws are independent standard normals: over 20 000 runs their
    /// correlation is within 5 standard errors (1/sqrt(n)) of 0 and the short draw's mean and
    /// variance are those of N(0, 1) (5 standard errors: mean 1/sqrt(n), variance sqrt(2/n)).
    #[test]
    fn the_two_groups_draw_independently() {
        let n = 20_000usize;
        let d: Vec<[f64; 2]> = (0..n as u64).map(|r| run_draws(5, r, 4)).collect();
        let nf = n as f64;
        let mean = |k: usize| d.iter().map(|x| x[k]).sum::<f64>() / nf;
        let (m0, m1) = (mean(0), mean(1));
        let var = |k: usize, m: f64| d.iter().map(|x| (x[k] - m).powi(2)).sum::<f64>() / nf;
        let cov = d.iter().map(|x| (x[0] - m0) * (x[1] - m1)).sum::<f64>() / nf;
        let corr = cov / (var(0, m0) * var(1, m1)).sqrt();
        assert!(corr.abs() < 5.0 / nf.sqrt(), "correlation {corr}");
        assert!(m1.abs() < 5.0 / nf.sqrt(), "mean {m1}");
        assert!(
            (var(1, m1) - 1.0).abs() < 5.0 * (2.0 / nf).sqrt(),
            "variance"
        );
    }

    /// The draws are standard normal: over 20 000 runs the mean of ln(factor) is -s^2 and its sd
    /// s, and the mean square of the factor 1 (the convention). Tolerances: 5 standard errors
    /// (false alarm about 6e-7 per statistic): sd(mean ln) = s/sqrt(n); sd(sample sd) =
    /// s/sqrt(2n); sd(mean of f^2) = sqrt((e^{4 s^2} - 1)/n).
    #[test]
    fn drawn_factors_are_log_normal_with_unit_mean_square() {
        let (n, s) = (20_000usize, 0.3f64);
        let lf: Vec<f64> = (0..n as u64)
            .map(|r| level_factor(s, run_draw(11, r, 2)).ln())
            .collect();
        let mean = lf.iter().sum::<f64>() / n as f64;
        let sd = (lf.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        let ms = lf.iter().map(|x| (2.0 * x).exp()).sum::<f64>() / n as f64;
        let nf = n as f64;
        assert!((mean + s * s).abs() < 5.0 * s / nf.sqrt(), "mean {mean}");
        assert!((sd - s).abs() < 5.0 * s / (2.0 * nf).sqrt(), "sd {sd}");
        let sd_ms = (((4.0 * s * s).exp() - 1.0) / nf).sqrt();
        assert!((ms - 1.0).abs() < 5.0 * sd_ms, "mean square {ms}");
    }
}
