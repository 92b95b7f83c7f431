//! Numbers for people, shared by every crate's messages and by the front ends' tables:
//! significant digits, engineering notation with SI prefixes, times, and the units spec sheets
//! use for Allan coefficients. JSON and CSV stay in SI; only human text uses these.

/// `v` with `digits` significant digits as a plain decimal ("0.0259", "226.7", "1480"), falling
/// back to scientific notation outside 1e-4 ..= 1e7. NaN prints as "NaN" (never as 0). The
/// reader's messages use it; so do the command line's tables.
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

/// `v` (in `unit`) in engineering notation with an SI prefix (femto to kilo) and 4 significant digits:
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
    // Kilo is the largest prefix: "22360 km" reads better than "22.36 Mm" (easily taken for mm).
    let exp3 = ((v.abs().log10() / 3.0).floor() as i32 * 3).clamp(-15, 3);
    let prefix = PREFIXES
        .iter()
        .find(|(e, _)| *e == exp3)
        .map_or("", |(_, p)| p);
    let scaled = v / 10f64.powi(exp3);
    // Rounding can carry 999.95 to 1000.0: print it as 1000 rather than switch prefix mid-table.
    format!("{} {prefix}{unit}", sig(scaled, 4))
}

/// A time in seconds, compactly: "0.1 s", "60 s", "10 min", "1 h".
pub fn time(t_s: f64) -> String {
    if t_s >= 3600.0 && (t_s / 3600.0).fract() == 0.0 {
        format!("{} h", t_s / 3600.0)
    } else if t_s >= 60.0 && (t_s / 60.0).fract() == 0.0 && t_s < 3600.0 {
        format!("{} min", t_s / 60.0)
    } else {
        format!("{} s", trimmed(t_s, 4))
    }
}

/// A number with at most `digits` significant digits and no trailing zeros after the point
/// ("200" for 199.99999995867375, "0.6827" for 0.6826894921370859 with 4).
pub fn trimmed(v: f64, digits: usize) -> String {
    let text = sig(v, digits);
    if text.contains('.') && !text.contains('e') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// A sample rate as people write it: 7 significant digits at most ("200 Hz", "99.8 Hz"); a
/// rate from timestamps carries their rounding far below that.
pub fn rate(hz: f64) -> String {
    format!("{} Hz", trimmed(hz, 7))
}

/// A log's sampling for messages: "100 Hz, a sample every 0.01 s".
pub fn sampling(dt_s: f64) -> String {
    format!("{}, a sample every {}", si(1.0 / dt_s, "Hz"), time(dt_s))
}

/// Display scale and unit for an Allan deviation and the five IEEE 952 coefficients (Q, N, B, K,
/// R) of a channel whose SI unit is `si_unit`, as spec sheets write them: gyro deg/h, arcsec,
/// deg/sqrt(h), deg/h, deg/h/sqrt(h), deg/h^2; accelerometer ug, m/s, m/s/sqrt(h), ug. A value
/// in SI times the scale is in the unit (IEEE Std 952-1997 Annex C gives Q in arcsec).
pub fn allan_units(si_unit: &str) -> [(f64, String); 6] {
    let deg = 180.0 / std::f64::consts::PI;
    let g = crate::units::STANDARD_GRAVITY_MPS2;
    match si_unit {
        "rad/s" => [
            (deg * 3600.0, "deg/h".into()),
            // Q (rad): deg/h x s is deg/3600, an arcsecond (IEEE 952 gives Q in arcsec).
            (deg * 3600.0, "arcsec".into()),
            (deg * 60.0, "deg/sqrt(h)".into()),
            (deg * 3600.0, "deg/h".into()),
            (deg * 3600.0 * 60.0, "deg/h/sqrt(h)".into()),
            (deg * 3600.0 * 3600.0, "deg/h^2".into()),
        ],
        "m/s^2" => [
            (1e6 / g, "ug".into()),
            (1.0, "m/s".into()),
            (60.0, "m/s/sqrt(h)".into()),
            (1e6 / g, "ug".into()),
            (1e6 / g, "ug/sqrt(s)".into()),
            (1e6 / g, "ug/s".into()),
        ],
        other => [
            (1.0, other.to_string()),
            (1.0, format!("{other}*s")),
            (1.0, format!("{other}*sqrt(s)")),
            (1.0, other.to_string()),
            (1.0, format!("{other}/sqrt(s)")),
            (1.0, format!("{other}/s")),
        ],
    }
}

/// A white-noise coefficient N (SI: rad/sqrt(s) or m/s^2*sqrt(s), i.e. per sqrt(Hz)) as the other
/// unit datasheets use for it: a gyro's rate noise density in deg/s/sqrt(Hz), an accelerometer's
/// noise density in ug/sqrt(Hz) (1 ug = 9.80665e-6 m/s^2, the standard gravity of
/// [`crate::units`]). `None` for other units.
pub fn noise_density_alt(si_unit: &str, v: f64) -> Option<String> {
    match si_unit {
        "rad/s" => Some(format!("{} deg/s/sqrt(Hz)", sig(v.to_degrees(), 4))),
        "m/s^2" => Some(format!(
            "{} ug/sqrt(Hz)",
            sig(v / crate::units::STANDARD_GRAVITY_MPS2 * 1e6, 4)
        )),
        _ => None,
    }
}

/// An error and its causes joined by ": ", as the command line prints an error (`{e:#}`).
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cause = c.source();
    }
    s
}
