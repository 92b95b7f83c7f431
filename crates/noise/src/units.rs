//! Units as spec sheets write them: `"0.2 deg/sqrt(h)"`, `"70 deg/h"`, `"0.004 m/s^2/sqrt(Hz)"`,
//! `"40 ug/sqrt(Hz)"`, parsed into SI for a given quantity.
//!
//! A unit expression is a product of atoms (`deg`, `s`, `Hz`, `g`, `ppm`, ...), each with an optional
//! power (`s^2`, `h^-1`), `sqrt(..)` or `√..`, joined by `/`, `*` or `·`. Its dimension is tracked as
//! half-integer powers of angle, length, time and temperature, so `deg/sqrt(h)` and `rad/s/sqrt(Hz)`
//! are both recognised as angle·time^-1/2 and a unit that does not fit the quantity is an error.
//!
//! Conversion constants: degree = pi/180 rad; arc-second = pi/648000 rad; h = 3600 s;
//! g = 9.80665 m/s^2 (standard gravity, docs/cli.md); ppm = 1e-6; % = 1e-2. Temperature intervals
//! in degC or K are equal (a coefficient per degC is a coefficient per K).

use std::fmt;

/// Standard gravity in m/s^2 (the `g` unit and the static level accelerometer reading).
pub const STANDARD_GRAVITY_MPS2: f64 = 9.80665;

/// Dimension as doubled exponents (so half powers stay integers): angle, length, time, temperature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Dim {
    pub angle2: i32,
    pub length2: i32,
    pub time2: i32,
    pub temp2: i32,
}

impl Dim {
    pub const NONE: Dim = Dim::new(0, 0, 0, 0);
    /// Exponents in whole units (doubled internally).
    pub const fn new(angle: i32, length: i32, time: i32, temp: i32) -> Dim {
        Dim {
            angle2: 2 * angle,
            length2: 2 * length,
            time2: 2 * time,
            temp2: 2 * temp,
        }
    }
    const fn mul(self, o: Dim) -> Dim {
        Dim {
            angle2: self.angle2 + o.angle2,
            length2: self.length2 + o.length2,
            time2: self.time2 + o.time2,
            temp2: self.temp2 + o.temp2,
        }
    }
    /// Raise to the power p/2.
    fn pow_half(self, p2: i32) -> Option<Dim> {
        let f = |e: i32| -> Option<i32> {
            let x = e * p2;
            (x % 2 == 0).then_some(x / 2)
        };
        Some(Dim {
            angle2: f(self.angle2)?,
            length2: f(self.length2)?,
            time2: f(self.time2)?,
            temp2: f(self.temp2)?,
        })
    }
    /// Multiply by time^(half_powers/2).
    pub const fn with_time_half(self, half_powers: i32) -> Dim {
        Dim {
            time2: self.time2 + half_powers,
            ..self
        }
    }
    pub const fn over_temperature(self) -> Dim {
        Dim {
            temp2: self.temp2 - 2,
            ..self
        }
    }
}

impl fmt::Display for Dim {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        for (name, e2) in [
            ("rad", self.angle2),
            ("m", self.length2),
            ("s", self.time2),
            ("K", self.temp2),
        ] {
            match e2 {
                0 => {}
                2 => parts.push(name.to_string()),
                e if e % 2 == 0 => parts.push(format!("{name}^{}", e / 2)),
                e => parts.push(format!("{name}^{}", e as f64 / 2.0)),
            }
        }
        if parts.is_empty() {
            write!(f, "dimensionless")
        } else {
            write!(f, "{}", parts.join("·"))
        }
    }
}

/// What a configured value is: the quantity kinds a sensor config uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// The sensor's output signal: rad/s (gyro) or m/s^2 (accel).
    Signal(Signal),
    /// White-noise density N (ARW / VRW): signal·sqrt(s).
    NoiseDensity(Signal),
    /// Random-walk density K (RRW / acceleration random walk): signal/sqrt(s).
    RandomWalk(Signal),
    /// Ramp R: signal/s.
    Ramp(Signal),
    /// Quantisation coefficient Q of the integrated output: rad (gyro) or m/s (accel).
    Integrated(Signal),
    /// Temperature coefficient: signal per degC.
    PerDegree(Signal),
    /// Small angle (misalignment): rad.
    Angle,
    /// Dimensionless ratio (scale-factor error): 1.
    Ratio,
    /// Time: s.
    Time,
    /// Frequency: Hz.
    Frequency,
    /// Temperature difference / level: degC.
    Temperature,
    /// Temperature rate: degC/s.
    TemperatureRate,
}

