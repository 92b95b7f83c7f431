//! All the cells of a drift check judged together (docs/drift.md, "Every cell at once").
//!
//! A check has one verdict per (horizon, quantity) cell, each against a 95 % band: a model that is
//! right still leaves a cell outside now and then, and with twenty cells, most of them driven by
//! the same gyros, how many misses are too many is not obvious. The joint test answers it from
//! the model's own simulated experiments, with no threshold of ours.
//!
//! The members are the measurement and the R simulated experiments (exchangeable when the model
//! is right: each experiment is a draw of the same statistics the measurement is). For member i
//! and cell c, z_ic = (ln x_ic - mean_j ln x_jc) / sd_j ln x_jc over the other R members j, x the
//! cell's RMS. Two statistics per member: T_i = max over cells of |z_ic|, the most extreme cell
//! standardised by the others (the max-T statistic of Westfall & Young, Resampling-Based
//! Multiple Testing, 1993, §2.6, which keeps the family-wise level whatever the correlation of
//! the cells), for one cell far out; and C_i, the cells outside their band against the others
//! (the band rule of `drift_check`, order statistics a and R + 1 - a of the R other members,
//! a = 0.025 (R + 1)), for many cells a little out. Each member's rank p-values among all
//! members, p_T(i) = #{j : T_j >= T_i} / (R + 1) and p_C(i) likewise, are combined as
//! S_i = min(p_T(i), p_C(i)), and the p-value is the measurement's rank on S,
//! p = #{i : S_i <= S_0} / (R + 1) (member 0 the measurement; the min-p combination of
//! Westfall & Young §2.6 with the Monte Carlo test's rank, Davison & Hinkley 1997, §4.2.5):
//! exact for exchangeable members, at least 1 / (R + 1). Leaving each member out of its own
//! reference treats all of them alike, which is what makes the rank uniform under the model.

use serde::Serialize;

/// The joint verdict of every informed cell of a drift check.
#[derive(Clone, Debug, Serialize)]
pub struct JointCheck {
    /// Informed cells judged.
    pub cells: usize,
    /// Measured cells outside their 95 % band.
    pub outside: usize,
    /// Cells outside per simulated experiment against the others: the mean, and the share of
    /// experiments with at least as many as measured.
    pub model_outside_mean: f64,
    pub model_outside_at_least: f64,
    /// Share of simulated experiments with every cell inside the others' bands: how often a right
    /// model passes a demand that every cell be inside.
    pub model_all_inside: f64,
    /// The measurement's most extreme cell, standardised by the simulated experiments: its
    /// horizon, quantity and |z| (T_0).
    pub worst: WorstCell,
    /// The joint test's p-value: the measurement's rank on the smaller of its two rank p-values,
    /// max |z| and cells outside (module doc).
    pub p_value: f64,
    /// p >= 0.05: the misses are as many and as far as a right model's.
    pub consistent: bool,
}

/// A cell named by its horizon and quantity, with the measurement's |z| there.
#[derive(Clone, Debug, Serialize)]
pub struct WorstCell {
    pub t_s: f64,
    pub quantity: &'static str,
    pub abs_z: f64,
}

/// Level of the joint test.
pub const JOINT_LEVEL: f64 = 0.05;

/// One cell: its horizon and quantity, the measured RMS and the R simulated experiments' RMS.
pub struct Cell {
    pub t_s: f64,
    pub quantity: &'static str,
    pub measured: f64,
    pub simulated: Vec<f64>,
}

/// The order statistic of 1-based fractional rank `a` of a sorted list of `len` values read by
/// `at` (linear between neighbours, clamped): the band rule of `drift_check`.
fn order_stat(len: usize, at: impl Fn(usize) -> f64, a: f64) -> f64 {
    let a = a.clamp(1.0, len as f64);
    let i = a.floor() as usize;
    let f = a - i as f64;
    if i < len {
        at(i - 1) * (1.0 - f) + at(i) * f
    } else {
        at(i - 1)
    }
}

