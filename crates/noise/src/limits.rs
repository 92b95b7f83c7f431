//! The one definition of a sane value, shared by the model's terms, the generator, the log
//! readers (`logio`, which re-exports it) and the simulation: a value a sensor sample (or a
//! model's value in SI units) may have.

/// Largest magnitude a sample or a model value may have (exclusive). Analyses sum squares of
/// values and of their differences (the Allan variance, Allan 1966; least-squares fits): with
/// |x| < 1e100 a sum of 1e9 such squares stays below 1e210, far from the f64 overflow at 1.8e308
/// (IEEE 754), while 1e150 and more overflow. No sensor's reading (or time stamp) comes near.
pub const MAX_ABS_VALUE: f64 = 1e100;

/// Whether `v` is a value a sample may have: finite and of magnitude below [`MAX_ABS_VALUE`]
/// (NaN fails the comparison).
#[inline(always)]
pub fn valid_value(v: f64) -> bool {
    v.abs() < MAX_ABS_VALUE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sane_values_are_finite_and_below_1e100() {
        for v in [0.0, -1.0, 9.81, 1e99, -9.99e99, 5e-324] {
            assert!(valid_value(v), "{v}");
        }
        for v in [
            1e100,
            -1e100,
            1e150,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ] {
            assert!(!valid_value(v), "{v}");
        }
    }
}