/// The two signal kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    /// rad/s
    AngularRate,
    /// m/s^2
    Acceleration,
}

impl Quantity {
    /// SI dimension of the quantity.
    pub fn dim(self) -> Dim {
        let sig = |s: Signal| match s {
            Signal::AngularRate => Dim::new(1, 0, -1, 0),
            Signal::Acceleration => Dim::new(0, 1, -2, 0),
        };
        match self {
            Quantity::Signal(s) => sig(s),
            Quantity::NoiseDensity(s) => sig(s).with_time_half(1),
            Quantity::RandomWalk(s) => sig(s).with_time_half(-1),
            Quantity::Ramp(s) => sig(s).with_time_half(-2),
            Quantity::Integrated(s) => sig(s).with_time_half(2),
            Quantity::PerDegree(s) => sig(s).over_temperature(),
            Quantity::Angle => Dim::new(1, 0, 0, 0),
            Quantity::Ratio => Dim::NONE,
            Quantity::Time => Dim::new(0, 0, 1, 0),
            Quantity::Frequency => Dim::new(0, 0, -1, 0),
            Quantity::Temperature => Dim::new(0, 0, 0, 1),
            Quantity::TemperatureRate => Dim::new(0, 0, -1, 1),
        }
    }

    /// The SI unit the value is converted to (and written back in), e.g. `rad/s/sqrt(Hz)`.
    pub fn si_unit(self) -> &'static str {
        use Signal::*;
        match self {
            Quantity::Signal(AngularRate) => "rad/s",
            Quantity::Signal(Acceleration) => "m/s^2",
            Quantity::NoiseDensity(AngularRate) => "rad/s/sqrt(Hz)",
            Quantity::NoiseDensity(Acceleration) => "m/s^2/sqrt(Hz)",
            Quantity::RandomWalk(AngularRate) => "rad/s/sqrt(s)",
            Quantity::RandomWalk(Acceleration) => "m/s^2/sqrt(s)",
            Quantity::Ramp(AngularRate) => "rad/s^2",
            Quantity::Ramp(Acceleration) => "m/s^3",
            Quantity::Integrated(AngularRate) => "rad",
            Quantity::Integrated(Acceleration) => "m/s",
            Quantity::PerDegree(AngularRate) => "rad/s/degC",
            Quantity::PerDegree(Acceleration) => "m/s^2/degC",
            Quantity::Angle => "rad",
            Quantity::Ratio => "1",
            Quantity::Time => "s",
            Quantity::Frequency => "Hz",
            Quantity::Temperature => "degC",
            Quantity::TemperatureRate => "degC/s",
        }
    }

    /// An example a user can copy, for error messages.
    pub fn example(self) -> &'static str {
        use Signal::*;
        match self {
            Quantity::Signal(AngularRate) => "\"0.05 deg/s\" or \"70 deg/h\"",
            Quantity::Signal(Acceleration) => "\"0.2 mg\" or \"0.002 m/s^2\"",
            Quantity::NoiseDensity(AngularRate) => "\"0.2 deg/sqrt(h)\" or \"0.05 deg/s/sqrt(Hz)\"",
            Quantity::NoiseDensity(Acceleration) => {
                "\"0.004 m/s^2/sqrt(Hz)\" or \"40 ug/sqrt(Hz)\""
            }
            Quantity::RandomWalk(AngularRate) => "\"0.5 deg/h/sqrt(h)\"",
            Quantity::RandomWalk(Acceleration) => "\"10 ug/sqrt(s)\"",
            Quantity::Ramp(AngularRate) => "\"1 deg/h/h\"",
            Quantity::Ramp(Acceleration) => "\"1 ug/s\"",
            Quantity::Integrated(AngularRate) => "\"0.001 deg\"",
            Quantity::Integrated(Acceleration) => "\"0.0001 m/s\"",
            Quantity::PerDegree(AngularRate) => "\"0.01 deg/s/degC\"",
            Quantity::PerDegree(Acceleration) => "\"0.1 mg/degC\"",
            Quantity::Angle => "\"0.5 mrad\" or \"0.1 deg\"",
            Quantity::Ratio => "\"300 ppm\" or \"0.1 %\"",
            Quantity::Time => "\"100 s\" or \"2 h\"",
            Quantity::Frequency => "\"0.5 Hz\"",
            Quantity::Temperature => "\"25 degC\"",
            Quantity::TemperatureRate => "\"0.01 degC/s\"",
        }
    }
}

