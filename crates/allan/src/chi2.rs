//! Chi-squared quantiles and the confidence interval of a deviation from its EDF.
//!
//! Special functions after Numerical Recipes (Press et al., 3rd ed.): `ln_gamma` by the
//! Lanczos approximation (§6.1, g = 7, 9 coefficients), the regularised incomplete gamma
//! function by its series and Lentz continued fraction (§6.2); the normal quantile by
//! Acklam's rational approximation refined by one Halley step; the chi-squared quantile by
//! a safeguarded Newton iteration on the exact CDF started at the Wilson–Hilferty value.

/// ln Gamma(x), x > 0 (the workspace's one copy: `stats::ln_gamma`).
pub use stats::ln_gamma;

/// Regularised lower incomplete gamma P(a, x).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let ln_pre = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        // Series: P = e^-x x^a / Gamma(a+1) * sum x^n / ((a+1)...(a+n)).
        let mut ap = a;
        let mut del = 1.0 / a;
        let mut sum = del;
        for _ in 0..100_000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (sum.ln() + ln_pre).exp()
    } else {
        1.0 - gamma_q_cf(a, x, ln_pre)
    }
}

/// Continued fraction for Q(a, x) (modified Lentz), NR §6.2.
fn gamma_q_cf(a: f64, x: f64, ln_pre: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..100_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (ln_pre + h.ln()).exp()
}

/// Chi-squared CDF with `k` degrees of freedom.
pub fn chi2_cdf(x: f64, k: f64) -> f64 {
    gamma_p(0.5 * k, 0.5 * x)
}

/// ln of the chi-squared density.
fn chi2_ln_pdf(x: f64, k: f64) -> f64 {
    (0.5 * k - 1.0) * x.ln() - 0.5 * x - 0.5 * k * std::f64::consts::LN_2 - ln_gamma(0.5 * k)
}

/// Standard normal quantile (Acklam's algorithm, relative error < 1.2e-9, then one Halley
/// step against erfc for full double precision).
pub fn normal_ppf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.024_25;
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    let x = if p < P_LOW {
        let q = (-2.0 * p.ln()).sqrt();
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    } else if p <= 1.0 - P_LOW {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        let q = (-2.0 * (1.0 - p).ln()).sqrt();
        -(((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    // Halley refinement with Phi(x) = 1 - Q(1/2, x^2/2)/2 for x >= 0.
    let phi = normal_cdf(x);
    let e = phi - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
    x - u / (1.0 + 0.5 * x * u)
}

/// Standard normal CDF via the incomplete gamma function: erf(z) = P(1/2, z^2).
pub fn normal_cdf(x: f64) -> f64 {
    let half = 0.5 * gamma_p(0.5, 0.5 * x * x);
    if x >= 0.0 {
        0.5 + half
    } else {
        0.5 - half
    }
}

/// Quantile of Student's t distribution with `nu` degrees of freedom by the Cornish-Fisher
/// expansion about the normal quantile (Abramowitz & Stegun 26.7.5, terms to nu^-4): within
/// 1e-5 of the exact value at p = 0.975 for nu >= 10, 3e-4 at nu = 5 and 4e-3 at nu = 3 (A&S
/// Table 26.10). NaN for
/// p outside (0, 1) or nu <= 0.
pub fn t_ppf(p: f64, nu: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && nu > 0.0) {
        return f64::NAN;
    }
    let z = normal_ppf(p);
    let (z2, n) = (z * z, nu);
    let g1 = z * (z2 + 1.0) / 4.0;
    let g2 = z * ((5.0 * z2 + 16.0) * z2 + 3.0) / 96.0;
    let g3 = z * (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) / 384.0;
    let g4 = z * ((((79.0 * z2 + 776.0) * z2 + 1482.0) * z2 - 1920.0) * z2 - 945.0) / 92160.0;
    z + g1 / n + g2 / (n * n) + g3 / (n * n * n) + g4 / (n * n * n * n)
}

/// Quantile of the chi-squared distribution with `k > 0` degrees of freedom.
pub fn chi2_ppf(p: f64, k: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && k > 0.0) {
        return f64::NAN;
    }
    // Wilson–Hilferty start.
    let z = normal_ppf(p);
    let h = 2.0 / (9.0 * k);
    let mut x = (k * (1.0 - h + z * h.sqrt()).powi(3)).max(1e-8 * k.min(1.0));
    // Bracket and safeguarded Newton.
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for _ in 0..200 {
        let f = chi2_cdf(x, k) - p;
        if f < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let step = f / chi2_ln_pdf(x, k).exp();
        let mut next = x - step;
        if next <= lo || next >= hi || !next.is_finite() {
            next = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                2.0 * x.max(1e-300)
            };
        }
        if (next - x).abs() <= 1e-14 * x {
            return next;
        }
        x = next;
    }
    x
}

