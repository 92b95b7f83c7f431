//! Unit tests of the estimators, the phase conversion and the kernels.

use super::kernels::*;
use super::*;

/// Deterministic pseudo-random series (SplitMix64 mapped to [-0.5, 0.5)).
fn series(n: usize, seed: u64) -> Vec<f64> {
    let mut g = testkit::SplitMix64::new(seed);
    (0..n).map(|_| g.centred()).collect()
}

/// Direct textbook formulas (no phase, no running sums), O(N m) per tau.
fn naive(y: &[f64], est: Estimator, m: usize) -> f64 {
    let n = y.len();
    let avg = |k: usize| y[k..k + m].iter().sum::<f64>() / m as f64;
    match est {
        Estimator::Overlapping | Estimator::NonOverlapping => {
            let stride = if est == Estimator::Overlapping { 1 } else { m };
            let mut s = 0.0;
            let mut c = 0;
            let mut k = 0;
            while k + 2 * m <= n {
                let d = avg(k + m) - avg(k);
                s += d * d;
                c += 1;
                k += stride;
            }
            (s / (2.0 * c as f64)).sqrt()
        }
        Estimator::Hadamard | Estimator::OverlappingHadamard => {
            let stride = if est == Estimator::OverlappingHadamard {
                1
            } else {
                m
            };
            let mut s = 0.0;
            let mut c = 0;
            let mut k = 0;
            while k + 3 * m <= n {
                let d = avg(k + 2 * m) - 2.0 * avg(k + m) + avg(k);
                s += d * d;
                c += 1;
                k += stride;
            }
            (s / (6.0 * c as f64)).sqrt()
        }
        Estimator::Modified => {
            // Mod sigma^2 = 1/(2 m^2 (N-3m+2)) sum_j [sum_{i=j}^{j+m-1} (ybar_{i+m} - ybar_i)]^2
            // with ybar the m-averages (SP 1065 eq (15), frequency form).
            let mut s = 0.0;
            let mut c = 0;
            let mut j = 0;
            while j + 3 * m <= n + 1 {
                let inner: f64 = (j..j + m).map(|i| avg(i + m) - avg(i)).sum();
                s += inner * inner;
                c += 1;
                j += 1;
            }
            (s / (2.0 * (m * m) as f64 * c as f64)).sqrt()
        }
        // Tested against their own definitions (total.rs) and allantools (Python tests).
        Estimator::Total
        | Estimator::ModifiedTotal
        | Estimator::HadamardTotal
        | Estimator::Theo1
        | Estimator::TheoH => unreachable!(),
    }
}