/// Why a value string could not be read.
#[derive(Clone, Debug, PartialEq)]
pub enum UnitError {
    /// No number at the start.
    NoNumber,
    /// The number is NaN or infinite.
    NotFinite,
    /// The unit expression has a syntax error or an unknown atom.
    BadUnit(String),
    /// The unit parses but has the wrong dimension.
    WrongDimension { unit: String, found: Dim, want: Dim },
}

impl fmt::Display for UnitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UnitError::NoNumber => write!(f, "no number at the start of the value"),
            UnitError::NotFinite => write!(f, "the number is not finite"),
            UnitError::BadUnit(m) => write!(f, "{m}"),
            UnitError::WrongDimension { unit, found, want } => write!(
                f,
                "unit `{unit}` is {found}, which does not fit a quantity in {want}"
            ),
        }
    }
}

/// Parse `"<number> <unit>"` into SI for `quantity`. For a `Ratio` a bare number is allowed.
pub fn parse_quantity(text: &str, quantity: Quantity) -> Result<f64, UnitError> {
    let text = text.trim();
    let split = number_prefix_len(text);
    if split == 0 {
        let lower = text.trim_start_matches(['+', '-']).to_ascii_lowercase();
        if lower.starts_with("nan") || lower.starts_with("inf") {
            return Err(UnitError::NotFinite);
        }
        return Err(UnitError::NoNumber);
    }
    let value: f64 = text[..split].parse().map_err(|_| UnitError::NoNumber)?;
    if !value.is_finite() {
        return Err(UnitError::NotFinite);
    }
    let unit_text = text[split..].trim();
    let (factor, offset, dim) = if unit_text.is_empty() {
        (1.0, 0.0, Dim::NONE)
    } else {
        let u = parse_unit(unit_text)?;
        (u.factor, u.offset, u.dim)
    };
    let want = quantity.dim();
    if dim != want {
        return Err(UnitError::WrongDimension {
            unit: if unit_text.is_empty() {
                "(none)".into()
            } else {
                unit_text.into()
            },
            found: dim,
            want,
        });
    }
    // Offsets only matter for absolute temperatures (K -> degC).
    let si = value * factor
        + if quantity == Quantity::Temperature {
            offset
        } else {
            0.0
        };
    if !si.is_finite() {
        return Err(UnitError::NotFinite);
    }
    Ok(si)
}

/// A time as a person gives it, s: a bare number is seconds, otherwise a value with its unit
/// (`"60"`, `"90 s"`, `"5 min"`, `"12 h"`); finite and >= 0. The message says what is expected
/// (a front end puts the setting's name before it).
pub fn duration_or_zero_s(text: &str) -> Result<f64, String> {
    let duration_s = match text.trim().parse::<f64>() {
        Ok(v) => v,
        Err(_) => parse_quantity(text, Quantity::Time)
            .map_err(|e| format!("expected seconds or a time such as \"12 h\" ({e})"))?,
    };
    if !(duration_s.is_finite() && duration_s >= 0.0) {
        return Err("expected a time >= 0".into());
    }
    Ok(duration_s)
}

/// As [`duration_or_zero_s`], and > 0.
pub fn duration_s(text: &str) -> Result<f64, String> {
    let duration_s = duration_or_zero_s(text)?;
    if duration_s == 0.0 {
        return Err("expected a time > 0".into());
    }
    Ok(duration_s)
}

/// Format an SI value so that `parse_quantity` gives back the same bits.
pub fn format_si(value: f64, quantity: Quantity) -> String {
    // `{:?}` prints the shortest representation that round-trips; SI units have factor 1.
    format!("{value:?} {}", quantity.si_unit())
}

