//! Numbers for people: engineering notation with SI prefixes, significant digits, and the units
//! spec sheets use (deg rather than rad for attitude, deg/h and deg/sqrt(h) for gyro terms). JSON and CSV stay in SI; only human text uses these.

/// `v` with `digits` significant digits as a plain decimal ("0.0259", "226.7", "1480"), falling
/// back to scientific notation outside 1e-4 ..= 1e7 (one definition, shared with the log
/// reader's messages).
pub use logio::sig;

/// Engineering notation, times, trimmed numbers, rates and the Allan units of spec sheets: one
/// definition in the noise crate (its messages and the libraries' use them too).
pub use noise::text::{allan_units, noise_density_alt, rate, si, time, trimmed};

/// A navigation-error quantity's value (SI, named as in the JSON: `_rad`, `_m`, `_mps`) as a person reads
/// it: angles in degrees, positions and velocities with SI prefixes.
pub fn quantity_value(quantity: &str, v_si: f64) -> String {
    if quantity.ends_with("_rad") {
        format!("{} deg", sig(v_si.to_degrees(), 4))
    } else if quantity.ends_with("_mps") {
        si(v_si, "m/s")
    } else if quantity.ends_with("_m") {
        si(v_si, "m")
    } else {
        sig(v_si, 4)
    }
}

/// A navigation-error quantity's name (as in the JSON) for titles: "heading" for `heading_rad`
/// and `yaw_rad`, "horizontal position" for `pos_horizontal_m` ...; other names as they are.
pub fn quantity_label(name: &str) -> String {
    let base = name
        .trim_end_matches("_rad")
        .trim_end_matches("_mps")
        .trim_end_matches("_m");
    let words: Vec<&str> = base.split('_').collect();
    match words.as_slice() {
        ["yaw"] | ["heading"] => "heading".into(),
        ["pos", axis] => format!("{axis} position"),
        ["vel", axis] => format!("{axis} velocity"),
        _ => base.replace('_', " "),
    }
}

/// An optional quantity value ("n/a" when absent).
pub fn quantity_opt(quantity: &str, v_si: Option<f64>) -> String {
    v_si.map_or_else(|| "n/a".into(), |v| quantity_value(quantity, v))
}

/// A size in bytes for people, binary units: "512 bytes", "3.5 KiB", "1.2 GiB" (never "0.0 GB";
/// one definition, shared with the log reader's messages).
pub use logio::byte_size as bytes;

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

/// A confidence level: "1-sigma (68.27 %)" for the one-sigma level, else "95 %".
pub fn confidence(level: f64) -> String {
    let pct = trimmed(100.0 * level, 4);
    if (level - allan::ONE_SIGMA_CI).abs() < 1e-9 {
        format!("1-sigma ({pct} %)")
    } else {
        format!("{pct} %")
    }
}

/// A text field of a CSV file: always quoted, an inner `"` doubled (RFC 4180 §2.7), so names and
/// notes with commas, quotes or line breaks stay one field. The one place CSV text is quoted.
pub fn csv_text(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_text_is_one_rfc4180_field() {
        assert_eq!(csv_text("Xsens MTx"), "\"Xsens MTx\"");
        assert_eq!(csv_text("a \"b\", c"), "\"a \"\"b\"\", c\"");
        assert_eq!(csv_text(""), "\"\"");
    }

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
        assert_eq!(si(2.4e6, "m"), "2400 km");
        assert_eq!(quantity_value("yaw_rad", std::f64::consts::PI), "180.0 deg");
        assert_eq!(quantity_value("vel_horizontal_mps", 9.58), "9.580 m/s");
        assert_eq!(time(600.0), "10 min");
        assert_eq!(time(3600.0), "1 h");
        assert_eq!(time(0.1), "0.1 s");
        assert_eq!(time(45.96), "45.96 s");
        assert_eq!(rate(199.99999995867375), "200 Hz");
        assert_eq!(rate(99.8), "99.8 Hz");
        assert_eq!(confidence(allan::ONE_SIGMA_CI), "1-sigma (68.27 %)");
        assert_eq!(confidence(0.95), "95 %");
        assert_eq!(
            noise_density_alt("m/s^2", 9.80665e-4).as_deref(),
            Some("100.0 ug/sqrt(Hz)")
        );
        // Woodman Table 4 (MTx): 0.075 deg/sqrt(s) = 4.5 deg/sqrt(h).
        assert_eq!(arw(0.075f64.to_radians()), "4.50 deg/sqrt(h)");
        assert_eq!(gyro_bias(0.01f64.to_radians()), "36.0 deg/h");
        // 0.075 deg/sqrt(s) is 4.5 deg/sqrt(h); 1 mg is 1000 ug; 1 m/s/sqrt(s) is 60 m/s/sqrt(h).
        let gy = allan_units("rad/s");
        assert!((0.075f64.to_radians() * gy[2].0 - 4.5).abs() < 1e-12);
        assert!((0.01f64.to_radians() * gy[0].0 - 36.0).abs() < 1e-12);
        let ac = allan_units("m/s^2");
        assert!((9.80665e-3 * ac[0].0 - 1000.0).abs() < 1e-9);
        assert_eq!((ac[2].0, ac[2].1.as_str()), (60.0, "m/s/sqrt(h)"));
    }
}