/// The 95 % band of a sorted list of R values read by `at`: order statistics a and R + 1 - a,
/// a = 0.025 (R + 1), at least the extremes.
fn band_of(r: usize, at: impl Fn(usize) -> f64 + Copy) -> (f64, f64) {
    let a = (0.025 * (r + 1) as f64).max(1.0);
    (order_stat(r, at, a), order_stat(r, at, (r + 1) as f64 - a))
}

/// The 95 % band of `sorted` (module doc of `drift_check`).
pub(crate) fn band(sorted: &[f64]) -> (f64, f64) {
    band_of(sorted.len(), |j| sorted[j])
}

/// [`band`] of `sorted` without its element at index `skip` (the others of one member), read in
/// place: element j of the shortened list is `sorted[j]` below `skip`, `sorted[j + 1]` from it.
fn band_without(sorted: &[f64], skip: usize) -> (f64, f64) {
    band_of(sorted.len() - 1, |j| {
        sorted[if j < skip { j } else { j + 1 }]
    })
}

/// The cells whose members (the measurement and the simulated experiments) are all positive and
/// finite, with at least 10 experiments, and the member count; None without one, or when the
/// cells disagree on the count.
fn usable(cells: &[Cell]) -> Option<(Vec<&Cell>, usize)> {
    let cells: Vec<&Cell> = cells
        .iter()
        .filter(|c| {
            c.simulated.len() >= 10
                && std::iter::once(c.measured)
                    .chain(c.simulated.iter().copied())
                    .all(|x| x.is_finite() && x > 0.0)
        })
        .collect();
    let members = cells.first()?.simulated.len() + 1;
    if cells.iter().any(|c| c.simulated.len() + 1 != members) {
        return None;
    }
    Some((cells, members))
}

/// The joint test over `cells` (module doc); None without a cell whose members all have a
/// positive finite RMS, or with fewer than 10 simulated experiments.
pub fn joint_check(cells: &[Cell]) -> Option<JointCheck> {
    let (cells, members) = usable(cells)?;
    // Per member (0 the measurement): its largest |z| (T), the cell of it, its cells outside (C).
    let mut t = vec![0.0f64; members];
    let mut worst = vec![0usize; members];
    let mut outside = vec![0usize; members];
    for (k, c) in cells.iter().enumerate() {
        let x: Vec<f64> = std::iter::once(c.measured)
            .chain(c.simulated.iter().copied())
            .collect();
        // ln RMS about the members' mean (the leave-one-out sums below then keep their digits).
        let ln: Vec<f64> = x.iter().map(|v| v.ln()).collect();
        let centre = stats::mean(&ln);
        let ln: Vec<f64> = ln.iter().map(|v| v - centre).collect();
        // The members sorted once, and each member's place there: its band is that of the
        // others, the sorted list without it (`band_without`).
        let mut order: Vec<usize> = (0..members).collect();
        order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
        let sorted: Vec<f64> = order.iter().map(|&j| x[j]).collect();
        let mut rank = vec![0usize; members];
        for (r, &j) in order.iter().enumerate() {
            rank[j] = r;
        }
        // Every member's leave-one-out mean and variance from the two sums, in one pass (not
        // `stats::sample_variance` per member, R passes).
        let (sum, sum2) = ln.iter().fold((0.0, 0.0), |(s, q), v| (s + v, q + v * v));
        let others = (members - 1) as f64;
        for i in 0..members {
            let m = (sum - ln[i]) / others;
            let var = ((sum2 - ln[i] * ln[i]) - others * m * m) / (others - 1.0);
            if var > 0.0 {
                let z = ((ln[i] - m) / var.sqrt()).abs();
                if z > t[i] {
                    t[i] = z;
                    worst[i] = k;
                }
            }
            let (lo, hi) = band_without(&sorted, rank[i]);
            if x[i] < lo || x[i] > hi {
                outside[i] += 1;
            }
        }
    }
    // Each member's rank p-value on each statistic among all members, their minimum, and the
    // measurement's rank on that minimum (module doc).
    let m = members as f64;
    let rank_p = |i: usize| {
        let p_t = t.iter().filter(|&&y| y >= t[i]).count() as f64 / m;
        let p_c = outside.iter().filter(|&&y| y >= outside[i]).count() as f64 / m;
        p_t.min(p_c)
    };
    let s: Vec<f64> = (0..members).map(rank_p).collect();
    let p_value = s.iter().filter(|&&y| y <= s[0]).count() as f64 / m;
    let sims = &outside[1..];
    let model_outside_mean = sims.iter().sum::<usize>() as f64 / sims.len() as f64;
    let model_outside_at_least =
        sims.iter().filter(|&&o| o >= outside[0]).count() as f64 / sims.len() as f64;
    let model_all_inside = sims.iter().filter(|&&o| o == 0).count() as f64 / sims.len() as f64;
    Some(JointCheck {
        cells: cells.len(),
        outside: outside[0],
        model_outside_mean,
        model_outside_at_least,
        model_all_inside,
        worst: WorstCell {
            t_s: cells[worst[0]].t_s,
            quantity: cells[worst[0]].quantity,
            abs_z: t[0],
        },
        p_value,
        consistent: p_value >= JOINT_LEVEL,
    })
}