/// The unit part of a config value ("0.15 deg/sqrt(h)" -> "deg/sqrt(h)"); empty when none.
pub fn unit_part(text: &str) -> &str {
    let text = text.trim();
    &text[number_prefix_len(text)..]
}

fn number_prefix_len(s: &str) -> usize {
    let b = s.as_bytes();
    let mut i = 0;
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let start_digits = i;
    while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
        i += 1;
    }
    if i == start_digits {
        return 0;
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        let exp_digits = j;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        if j > exp_digits {
            i = j;
        }
    }
    i
}

struct Unit {
    factor: f64,
    offset: f64,
    dim: Dim,
}

fn atom(name: &str) -> Option<(f64, Dim)> {
    use std::f64::consts::PI;
    let angle = Dim::new(1, 0, 0, 0);
    let length = Dim::new(0, 1, 0, 0);
    let time = Dim::new(0, 0, 1, 0);
    let freq = Dim::new(0, 0, -1, 0);
    let accel = Dim::new(0, 1, -2, 0);
    let temp = Dim::new(0, 0, 0, 1);
    let deg = PI / 180.0;
    Some(match name {
        "rad" => (1.0, angle),
        "mrad" => (1e-3, angle),
        "urad" | "µrad" => (1e-6, angle),
        // `º` (the ordinal indicator) is often typed for the degree sign.
        "deg" | "°" | "º" => (deg, angle),
        "arcmin" => (deg / 60.0, angle),
        "arcsec" => (deg / 3600.0, angle),
        "m" => (1.0, length),
        "mm" => (1e-3, length),
        "s" | "sec" => (1.0, time),
        "ms" => (1e-3, time),
        "us" | "µs" => (1e-6, time),
        "min" => (60.0, time),
        "h" | "hr" => (3600.0, time),
        "Hz" => (1.0, freq),
        "kHz" => (1e3, freq),
        "mHz" => (1e-3, freq),
        "g" => (STANDARD_GRAVITY_MPS2, accel),
        "mg" => (1e-3 * STANDARD_GRAVITY_MPS2, accel),
        "ug" | "µg" => (1e-6 * STANDARD_GRAVITY_MPS2, accel),
        "dps" => (deg, Dim::new(1, 0, -1, 0)),
        "dph" => (deg / 3600.0, Dim::new(1, 0, -1, 0)),
        "degC" | "°C" | "C" | "K" => (1.0, temp),
        "ppm" => (1e-6, Dim::NONE),
        "%" => (1e-2, Dim::NONE),
        "1" => (1.0, Dim::NONE),
        _ => return None,
    })
}

/// Recursive-descent parser over: product := factor (('/'|'*'|'·') factor)*;
/// factor := ('sqrt(' product ')' | '√' factor | '(' product ')' | atom) ('^' int)?
struct Parser<'a> {
    s: &'a str,
    pos: usize,
    /// Nesting depth of parentheses and roots: bounded so no input can exhaust the stack.
    depth: usize,
}

/// Deepest nesting of parentheses and roots a unit may have (real units need two or three).
const MAX_UNIT_DEPTH: usize = 16;
/// Largest integer power a unit may carry (`m/s^2`, `Hz^-1`; nothing needs more).
const MAX_UNIT_POWER: i32 = 8;