/// Confidence interval of a deviation with `edf` degrees of freedom at confidence `ci`,
/// NIST SP 1065 eq (45) / allantools `confidence_interval`:
/// var_lo = edf var / chi2_{1-(1-ci)/2}, var_hi = edf var / chi2_{(1-ci)/2}.
pub fn confidence_interval(dev: f64, edf: f64, ci: f64) -> (f64, f64) {
    if edf.is_nan() || edf <= 0.0 || !edf.is_finite() {
        return (f64::NAN, f64::NAN);
    }
    // Two-sided: (1 - ci)/2 in each tail (ci in (0, 1); allantools' min(ci, 1 - ci) would turn a
    // 30 % interval into a 70 % one). For ci >= 0.5 this is bit-identical to that form.
    let p_lo = (1.0 - ci).clamp(0.0, 1.0) / 2.0;
    let p_hi = 1.0 - p_lo;
    let var = dev * dev;
    let lo = (edf * var / chi2_ppf(p_hi, edf)).sqrt();
    let hi = (edf * var / chi2_ppf(p_lo, edf)).sqrt();
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Student's t at 0.975 against Abramowitz & Stegun Table 26.10 (5 digits; scipy's
    /// `t.ppf(0.975, nu)` gives the same): 3.18245 (3), 2.57058 (5), 2.20099 (11), 2.04227 (30);
    /// symmetric about 0.5.
    #[test]
    fn t_quantiles_match_the_table() {
        for (nu, t) in [(11.0, 2.20099), (30.0, 2.04227)] {
            let got = t_ppf(0.975, nu);
            assert!((got - t).abs() < 2e-5, "nu {nu}: {got}");
        }
        assert!((t_ppf(0.975, 5.0) - 2.57058).abs() < 5e-4);
        assert!((t_ppf(0.975, 3.0) - 3.18245).abs() < 5e-3);
        assert!((t_ppf(0.025, 11.0) + t_ppf(0.975, 11.0)).abs() < 1e-12);
    }

    #[test]
    fn a_narrow_level_gives_a_narrow_interval() {
        // A 30 % interval lies inside the 70 % one (it used to be the same interval).
        let (lo30, hi30) = confidence_interval(1.0, 20.0, 0.3);
        let (lo70, hi70) = confidence_interval(1.0, 20.0, 0.7);
        assert!(lo70 < lo30 && hi30 < hi70, "{lo30} {hi30} {lo70} {hi70}");
        // 1 - ci = 0.7 split over two tails: chi2 quantiles at 0.35 and 0.65.
        assert!((lo30 - (20.0 / chi2_ppf(0.65, 20.0)).sqrt()).abs() < 1e-14);
    }

    #[test]
    fn against_scipy() {
        // scipy.stats.chi2.ppf / norm.ppf values (scipy 1.17), printed with 17 digits.
        // Tolerance 1e-10: both are converged double-precision quantiles.
        const REL_TOL: f64 = 1e-10;
        let cases = [
            (0.15865525393145707, 1.0, 0.04006950463364094),
            (0.8413447460685429, 1.0, 1.986996713315955),
            (0.15865525393145707, 7.5, 3.804126264157349),
            (0.8413447460685429, 7.5, 11.204090940355771),
            (0.15865525393145707, 19981.0, 19781.098358982596),
            (0.8413447460685429, 19981.0, 20180.90164398325),
            (0.025, 2.0, 0.05063561596857975),
            (0.975, 3_000_000.0, 3_004_802.8057013326),
        ];
        for (p, k, want) in cases {
            let got = chi2_ppf(p, k);
            assert!(
                ((got - want) / want).abs() < REL_TOL,
                "p={p} k={k}: {got} vs {want}"
            );
        }
        assert!((normal_ppf(0.975) - 1.959963984540054).abs() < 1e-12);
        assert!((normal_cdf(1.0) - 0.8413447460685429).abs() < 1e-14);
    }
}
