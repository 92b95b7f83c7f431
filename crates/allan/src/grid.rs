//! Tau grids: which averaging factors m (tau = m * tau0) to evaluate.

use serde::{Deserialize, Serialize};

/// A set of averaging factors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum TauGrid {
    /// m = 1, 2, 4, 8, ... (allantools / Stable32 "octave").
    Octave,
    /// m = 1, 2, 4, 10, 20, 40, 100, ... (allantools / Stable32 "decade").
    Decade,
    /// About n log-spaced factors per decade: allantools `tau_reduction` of the "all" list
    /// (keep m where round(n log10 m) changes).
    PerDecade(u32),
    /// Every m = 1, 2, 3, ... (Stable32 "all tau").
    All,
    /// These m values, as given (sorted and deduplicated).
    Explicit(Vec<usize>),
}

impl TauGrid {
    /// Parse `octave`, `decade`, `all`, `N/decade` or `per-decade:N`, or a comma list of m values.
    pub fn parse(text: &str) -> Option<TauGrid> {
        let t = text.trim();
        match t {
            "octave" => return Some(TauGrid::Octave),
            "decade" => return Some(TauGrid::Decade),
            "all" => return Some(TauGrid::All),
            _ => {}
        }
        let per = t
            .strip_suffix("/decade")
            .or_else(|| t.strip_prefix("per-decade:"));
        if let Some(n) = per {
            return n
                .trim()
                .parse()
                .ok()
                .filter(|&n| n > 0)
                .map(TauGrid::PerDecade);
        }
        let ms: Option<Vec<usize>> = t.split(',').map(|s| s.trim().parse().ok()).collect();
        ms.filter(|v| !v.is_empty() && v.iter().all(|&m| m > 0))
            .map(TauGrid::Explicit)
    }

    /// Averaging factors below `n_phase` (the number of phase points), ascending, unique.
    pub fn ms(&self, n_phase: usize) -> Vec<usize> {
        let mut ms: Vec<usize> = match self {
            TauGrid::Octave => (0..usize::BITS)
                .map(|k| 1usize << k)
                .take_while(|&m| m < n_phase)
                .collect(),
            TauGrid::Decade => {
                let mut v = Vec::new();
                let mut p = 1usize;
                while p < n_phase {
                    for f in [1, 2, 4] {
                        v.push(p * f);
                    }
                    p = p.saturating_mul(10);
                }
                v
            }
            TauGrid::All => (1..n_phase).collect(),
            TauGrid::PerDecade(n) => {
                // allantools tau_reduction: keep m[i] when rint(n log10 m[i+1]) != rint(n log10 m[i]).
                let n = *n as f64;
                let key = |m: usize| (n * (m as f64).log10()).round_ties_even();
                (1..n_phase.saturating_sub(1))
                    .filter(|&m| key(m + 1) != key(m))
                    .collect()
            }
            TauGrid::Explicit(v) => v.clone(),
        };
        ms.retain(|&m| m >= 1 && m < n_phase);
        ms.sort_unstable();
        ms.dedup();
        ms
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids() {
        assert_eq!(TauGrid::Octave.ms(20), vec![1, 2, 4, 8, 16]);
        assert_eq!(
            TauGrid::Decade.ms(500),
            vec![1, 2, 4, 10, 20, 40, 100, 200, 400]
        );
        assert_eq!(TauGrid::All.ms(5), vec![1, 2, 3, 4]);
        let p = TauGrid::PerDecade(10).ms(10_000);
        // about 10 per decade, log-spaced
        let in_decade = p.iter().filter(|&&m| (100..1000).contains(&m)).count();
        assert!((9..=11).contains(&in_decade), "{in_decade}");
        assert_eq!(TauGrid::parse("5/decade"), Some(TauGrid::PerDecade(5)));
        assert_eq!(
            TauGrid::parse("1,2,8"),
            Some(TauGrid::Explicit(vec![1, 2, 8]))
        );
        assert_eq!(TauGrid::parse("0"), None);
    }
}