impl<'a> Parser<'a> {
    fn peek(&self) -> Option<char> {
        self.s[self.pos..].chars().next()
    }
    fn skip_ws(&mut self) {
        while let Some(c) = self.peek() {
            if c.is_whitespace() {
                self.pos += c.len_utf8();
            } else {
                break;
            }
        }
    }
    fn err(&self, what: &str) -> UnitError {
        UnitError::BadUnit(format!(
            "cannot read unit `{}` at `{}`: {what}",
            self.s,
            &self.s[self.pos..]
        ))
    }
    fn product(&mut self) -> Result<Unit, UnitError> {
        let mut acc = self.factor()?;
        loop {
            self.skip_ws();
            let op = match self.peek() {
                Some(c @ ('/' | '*' | '·')) => c,
                _ => return Ok(acc),
            };
            self.pos += op.len_utf8();
            let rhs = self.factor()?;
            if op == '/' {
                acc.factor /= rhs.factor;
                acc.dim = acc.dim.mul(rhs.dim.pow_half(-2).expect("integer power"));
            } else {
                acc.factor *= rhs.factor;
                acc.dim = acc.dim.mul(rhs.dim);
            }
            acc.offset = 0.0;
        }
    }
    fn factor(&mut self) -> Result<Unit, UnitError> {
        self.depth += 1;
        if self.depth > MAX_UNIT_DEPTH {
            return Err(self.err(&format!(
                "more than {MAX_UNIT_DEPTH} nested parentheses or roots"
            )));
        }
        let u = self.factor_inner();
        self.depth -= 1;
        u
    }
    /// One factor: a base (a root, a parenthesised product or a named unit) and its power.
    fn factor_inner(&mut self) -> Result<Unit, UnitError> {
        self.skip_ws();
        let mut u = self.base()?;
        self.skip_ws();
        if let Some(p) = self.power()? {
            u.factor = u.factor.powi(p);
            u.dim = u.dim.pow_half(2 * p).expect("integer power");
            u.offset = 0.0;
        }
        Ok(u)
    }

    /// `sqrt(..)` / `rt(..)` (the datasheet shorthand), `√..`, `(..)` or a named unit.
    fn base(&mut self) -> Result<Unit, UnitError> {
        let rest = &self.s[self.pos..];
        let root_len = if rest.starts_with("sqrt(") {
            5
        } else if rest.starts_with("rt(") {
            3
        } else {
            0
        };
        if root_len > 0 {
            self.pos += root_len;
            let inner = self.closed_product()?;
            sqrt_unit(inner, self)
        } else if rest.starts_with('√') {
            self.pos += '√'.len_utf8();
            let inner = self.factor()?;
            sqrt_unit(inner, self)
        } else if rest.starts_with('(') {
            self.pos += 1;
            self.closed_product()
        } else {
            self.named()
        }
    }

    /// A product and the `)` that closes it (the opening one already read).
    fn closed_product(&mut self) -> Result<Unit, UnitError> {
        let inner = self.product()?;
        self.skip_ws();
        if self.peek() != Some(')') {
            return Err(self.err("expected `)`"));
        }
        self.pos += 1;
        Ok(inner)
    }

    /// A unit's name ([`atom`]), or `rt` and a name (`rtHz`, `rth`: the root of that unit).
    fn named(&mut self) -> Result<Unit, UnitError> {
        let rest = &self.s[self.pos..];
        let len: usize = rest
            .char_indices()
            .find(|&(_, c)| {
                !(c.is_alphanumeric() || matches!(c, '%' | '°' | 'º' | 'µ'))
                    || matches!(c, '²' | '³')
            })
            .map(|(i, _)| i)
            .unwrap_or(rest.len());
        let name = &rest[..len];
        if name.is_empty() {
            return Err(self.err("expected a unit name"));
        }
        let unknown = || {
            self.err(&format!(
                "unknown unit `{name}` (known: rad mrad urad deg arcmin arcsec m mm s ms us min h Hz kHz mHz g mg ug dps dph degC K ppm %, with sqrt(..), √.., rt.. for roots, e.g. \"0.05 deg/s/sqrt(Hz)\", \"0.2 °/√h\", \"40 ug/rtHz\")"
            ))
        };
        let (factor, dim, root) = match atom(name) {
            Some((f, d)) => (f, d, false),
            None => match name.strip_prefix("rt").and_then(atom) {
                Some((f, d)) => (f, d, true),
                None => return Err(unknown()),
            },
        };
        self.pos += len;
        let unit = Unit {
            factor,
            offset: if name == "K" { -273.15 } else { 0.0 },
            dim,
        };
        if root {
            sqrt_unit(unit, self)
        } else {
            Ok(unit)
        }
    }

