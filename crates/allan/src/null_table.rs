//! The null thresholds' shipped table ([`crate::null::tabulated_thresholds`]): the upper tail of
//! the five term statistics, simulated once over log lengths for the analyses users run by default
//! (adev, oadev and totdev on the octave and decade grids, Greenhall EDF, Stable32 stop ratio),
//! and looked up by interpolation instead of simulating null logs on every call.
//!
//! Where the table holds, the statistic's null depends on the log only through its length n:
//! not on the sample values (the statistic is scale-free), the sample interval (the fit's basis
//! columns scale by powers of tau0, which the Wald ratio ignores) or the confidence level (it sets
//! the intervals, not the EDF or the fit): crates/allan/tests/null_table.rs checks each.
//!
//! Layout. The grid's factors m_0 < m_1 < ... (octave 1, 2, 4, ...; decade 1, 2, 4, 10, ...) are
//! cut at n / ratio (Stable32's stop ratio, [`Estimator::stable32_stop_ratio`]), so the number of
//! points is constant on the segments n in [ratio m_s, ratio m_{s+1}): a new top point with few
//! degrees of freedom appears at each segment's start. A length is located by its segment s and
//! its position f = ln(n / (ratio m_s)) / ln(m_{s+1} / m_s) in [0, 1); the table holds four nodes
//! per segment (f = 0, 1/3, 2/3 and the segment's last n), and a length between nodes gets the
//! linear interpolation in f of the tail's start and scale, never across a segment's start.
//! Beyond the table's top the grid repeats its shape (octave every segment, decade every three)
//! and the statistic's null converges (the top points set the K, R and B statistics, the
//! bottom points the Q and N ones, whose estimates only sharpen): a length there is read at the
//! same position of the table's top period, and tests/null_table.rs compares the last two
//! periods and a full simulation beyond the top.

use crate::{Estimator, TauGrid};

/// One tabulated length: the tail of the null statistics of Q, N, B, K, R there
/// ([`crate::null::tail_of`]).
#[derive(Clone, Copy, Debug)]
pub struct Row {
    /// Rate samples in the log.
    pub n: usize,
    /// Empirical (1 - TAIL_SHARE) quantile of each statistic.
    pub start: [f64; 5],
    /// Mean excess beyond it.
    pub scale: [f64; 5],
}

/// The grids the table covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grid {
    Octave,
    Decade,
}

impl Grid {
    /// The table's grid for `grid`, if it has one.
    pub fn of(grid: &TauGrid) -> Option<Grid> {
        match grid {
            TauGrid::Octave => Some(Grid::Octave),
            TauGrid::Decade => Some(Grid::Decade),
            _ => None,
        }
    }

    /// The library's grid.
    pub fn tau_grid(self) -> TauGrid {
        match self {
            Grid::Octave => TauGrid::Octave,
            Grid::Decade => TauGrid::Decade,
        }
    }

    /// Segments per repetition of the grid's shape.
    pub fn period(self) -> usize {
        match self {
            Grid::Octave => 1,
            Grid::Decade => 3,
        }
    }

    /// The grid's factors m_0 < m_1 < ... below 2^60.
    pub fn factors(self) -> Vec<usize> {
        self.tau_grid().ms(1 << 60)
    }
}

/// The table of one estimator on one grid.
#[derive(Clone, Copy, Debug)]
pub struct Family {
    pub est: Estimator,
    pub grid: Grid,
    /// Null logs simulated per row.
    pub replicates: usize,
    /// Rows by increasing n.
    pub rows: &'static [Row],
}

/// The segment s and position f of a log of `n` rate samples (module docs); `None` below the
/// first segment (fewer than `ratio` samples: no averaging factor).
pub fn position(n: usize, ratio: usize, factors: &[usize]) -> Option<(usize, f64)> {
    let s = factors
        .windows(2)
        .position(|w| ratio * w[0] <= n && n < ratio * w[1])?;
    let (lo, hi) = (factors[s] as f64, factors[s + 1] as f64);
    Some((s, (n as f64 / (ratio as f64 * lo)).ln() / (hi / lo).ln()))
}

/// The nodes tabulated in segment `s`: f = 0, 1/3, 2/3 (rounded to whole samples) and the
/// segment's last length.
pub fn nodes(s: usize, ratio: usize, factors: &[usize]) -> Vec<usize> {
    let (lo, end) = (ratio * factors[s], ratio * factors[s + 1]);
    let mut v: Vec<usize> = (0..3)
        .map(|j| (lo as f64 * (end as f64 / lo as f64).powf(j as f64 / 3.0)).round() as usize)
        .chain([end - 1])
        .map(|n| n.clamp(lo, end - 1))
        .collect();
    v.dedup();
    v
}

impl Family {
    /// The tail at `n` rate samples: interpolated within n's segment, read at the same position
    /// of the top period beyond the table (module docs). `None` below the first segment.
    pub fn tail_at(&self, n: usize) -> Option<([f64; 5], [f64; 5])> {
        let ratio = self.est.stable32_stop_ratio();
        let factors = self.grid.factors();
        let (s, f) = position(n, ratio, &factors)?;
        let top = position(self.rows.last()?.n, ratio, &factors)?.0;
        let p = self.grid.period();
        let s = if s > top {
            s - p * (s - top).div_ceil(p)
        } else {
            s
        };
        let seg: Vec<(f64, &Row)> = self
            .rows
            .iter()
            .filter_map(|r| {
                let (rs, rf) = position(r.n, ratio, &factors)?;
                (rs == s).then_some((rf, r))
            })
            .collect();
        let (f0, first) = *seg.first()?;
        if f <= f0 {
            return Some((first.start, first.scale));
        }
        for w in seg.windows(2) {
            let ((fa, a), (fb, b)) = (w[0], w[1]);
            if f <= fb {
                let x = (f - fa) / (fb - fa);
                let lerp = |u: &[f64; 5], v: &[f64; 5]| -> [f64; 5] {
                    std::array::from_fn(|j| u[j] + x * (v[j] - u[j]))
                };
                return Some((lerp(&a.start, &b.start), lerp(&a.scale, &b.scale)));
            }
        }
        let last = seg.last()?.1;
        Some((last.start, last.scale))
    }
}