#[test]
fn fast_sums_match_textbook_formulas() {
    // Reason for 1e-11: both sides are exact formulas; the difference is rounding only.
    const REL_TOL: f64 = 1e-11;
    let y: Vec<f64> = series(3000, 7).iter().map(|v| 3.0 + v).collect();
    for est in [
        Estimator::Overlapping,
        Estimator::NonOverlapping,
        Estimator::Hadamard,
        Estimator::OverlappingHadamard,
        Estimator::Modified,
    ] {
        for m in [1usize, 2, 3, 7, 50, 333] {
            let p = deviation_with(
                &y,
                DataKind::Rate,
                1.0,
                est,
                &TauGrid::Explicit(vec![m]),
                &Options {
                    edf: EdfMethod::None,
                    ..Options::default()
                },
            );
            let got = p[0].dev;
            let want = naive(&y, est, m);
            assert!(
                ((got - want) / want).abs() < REL_TOL,
                "{est:?} m={m}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn blocked_kernel_matches_single_tau_path() {
    // Same sums, different association of the additions: 1e-12 relative.
    let y = series(300_000, 9);
    let s = Series::new(&y, DataKind::Rate, 0.01);
    let ms: Vec<usize> = (0..17)
        .map(|k| 1usize << k)
        .chain([3, 7, 1000, 4097])
        .collect();
    let mut ms = ms;
    ms.sort_unstable();
    for est in [Estimator::Overlapping, Estimator::OverlappingHadamard] {
        let blocked = s.raw_points(est, &ms);
        let single: Vec<AllanPoint> = ms.iter().filter_map(|&m| s.raw_point(est, m)).collect();
        assert_eq!(blocked.len(), single.len());
        for (p, q) in blocked.iter().zip(&single) {
            assert_eq!((p.m, p.n_terms), (q.m, q.n_terms));
            assert!(((p.dev - q.dev) / q.dev).abs() < 1e-12, "{est:?} m={}", p.m);
        }
    }
}

#[test]
fn wide_vector_variants_give_the_same_bits() {
    // The dispatched kernels (AVX-512 or AVX2 on CPUs that have them) against the same
    // code compiled for the baseline target: identical results, not merely close.
    let y = series(100_003, 11);
    let x = rate_to_phase(&y, 0.01);
    let ms: Vec<usize> = (0..14).map(|k| 1usize << k).chain([3, 4097]).collect();
    let mut ms = ms;
    ms.sort_unstable();
    for order in [2, 3] {
        let fast = blocked_diff_sums_fast(&x, &ms, order);
        let base = blocked_diff_sums(&x, &ms, order);
        assert_eq!(fast.len(), base.len());
        for (a, b) in fast.iter().zip(&base) {
            assert_eq!(a.to_bits(), b.to_bits(), "order {order}");
        }
    }
    for est in [
        Estimator::Overlapping,
        Estimator::OverlappingHadamard,
        Estimator::Modified,
        Estimator::Total,
    ] {
        for m in [1, 5, 64, 20_000] {
            let fast = estimator_sum_fast(&x, est, m).map(|(s, n)| (s.to_bits(), n));
            let base = estimator_sum(&x, est, m).map(|(s, n)| (s.to_bits(), n));
            assert_eq!(fast, base, "{est:?} m={m}");
        }
    }
    for m in [1, 2, 16, 1000] {
        let blocks = y.len() / m;
        let base = edf::rate_noise_id_fn(blocks, |j| x[(j + 1) * m] - x[j * m], 2);
        assert!(base.is_some());
        assert_eq!(rate_noise_id_fast(&x, m, blocks, 2), base, "m={m}");
    }
}

#[test]
fn phase_sum_is_compensated() {
    // A large offset plus small noise over 4M samples: a naive running sum loses about
    // log10(N) digits; the compensated phase must give the m = 1 Allan deviation that the
    // direct first-difference formula gives (no summation at all) to 1e-12.
    const REL_TOL: f64 = 1e-12;
    let n = 4_000_000;
    let y: Vec<f64> = series(n, 11).iter().map(|v| 1.0e3 + 1.0e-3 * v).collect();
    let p = deviation_with(
        &y,
        DataKind::Rate,
        0.01,
        Estimator::Overlapping,
        &TauGrid::Explicit(vec![1]),
        &Options {
            edf: EdfMethod::None,
            ..Options::default()
        },
    );
    let direct: f64 = y
        .windows(2)
        .map(|w| (w[1] - w[0]) * (w[1] - w[0]))
        .sum::<f64>()
        / (2.0 * (n - 1) as f64);
    let direct = direct.sqrt();
    assert!(
        ((p[0].dev - direct) / direct).abs() < REL_TOL,
        "{} vs {}",
        p[0].dev,
        direct
    );
}

#[test]
fn rate_and_phase_input_agree() {
    const REL_TOL: f64 = 1e-10;
    let y = series(2000, 3);
    let x = rate_to_phase(&y, 0.5);
    for est in Estimator::ALL {
        let a = deviation(&y, DataKind::Rate, 0.5, est, &TauGrid::Octave);
        let b = deviation(&x, DataKind::Phase, 0.5, est, &TauGrid::Octave);
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(&b) {
            assert_eq!(p.n_terms, q.n_terms);
            assert!(((p.dev - q.dev) / q.dev).abs() < REL_TOL);
        }
    }
}

#[test]
fn hadamard_ignores_a_rate_ramp_allan_does_not() {
    // A rate ramp integrates to a quadratic phase, which every third difference removes
    // exactly (SP 1065 §5.2.8): HDEV of white + ramp equals HDEV of white alone up to
    // rounding (1e-9: the ramp's phase is ~1e4 times the noise's), while OADEV grows.
    let white = series(20_000, 21);
    let ramp: Vec<f64> = white
        .iter()
        .enumerate()
        .map(|(k, w)| w + 1e-3 * k as f64)
        .collect();
    for est in [Estimator::Hadamard, Estimator::OverlappingHadamard] {
        let a = deviation(&white, DataKind::Rate, 1.0, est, &TauGrid::Octave);
        let b = deviation(&ramp, DataKind::Rate, 1.0, est, &TauGrid::Octave);
        for (p, q) in a.iter().zip(&b) {
            assert!(((p.dev - q.dev) / p.dev).abs() < 1e-9, "{est:?} m={}", p.m);
        }
    }
    let a = deviation(
        &white,
        DataKind::Rate,
        1.0,
        Estimator::Overlapping,
        &TauGrid::Octave,
    );
    let b = deviation(
        &ramp,
        DataKind::Rate,
        1.0,
        Estimator::Overlapping,
        &TauGrid::Octave,
    );
    let last = a.len() - 1;
    // R^2 tau^2 / 2 dominates at long tau (docs/model.md §2): 1e-3 * tau / sqrt 2.
    let want = 1e-3 * a[last].tau_s / 2f64.sqrt();
    assert!(
        (b[last].dev / want - 1.0).abs() < 0.05,
        "{} vs {want}",
        b[last].dev
    );
}

#[test]
fn short_or_degenerate_inputs_do_not_panic() {
    let grids = [
        TauGrid::Octave,
        TauGrid::Decade,
        TauGrid::All,
        TauGrid::PerDecade(3),
    ];
    for n in 0..40 {
        let y = series(n, n as u64);
        let constant = vec![1.0; n];
        for data in [&y, &constant] {
            for est in Estimator::ALL {
                for g in &grids {
                    for kind in [DataKind::Rate, DataKind::Phase] {
                        let p = deviation(data, kind, 0.01, est, g);
                        assert!(p.iter().all(|q| q.n_terms >= 2));
                        let _ = fit::fit_ieee952(&p);
                    }
                }
            }
        }
    }
}

#[test]
fn woodman_bins_rule() {
    let y = series(1000, 5);
    let p = deviation(
        &y,
        DataKind::Rate,
        1.0,
        Estimator::NonOverlapping,
        &TauGrid::All,
    );
    for q in &p {
        assert_eq!(q.bins, 1000 / q.m);
        assert_eq!(q.n_terms, q.bins - 1);
        assert_eq!(q.woodman_ok(), q.m <= 111);
    }
}

#[test]
fn total_deviation_reaches_the_largest_factor() {
    // SP 1065 eq (25) on the explicitly built 3N - 4 point reflected series (allantools `totdev`),
    // for every m up to N - 1, the largest factor the reflections cover.
    // Reason for 1e-12: the same sums in another order; the difference is rounding only.
    const REL_TOL: f64 = 1e-12;
    let x = series(40, 11);
    let n = x.len();
    let mut star: Vec<f64> = (1..n - 1).rev().map(|j| 2.0 * x[0] - x[j]).collect();
    star.extend_from_slice(&x);
    star.extend((1..n - 1).map(|j| 2.0 * x[n - 1] - x[n - 1 - j]));
    let mid = n - 2;
    for m in 1..n {
        let s: f64 = (1..n - 1)
            .map(|i| {
                let d = star[mid + i - m] - 2.0 * star[mid + i] + star[mid + i + m];
                d * d
            })
            .sum();
        let (fast, terms) = estimator_sum(&x, Estimator::Total, m).expect("m < N");
        assert_eq!(terms, n - 2);
        assert!((fast - s).abs() <= REL_TOL * s, "m={m}: {fast} vs {s}");
    }
    assert!(estimator_sum(&x, Estimator::Total, n).is_none());
}

#[test]
fn phase_from_a_slice_equals_phase_in_place() {
    // Several blocks of the phase conversion and a remainder (not a multiple of 8): groups of
    // 2 and 1 blocks side by side (3 blocks), of 8, 4 and 1 (13), two tasks of 8 (16 blocks).
    for (blocks, extra) in [(3, 5), (13, 7), (16, 0)] {
        let y = series(blocks * (1 << 16) + extra, 21);
        let a = rate_to_phase(&y, 0.01);
        let b = crate::rate_to_phase_in_place(y.clone(), 0.01);
        assert_eq!(a.len(), y.len() + 1);
        assert!(
            a.iter().zip(&b).all(|(p, q)| p.to_bits() == q.to_bits()),
            "{blocks}"
        );
    }
}

#[test]
fn streamed_kernel_gives_the_single_factor_sums_bit_for_bit() {
    // The large factors of a grid in one streamed pass: exactly `estimator_sum`'s sums (the
    // blocks and the lane-0 tail reproduce its order of additions), for records whose term
    // counts leave every remainder mod 8.
    for n in [70_001usize, 70_004, 81_923] {
        let x = rate_to_phase(&series(n, 5), 0.01);
        let ms = [1000usize, 2048, 4096, 8192, 9000, 16384];
        for (order, est) in [
            (2, Estimator::Overlapping),
            (3, Estimator::OverlappingHadamard),
        ] {
            let streamed = crate::kernels::streamed_diff_sums_fast(&x, &ms, order);
            for (&m, s) in ms.iter().zip(&streamed) {
                let (single, _) = crate::kernels::estimator_sum(&x, est, m).unwrap();
                assert_eq!(s.to_bits(), single.to_bits(), "n {n} order {order} m {m}");
            }
        }
    }
}

#[test]
fn blocked_kernel_sums_each_lane_in_index_order() {
    // The blocked kernel (factors fused four at a time over whole blocks) against the plain
    // loop it stands for: lane i mod 8, additions in index order, lanes added pairwise.
    let x = rate_to_phase(&series(50_001, 17), 0.01);
    let ms: Vec<usize> = (0..13)
        .map(|k| 1usize << k)
        .chain([3, 5, 7, 1000])
        .collect();
    for order in [2usize, 3] {
        let fast = blocked_diff_sums_fast(&x, &ms, order);
        for (&m, s) in ms.iter().zip(&fast) {
            let mut acc = [0.0f64; 8];
            for i in 0..x.len() - order * m {
                let v = if order == 2 {
                    x[i + 2 * m] - 2.0 * x[i + m] + x[i]
                } else {
                    x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i]
                };
                acc[i % 8] += v * v;
            }
            let plain = crate::sum::pairwise_lanes(&acc);
            assert_eq!(s.to_bits(), plain.to_bits(), "order {order} m {m}");
        }
    }
}

#[test]
fn theoh_is_avar_below_a_tenth_of_the_record_and_bias_removed_theo1_beyond() {
    // SP 1065 §5.2.14 written out: AVAR at m tau0 < 0.1 T, TheoBR = kf Theo1 at even m with
    // 0.75 m tau0 >= 0.1 T, kf the mean of AVAR(9 + 3i) / Theo1(12 + 4i), i = 0..=n,
    // n = floor(0.1 N / 3) - 3 (N phase points), from the two estimators' own curves.
    let y = series(2999, 41);
    let tau0 = 0.01;
    let s = Series::new(&y, DataKind::Rate, tau0);
    let n = s.phase_len();
    assert_eq!(n, 3000);
    let top = (0.1 * n as f64 / 3.0).floor() as usize - 3;
    let dev = |est, m| s.raw_point(est, m).unwrap().dev;
    let kf = (0..=top)
        .map(|i| {
            dev(Estimator::Overlapping, 9 + 3 * i).powi(2)
                / dev(Estimator::Theo1, 12 + 4 * i).powi(2)
        })
        .sum::<f64>()
        / (top + 1) as f64;
    assert_eq!(s.theo_bias_factor(), Some(kf));
    let opts = Options {
        edf: EdfMethod::None,
        ..Options::default()
    };
    let points = s.deviation(Estimator::TheoH, &TauGrid::All, &opts);
    // 0.1 T = 299.9 samples: AVAR for m <= 299, TheoBR for even m >= 400 (0.75 m >= 299.9).
    let (avar, theo): (Vec<_>, Vec<_>) = points.iter().partition(|p| p.m <= 299);
    assert_eq!(avar.len(), 299);
    assert_eq!(theo.first().map(|p| p.m), Some(400));
    assert_eq!(theo.last().map(|p| p.m), Some(2998));
    for p in avar {
        // The same sums: bit for bit.
        assert_eq!(p.dev, dev(Estimator::Overlapping, p.m), "m={}", p.m);
        assert_eq!(p.tau_s, p.m as f64 * tau0);
    }
    for p in theo {
        assert_eq!(p.m % 2, 0);
        assert_eq!(p.tau_s, 0.75 * (p.m as f64 * tau0));
        let want = kf.sqrt() * dev(Estimator::Theo1, p.m);
        assert!(((p.dev - want) / want).abs() < 1e-15, "m={}", p.m);
    }
}

#[test]
fn theo_bias_factor_identifies_the_noise_as_howe_and_tasset_tabulate() {
    // Expected AVAR / Theo1 (Howe & Tasset 2004, quoted in SP 1065 §5.2.14 and Riley's TheoBR
    // code): 1.0 for white FM, about 0.4 for white PM (0.09 + 0.74 / r^0.4 at r = 0.75 m, 0.40 to
    // 0.22 over the factors kf averages here). Riley classifies the noise by kf against the
    // geometric means of neighbouring types' factors: white FM between sqrt(0.6 * 1.0) = 0.775
    // and sqrt(1.0 * 1.71) = 1.308, white PM below sqrt(0.4 * 0.6) = 0.490. Over 200 seeds of
    // these 8192-point records (`theo_bias_factor_spread`, docs/allan.md) white FM's kf ranged
    // 0.764 to 1.297 (a few records below the band), white PM's 0.172 to 0.175; the seeds here
    // are fixed draws inside (the test is deterministic; it fails if kf's definition changes).
    for seed in [1u64, 2, 3] {
        let white_fm = series(8191, seed);
        let kf = Series::new(&white_fm, DataKind::Rate, 1.0)
            .theo_bias_factor()
            .unwrap();
        assert!(
            (0.775..1.308).contains(&kf),
            "white FM seed {seed}: kf {kf}"
        );
        let white_pm = series(8192, seed + 100);
        let kf = Series::new(&white_pm, DataKind::Phase, 1.0)
            .theo_bias_factor()
            .unwrap();
        assert!(kf < 0.490, "white PM seed {seed}: kf {kf}");
    }
}

#[test]
#[ignore = "the spread of the TheoBR bias factor over 200 seeds (docs/allan.md): --ignored --nocapture"]
fn theo_bias_factor_spread() {
    let (mut fm, mut pm) = (Vec::new(), Vec::new());
    for seed in 0..200u64 {
        fm.push(
            Series::new(&series(8191, seed), DataKind::Rate, 1.0)
                .theo_bias_factor()
                .unwrap(),
        );
        pm.push(
            Series::new(&series(8192, seed + 1000), DataKind::Phase, 1.0)
                .theo_bias_factor()
                .unwrap(),
        );
    }
    let range = |v: &[f64]| {
        (
            v.iter().cloned().fold(f64::MAX, f64::min),
            v.iter().cloned().fold(f64::MIN, f64::max),
        )
    };
    let fm_outside = fm.iter().filter(|k| !(0.775..1.308).contains(*k)).count();
    let pm_outside = pm.iter().filter(|&&k| k >= 0.490).count();
    eprintln!(
        "white FM kf range {:?}, {fm_outside} of 200 outside [0.775, 1.308); white PM kf range {:?}, {pm_outside} of 200 at or above 0.490",
        range(&fm),
        range(&pm)
    );
    // Riley's classification by kf is a statistic: on 8192-point records it misreads white FM
    // on a few records in a hundred at most (measured: docs/allan.md), white PM never.
    assert!(fm_outside <= 6, "{fm_outside}");
    assert_eq!(pm_outside, 0);
}