    /// `^N` (an integer from -MAX_UNIT_POWER to MAX_UNIT_POWER), `²`, `³`, or none.
    fn power(&mut self) -> Result<Option<i32>, UnitError> {
        Ok(match self.peek() {
            Some('^') => {
                self.pos += 1;
                self.skip_ws();
                let rest = &self.s[self.pos..];
                let len = number_prefix_len(rest);
                let p: i32 = rest[..len]
                    .parse()
                    .ok()
                    .filter(|p: &i32| (-MAX_UNIT_POWER..=MAX_UNIT_POWER).contains(p))
                    .ok_or_else(|| {
                        self.err(&format!(
                            "expected an integer power from -{MAX_UNIT_POWER} to {MAX_UNIT_POWER}"
                        ))
                    })?;
                self.pos += len;
                Some(p)
            }
            Some('²') => {
                self.pos += '²'.len_utf8();
                Some(2)
            }
            Some('³') => {
                self.pos += '³'.len_utf8();
                Some(3)
            }
            _ => None,
        })
    }
}

fn sqrt_unit(inner: Unit, p: &Parser) -> Result<Unit, UnitError> {
    let dim = inner
        .dim
        .pow_half(1)
        .ok_or_else(|| p.err("square root of a unit with a half power"))?;
    Ok(Unit {
        factor: inner.factor.sqrt(),
        offset: 0.0,
        dim,
    })
}