/// The between-log tests of every cell judged together (docs/drift.md, "Runs that differ among
/// themselves"): does any cell's spread over the logs go beyond what the model's own experiments
/// give, counting that a right model flags about one cell in twenty by chance?
#[derive(Clone, Debug, Serialize)]
pub struct BetweenLogsJoint {
    /// Cells judged (informed in every experiment).
    pub cells: usize,
    /// Cells whose own between-log test flags (p < 0.05), and the share of the model's
    /// experiments with at least as many against the others.
    pub flagged: usize,
    pub model_flagged_at_least: f64,
    /// The measurement's rank on its largest standardised spread (max-T, `between_logs_joint`).
    pub p_value: f64,
    /// p < 0.05: the logs differ beyond the model's randomness, all cells counted.
    pub runs_differ: bool,
}

/// The max-T combination of the cells' between-log tests (Westfall & Young 1993, §2.6, as
/// [`joint_check`]): the members are the measurement and the R experiments, exchangeable under
/// the model. Member i's statistic in cell c is z_ic = (ln D_ic - mean_j ln D_jc) / sd_j ln D_jc
/// over the other R members j (one-sided: a spread above the others' is the alarm); T_i = max_c
/// z_ic, and the joint p-value is the measurement's rank on T, #{i : T_i >= T_0} / (R + 1): exact
/// for exchangeable members whatever the cells' correlation (each member is standardised by the
/// others alike). The cells' `measured` and `simulated` are D, the variance over the logs of
/// ln mean square (`drift_check`). A rank per cell instead (min-p) ties: with twenty cells most members are the
/// largest somewhere. None without a cell whose members are all positive and finite, or with
/// fewer than 10 experiments. `flagged` counts the measurement's cells whose own test
/// (`drift_check`'s, p = (1 + #{D_r >= D}) / (R + 1)) is below 0.05.
pub fn between_logs_joint(cells: &[Cell]) -> Option<BetweenLogsJoint> {
    let (cells, members) = usable(cells)?;
    let mut t = vec![f64::NEG_INFINITY; members];
    let mut flags = vec![0usize; members];
    for c in &cells {
        let ln: Vec<f64> = std::iter::once(c.measured)
            .chain(c.simulated.iter().copied())
            .map(f64::ln)
            .collect();
        let centre = stats::mean(&ln);
        let ln: Vec<f64> = ln.iter().map(|v| v - centre).collect();
        let (sum, sum2) = ln.iter().fold((0.0, 0.0), |(a, b), v| (a + v, b + v * v));
        let others = (members - 1) as f64;
        for (i, &x) in ln.iter().enumerate() {
            let mean = (sum - x) / others;
            let var = ((sum2 - x * x) - others * mean * mean) / (others - 1.0);
            let z = if var > 0.0 {
                (x - mean) / var.sqrt()
            } else {
                0.0
            };
            t[i] = t[i].max(z);
            let at_least = ln.iter().filter(|&&v| v >= x).count();
            flags[i] += usize::from((at_least as f64) / (members as f64) < JOINT_LEVEL);
        }
    }
    let p_value = t.iter().filter(|&&v| v >= t[0]).count() as f64 / members as f64;
    let at_least = flags[1..].iter().filter(|&&f| f >= flags[0]).count() as f64;
    Some(BetweenLogsJoint {
        cells: cells.len(),
        flagged: flags[0],
        model_flagged_at_least: at_least / (members - 1) as f64,
        p_value,
        runs_differ: p_value < JOINT_LEVEL,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_distr::StandardNormal;

    /// Cells of one experiment: `k` cells driven by one common normal and their own (a
    /// correlation of `rho` between cells), as ln RMS.
    fn draw(rng: &mut rand::rngs::StdRng, k: usize, rho: f64, shift: &[f64]) -> Vec<f64> {
        let common: f64 = rng.sample(StandardNormal);
        (0..k)
            .map(|c| {
                let own: f64 = rng.sample(StandardNormal);
                (0.3 * (rho.sqrt() * common + (1.0 - rho).sqrt() * own) + shift[c]).exp()
            })
            .collect()
    }

    fn cells(
        rng: &mut rand::rngs::StdRng,
        r: usize,
        k: usize,
        rho: f64,
        shift: &[f64],
    ) -> Vec<Cell> {
        let measured = draw(rng, k, rho, shift);
        let sims: Vec<Vec<f64>> = (0..r).map(|_| draw(rng, k, rho, &vec![0.0; k])).collect();
        (0..k)
            .map(|c| Cell {
                t_s: c as f64,
                quantity: "heading_rad",
                measured: measured[c],
                simulated: sims.iter().map(|s| s[c]).collect(),
            })
            .collect()
    }

    /// Of `trials` draws of `k` = 20 cells (R = 40 simulated, correlation `rho`, the measurement
    /// shifted by `shift`) from seed `seed`, how many the joint check's outcome `hit` counts.
    fn count(
        seed: u64,
        trials: usize,
        rho: f64,
        shift: &[f64],
        hit: impl Fn(&JointCheck) -> bool,
    ) -> usize {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        (0..trials)
            .filter(|_| hit(&joint_check(&cells(&mut rng, 40, 20, rho, shift)).unwrap()))
            .count()
    }

    /// The joint between-log test under the model rejects at its level, whatever the cells'
    /// correlation: 2000 trials each at rho = 0, 0.6 and 0.9, 20 cells, R = 40. The rank test is
    /// exact: P(p <= 2/41) = 2/41 = 4.88 %; bounds 4.88 % + 3.1 sd of 2000 trials (6.4 %) and at
    /// least 3 %. Meanwhile the per-cell tests flag one or more cells in most trials (20 cells at
    /// 5 % each), which is why the joint verdict is the one to read.
    #[test]
    fn between_logs_joint_rejects_five_percent_under_the_model() {
        for &rho in &[0.0, 0.6, 0.9] {
            let mut rng = rand::rngs::StdRng::seed_from_u64(23);
            let trials = 2000;
            let (mut rejected, mut any_flag) = (0usize, 0usize);
            for _ in 0..trials {
                let j = between_logs_joint(&cells(&mut rng, 40, 20, rho, &[0.0; 20])).unwrap();
                rejected += usize::from(j.runs_differ);
                any_flag += usize::from(j.flagged > 0);
            }
            let rate = rejected as f64 / trials as f64;
            println!("rho {rho}: joint rejected {rejected}/{trials}, some cell flagged {any_flag}");
            assert!((0.030..=0.064).contains(&rate), "rho {rho}: rate {rate}");
        }
    }

    /// A measurement whose D is 10 of its cell's standard deviations above the others' is found:
    /// its cell flags and the joint p is at its floor (1/41) or next to it.
    #[test]
    fn between_logs_joint_finds_one_cell_far_out() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut shift = vec![0.0; 20];
        shift[4] = 3.0;
        let j = between_logs_joint(&cells(&mut rng, 40, 20, 0.0, &shift)).unwrap();
        assert_eq!(j.flagged.min(1), 1);
        assert!(j.runs_differ && j.p_value <= 2.0 / 41.0, "{j:?}");
        assert_eq!(j.cells, 20);
    }

    /// Under the model (the measurement one more experiment) the test rejects at most 5 % of the
    /// time, whatever the cells' correlation: 2000 trials each at rho = 0, 0.3, 0.6 and 0.9, 20
    /// cells, R = 40 (measured 80-83 rejected, 4.0-4.2 %: the min-p of two statistics is a little
    /// conservative). The rejection rate of an exact test at level 0.05 with R = 40 is 2/41 = 4.88 %;
    /// the bound 4.88 % + 3.1 standard deviations of 2000 trials (sqrt(0.0488 * 0.951 / 2000)
    /// = 0.48 %): 6.4 %, passed by a right test with probability 0.999. And at least 3 %: a test
    /// that never rejects would pass a bound from above alone.
    #[test]
    fn rejects_five_percent_under_the_model() {
        for &rho in &[0.0, 0.3, 0.6, 0.9] {
            let trials = 2000;
            let rejected = count(7, trials, rho, &[0.0; 20], |j| !j.consistent);
            let rate = rejected as f64 / trials as f64;
            println!("rho {rho}: rejected {rejected}/{trials}");
            assert!((0.030..=0.064).contains(&rate), "rho {rho}: rate {rate}");
        }
    }

    /// One cell off by 5 of its own standard deviations is found, and named, in at least 80 % of
    /// trials (172 of 200 with this seed) (with R = 40 the p-value is below 0.05 only when the measurement is one of the
    /// two most extreme of the 41 members, so a smaller shift loses power to the maximum of twenty null
    /// cells), while the count of cells outside the band alone (one of twenty) would not tell it
    /// from a right model's misses.
    #[test]
    fn one_cell_far_out_is_found() {
        let mut shift = vec![0.0; 20];
        shift[13] = 0.3 * 5.0;
        let trials = 200;
        let found = count(11, trials, 0.5, &shift, |j| {
            !j.consistent && j.worst.t_s == 13.0
        });
        println!("one cell far out: found {found}/{trials}");
        assert!(
            found as f64 / trials as f64 >= 0.8,
            "found {found} of {trials}"
        );
    }

    /// Eight of twenty cells off by 2.5 of their standard deviations, none far enough out for the
    /// maximum alone, are found by the count outside: rejected in at least 80 % of 200 trials.
    #[test]
    fn many_cells_a_little_out_are_found() {
        let shift: Vec<f64> = (0..20)
            .map(|c| if c % 5 < 2 { 0.75 } else { 0.0 })
            .collect();
        let trials = 200;
        let rejected = count(13, trials, 0.0, &shift, |j| !j.consistent);
        println!("many cells a little out: rejected {rejected}/{trials}");
        assert!(
            rejected as f64 / trials as f64 >= 0.8,
            "rejected {rejected} of {trials}"
        );
    }

    /// The count outside for the measurement is the band verdicts' count: a measurement outside
    /// every cell's band counts all of them, and its p-value is the smallest, 1 / (R + 1).
    #[test]
    fn counts_and_smallest_p() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let mut c = cells(&mut rng, 39, 5, 0.0, &[0.0; 5]);
        for cell in &mut c {
            cell.measured = 100.0 * cell.simulated.iter().cloned().fold(0.0, f64::max);
        }
        let j = joint_check(&c).unwrap();
        assert_eq!((j.cells, j.outside), (5, 5));
        assert_eq!(j.p_value, 1.0 / 40.0);
        assert!(!j.consistent);
        assert_eq!(j.model_outside_at_least, 0.0);
        assert!((0.0..=1.0).contains(&j.model_all_inside));
    }

    /// The band of the others read in place is the band of the shortened list, bit for bit.
    #[test]
    fn band_without_is_the_band_of_the_others() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for n in [11usize, 40, 41, 200] {
            let mut v: Vec<f64> = (0..n)
                .map(|_| rng.sample::<f64, _>(StandardNormal))
                .collect();
            v.sort_by(f64::total_cmp);
            for skip in 0..n {
                let mut rest = v.clone();
                rest.remove(skip);
                assert_eq!(band_without(&v, skip), band(&rest), "n {n} skip {skip}");
            }
        }
    }

    #[test]
    fn too_few_experiments_or_no_cell_is_none() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        assert!(joint_check(&cells(&mut rng, 9, 5, 0.0, &[0.0; 5])).is_none());
        assert!(joint_check(&[]).is_none());
    }
}
