//! Numbers for people: engineering notation with SI prefixes, significant digits, and the units
//! spec sheets use (deg rather than rad for attitude, deg/h and deg/sqrt(h) for gyro terms). JSON and CSV stay in SI; only human text uses these.

/// `v` with `digits` significant digits as a plain decimal ("0.0259", "226.7", "1480"), falling
/// back to scientific notation outside 1e-4 ..= 1e7. NaN prints as "NaN" (never as 0).
pub fn sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..7).contains(&mag) {
        return format!("{:.*e}", digits.saturating_sub(1), v);
    }
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{v:.decimals$}")
}

/// `v` (in `unit`) in engineering notation with an SI prefix and 4 significant digits:
/// `si(2.2667e2, "m")` = "226.7 m", `si(1.0224e-4, "m")` = "102.2 µm".
pub fn si(v: f64, unit: &str) -> String {
    const PREFIXES: [(i32, &str); 9] = [
        (-15, "f"),
        (-12, "p"),
        (-9, "n"),
        (-6, "µ"),
        (-3, "m"),
        (0, ""),
        (3, "k"),
        (6, "M"),
        (9, "G"),
    ];
    if !v.is_finite() || v == 0.0 {
        return format!("{} {unit}", sig(v, 4));
    }
    let exp3 = ((v.abs().log10() / 3.0).floor() as i32 * 3).clamp(-15, 9);
    let prefix = PREFIXES
        .iter()
        .find(|(e, _)| *e == exp3)
        .map_or("", |(_, p)| p);
    let scaled = v / 10f64.powi(exp3);
    // Rounding can carry 999.95 to 1000.0: print it as 1000 rather than switch prefix mid-table.
    format!("{} {prefix}{unit}", sig(scaled, 4))
}

/// A drift channel's value (SI, named as in the JSON: `_rad`, `_m`, `_mps`) as a person reads
/// it: angles in degrees, positions and velocities with SI prefixes.
pub fn channel_value(channel: &str, v_si: f64) -> String {
    if channel.ends_with("_rad") {
        format!("{} deg", sig(v_si.to_degrees(), 4))
    } else if channel.ends_with("_mps") {
        si(v_si, "m/s")
    } else if channel.ends_with("_m") {
        si(v_si, "m")
    } else {
        sig(v_si, 4)
    }
}

/// An optional channel value ("n/a" when absent).
pub fn channel_opt(channel: &str, v_si: Option<f64>) -> String {
    v_si.map_or_else(|| "n/a".into(), |v| channel_value(channel, v))
}

/// A time in seconds, compactly: "0.1 s", "60 s", "10 min", "1 h".
pub fn time(t_s: f64) -> String {
    if t_s >= 3600.0 && (t_s / 3600.0).fract() == 0.0 {
        format!("{} h", t_s / 3600.0)
    } else if t_s >= 60.0 && (t_s / 60.0).fract() == 0.0 && t_s < 3600.0 {
        format!("{} min", t_s / 60.0)
    } else {
        let text = sig(t_s, 4);
        let text = if text.contains('.') && !text.contains('e') {
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            text
        };
        format!("{text} s")
    }
}

/// Angle random walk (rad/sqrt(s)) as spec sheets write it, deg/sqrt(h).
pub fn arw(v_rad_per_sqrt_s: f64) -> String {
    format!(
        "{} deg/sqrt(h)",
        sig(v_rad_per_sqrt_s.to_degrees() * 60.0, 3)
    )
}

/// Gyro bias (rad/s) as spec sheets write it, deg/h.
pub fn gyro_bias(v_rad_per_s: f64) -> String {
    format!("{} deg/h", sig(v_rad_per_s.to_degrees() * 3600.0, 3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits_and_prefixes() {
        assert_eq!(sig(0.025909, 3), "0.0259");
        assert_eq!(sig(226.67, 4), "226.7");
        assert_eq!(sig(-8.8168e-4, 3), "-0.000882");
        assert_eq!(sig(1.5e-7, 3), "1.50e-7");
        assert_eq!(sig(f64::NAN, 3), "NaN");
        assert_eq!(si(226.67, "m"), "226.7 m");
        assert_eq!(si(1.0224e-4, "m"), "102.2 µm");
        assert_eq!(si(4.9218, "m"), "4.922 m");
        assert_eq!(si(0.0, "m"), "0 m");
        assert_eq!(si(2.4e6, "m"), "2.400 Mm");
        assert_eq!(channel_value("yaw_rad", std::f64::consts::PI), "180.0 deg");
        assert_eq!(channel_value("vel_horizontal_mps", 9.58), "9.580 m/s");
        assert_eq!(time(600.0), "10 min");
        assert_eq!(time(3600.0), "1 h");
        assert_eq!(time(0.1), "0.1 s");
        assert_eq!(time(45.96), "45.96 s");
        // Woodman Table 4 (MTx): 0.075 deg/sqrt(s) = 4.5 deg/sqrt(h).
        assert_eq!(arw(0.075f64.to_radians()), "4.50 deg/sqrt(h)");
        assert_eq!(gyro_bias(0.01f64.to_radians()), "36.0 deg/h");
    }
}