fn parse_unit(text: &str) -> Result<Unit, UnitError> {
    let mut p = Parser {
        s: text,
        pos: 0,
        depth: 0,
    };
    let u = p.product()?;
    p.skip_ws();
    if p.pos != text.len() {
        return Err(p.err("unexpected text"));
    }
    Ok(u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn datasheet_spellings_of_roots_and_degrees() {
        let arw = Quantity::NoiseDensity(Signal::AngularRate);
        let want = parse_quantity("0.05 deg/s/sqrt(Hz)", arw).unwrap();
        for text in [
            "0.05 deg/s/rtHz",
            "0.05 deg/s/rt(Hz)",
            "0.05 °/s/√Hz",
            "0.05 º/s/√Hz",
            "0.05 dps/rtHz",
            "3 deg/rth",
            "3 °/√h",
            "3 deg/rt(hr)",
        ] {
            let v = parse_quantity(text, arw).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert!((v / want - 1.0).abs() < 1e-12, "{text}: {v} vs {want}");
        }
        let g = parse_quantity("9.80665 m/s²", Quantity::Signal(Signal::Acceleration)).unwrap();
        assert!((g - 9.80665).abs() < 1e-12);
        let bi = parse_quantity("36 dph", Quantity::Signal(Signal::AngularRate)).unwrap();
        assert!((bi - 0.01f64.to_radians()).abs() < 1e-15);
        let vrw =
            parse_quantity("40 ug/rtHz", Quantity::NoiseDensity(Signal::Acceleration)).unwrap();
        assert!((vrw - 40e-6 * STANDARD_GRAVITY_MPS2).abs() < 1e-15);
    }

    #[test]
    fn hostile_units_are_errors_not_crashes() {
        // 30 000 nested parentheses: an error naming the limit, not a stack overflow.
        let deep = format!("1 {}s{}", "(".repeat(30_000), ")".repeat(30_000));
        let e = parse_quantity(&deep, Quantity::Time)
            .unwrap_err()
            .to_string();
        assert!(e.contains("nested"), "{e}");
        let deep_roots = format!("1 {}Hz", "√".repeat(30_000));
        assert!(parse_quantity(&deep_roots, Quantity::Frequency).is_err());
        // An exponent that would wrap when doubled: refused.
        for text in ["1 rad/s^-2147483648", "1 s^2147483647", "1 s^99"] {
            let e = parse_quantity(text, Quantity::Time)
                .unwrap_err()
                .to_string();
            assert!(e.contains("integer power"), "{text}: {e}");
        }
    }
    use std::f64::consts::PI;
    use Signal::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1e-300)
    }

    #[test]
    fn spec_sheet_units_convert_to_si() {
        // docs/model.md §2 unit conversions: N[rad/sqrt(s)] = N[deg/sqrt(h)]·(pi/180)/60.
        let arw = parse_quantity("0.2 deg/sqrt(h)", Quantity::NoiseDensity(AngularRate)).unwrap();
        assert!(close(arw, 0.2 * PI / 180.0 / 60.0));
        let arw2 =
            parse_quantity("0.075 deg/sqrt(s)", Quantity::NoiseDensity(AngularRate)).unwrap();
        assert!(close(arw2, 0.075 * PI / 180.0));
        let nd =
            parse_quantity("0.05 deg/s/sqrt(Hz)", Quantity::NoiseDensity(AngularRate)).unwrap();
        assert!(close(nd, 0.05 * PI / 180.0));
        let bs = parse_quantity("70 deg/h", Quantity::Signal(AngularRate)).unwrap();
        assert!(close(bs, 70.0 * PI / 180.0 / 3600.0));
        let vrw =
            parse_quantity("0.004 m/s^2/sqrt(Hz)", Quantity::NoiseDensity(Acceleration)).unwrap();
        assert!(close(vrw, 0.004));
        let ug = parse_quantity("40 ug/sqrt(Hz)", Quantity::NoiseDensity(Acceleration)).unwrap();
        assert!(close(ug, 40e-6 * STANDARD_GRAVITY_MPS2));
        // VRW[m/s/sqrt(h)] = 60·VRW[m/s/sqrt(s)] (docs/model.md §2).
        let vrw_h =
            parse_quantity("0.6 m/s/sqrt(h)", Quantity::NoiseDensity(Acceleration)).unwrap();
        assert!(close(vrw_h, 0.01));
        // K[deg/h/sqrt(h)] -> rad/s/sqrt(s): multiply by (pi/180)/3600/60 (docs/model.md §2).
        let k = parse_quantity("1 deg/h/sqrt(h)", Quantity::RandomWalk(AngularRate)).unwrap();
        assert!(close(k, PI / 180.0 / 3600.0 / 60.0));
        let ramp = parse_quantity("1 deg/h/h", Quantity::Ramp(AngularRate)).unwrap();
        assert!(close(ramp, PI / 180.0 / 3600.0 / 3600.0));
        let unicode = parse_quantity("0.2 °/√h", Quantity::NoiseDensity(AngularRate)).unwrap();
        assert!(close(unicode, arw));
        assert!(close(
            parse_quantity("300 ppm", Quantity::Ratio).unwrap(),
            300e-6
        ));
        assert!(close(
            parse_quantity("0.001", Quantity::Ratio).unwrap(),
            1e-3
        ));
        assert!(close(
            parse_quantity("298.15 K", Quantity::Temperature).unwrap(),
            25.0
        ));
        assert!(close(
            parse_quantity("2 h", Quantity::Time).unwrap(),
            7200.0
        ));
    }

    #[test]
    fn wrong_units_are_rejected() {
        assert!(matches!(
            parse_quantity("0.2 deg/h", Quantity::NoiseDensity(AngularRate)),
            Err(UnitError::WrongDimension { .. })
        ));
        assert!(matches!(
            parse_quantity("0.004 m/s^2/sqrt(Hz)", Quantity::NoiseDensity(AngularRate)),
            Err(UnitError::WrongDimension { .. })
        ));
        assert!(matches!(
            parse_quantity("0.2", Quantity::NoiseDensity(AngularRate)),
            Err(UnitError::WrongDimension { .. })
        ));
        assert!(matches!(
            parse_quantity("deg/h", Quantity::Signal(AngularRate)),
            Err(UnitError::NoNumber)
        ));
        assert!(matches!(
            parse_quantity("1 furlong", Quantity::Signal(AngularRate)),
            Err(UnitError::BadUnit(_))
        ));
        assert!(parse_quantity("1e400 deg/s", Quantity::Signal(AngularRate)).is_err());
        for bad in ["NaN deg/s", "-inf deg/s", "inf"] {
            assert_eq!(
                parse_quantity(bad, Quantity::Signal(AngularRate)),
                Err(UnitError::NotFinite)
            );
        }
    }

    #[test]
    fn si_formatting_round_trips_bit_for_bit() {
        for &q in &[
            Quantity::NoiseDensity(AngularRate),
            Quantity::RandomWalk(Acceleration),
            Quantity::Integrated(Acceleration),
            Quantity::PerDegree(AngularRate),
            Quantity::Ratio,
            Quantity::Temperature,
            Quantity::TemperatureRate,
        ] {
            for v in [1.2345678901234567e-7, -3.0, 0.1 + 0.2] {
                let back = parse_quantity(&format_si(v, q), q).unwrap();
                assert_eq!(back.to_bits(), v.to_bits(), "{q:?} {v}");
            }
        }
    }
}
