//! The decimal parser of the CSV fast path (Clinger's exact fast path and an eight-digit SWAR
//! step, falling back to the standard parser): kept because it pays, and pinned bit for bit
//! against the standard parser by the reader's tests.

/// Powers of ten exactly representable in f64 (10^0 .. 10^22).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Decimal numbers `[+-]digits[.digits][(e|E)[+-]digits]` in one scan. With at most 19 digits
/// in all (leading zeros included, so the integer significand w cannot overflow), w below 2^53
/// and a net power of ten within +-22, the value is w * 10^e or w / 10^-e with both operands
/// exact, so the one IEEE operation rounds it correctly (Clinger 1990, the fast path of every
/// correct parser); otherwise the scanned text goes straight to the standard parser (e.g. the
/// 17 significant digits of a double printed exactly). Returns (value, bytes used), or `None`
/// when there is no number (no digits): same values as the standard parser.
#[inline(always)]
pub(crate) fn fast_f64(s: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    let first = *s.first()?;
    let neg = first == b'-';
    if neg || first == b'+' {
        i = 1;
    }
    // The digits from s[i..] appended to w: (index after them, w).
    let scan = |mut i: usize, mut w: u64| {
        while let Some(&c) = s.get(i) {
            let d = c.wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            w = w.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        (i, w)
    };
    let int_start = i;
    let (after, mut w) = scan(i, 0);
    i = after;
    let mut digits = i - int_start;
    let mut exp10: i32 = 0;
    if s.get(i) == Some(&b'.') {
        let frac_start = i + 1;
        (i, w) = scan(frac_start, w);
        digits += i - frac_start;
        exp10 = -((i - frac_start) as i32);
    }
    if digits == 0 {
        return None;
    }
    if let Some(b'e' | b'E') = s.get(i) {
        i += 1;
        let eneg = match s.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let mut e: i32 = 0;
        let e_start = i;
        while let Some(&c) = s.get(i) {
            let d = c.wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            e = e.saturating_mul(10).saturating_add(i32::from(d));
            i += 1;
        }
        if i == e_start {
            return None;
        }
        exp10 = exp10.saturating_add(if eneg { -e } else { e });
    }
    // Longer significands (more than 19 digits: w may have wrapped) or larger exponents: the
    // standard parser (Eisel-Lemire) on the text just scanned, which is a valid decimal.
    if digits > 19 || !(-22..=22).contains(&exp10) || w >= 1u64 << 53 {
        // SAFETY: s[..i] was scanned above: ASCII digits, sign, point and exponent letter only,
        // hence valid UTF-8 (this check cost 12 % of a 17-digit CSV's whole run).
        let text = unsafe { std::str::from_utf8_unchecked(&s[..i]) };
        return Some((text.parse().ok()?, i));
    }
    // Clinger: both operands exact, one correctly rounded operation.
    let v = w as f64;
    let v = if exp10 >= 0 {
        v * POW10[exp10 as usize]
    } else {
        v / POW10[(-exp10) as usize]
    };
    Some((if neg { -v } else { v }, i))
}

/// Branch-light parse of the short numbers IMU logs are made of: `[-]digits[.digits]` with at
/// most 7 digits in all, the field ending within the 8 bytes after the sign (at `,`, `\n` or
/// `\r`). The digits are gathered into one 64-bit word and converted with three multiplies
/// (the SWAR "eight digits" step of simdjson and fast_float, Lemire 2021, "Number parsing at a
/// gigabyte per second", Software: Practice and Experience 51(8)); the value is then
/// w / 10^f with w < 10^7 and f <= 6, both exact, so the one division rounds correctly
/// (Clinger 1990), the same value as the standard parser. `None` sends the field to
/// [`fast_f64`]. The sign, the length and the position of the point are selected without
/// branches: random signs and lengths would otherwise cost a mispredicted branch each.
#[inline(always)]
pub(crate) fn swar_f64(s: &[u8]) -> Option<(f64, usize)> {
    let neg = *s.first()? == b'-';
    let start = usize::from(neg);
    let bytes: [u8; 8] = s.get(start..start + 8)?.try_into().ok()?;
    // Digit values in the bytes ('0'..'9' -> 0..9); a byte is not a digit when its value
    // (with the high bit cleared, so the add cannot carry into the next byte) is >= 10.
    let v = u64::from_le_bytes(bytes) ^ 0x3030_3030_3030_3030;
    let high = 0x8080_8080_8080_8080u64;
    let nondigit = (((v & 0x7f7f_7f7f_7f7f_7f7f) + 0x7676_7676_7676_7676) | v) & high;
    let p1 = (nondigit.trailing_zeros() / 8) as usize; // integer digits (8: none found)
    let rest = nondigit & nondigit.wrapping_sub(1); // the non-digits after the first
    let p2 = (rest.trailing_zeros() / 8) as usize;
    let dot = p1 < 8 && bytes[p1] == b'.';
    let end = if dot { p2 } else { p1 }; // the terminator's position
    if end >= 8 || !matches!(bytes[end], b',' | b'\n' | b'\r') {
        return None;
    }
    let frac = end - p1 - usize::from(dot);
    let digits = p1 + frac;
    if digits == 0 {
        return None;
    }
    // Integer digits, then the fraction digits after the point, right-aligned in 8 bytes
    // (leading zero digits), most significant digit first (lowest address).
    let int = v & ((1u64 << (8 * p1)) - 1);
    let frac_digits = (v >> (8 * (p1 + usize::from(dot)))) & ((1u64 << (8 * frac)) - 1);
    let mut w = (int | (frac_digits << (8 * p1))) << (8 * (8 - digits));
    w = w.wrapping_mul(10).wrapping_add(w >> 8);
    let mask = 0x0000_00ff_0000_00ffu64;
    let mul1 = 100 + (1_000_000u64 << 32);
    let mul2 = 1 + (10_000u64 << 32);
    let w = ((w & mask)
        .wrapping_mul(mul1)
        .wrapping_add(((w >> 16) & mask).wrapping_mul(mul2))
        >> 32) as u32;
    let value = f64::from(w) / POW10[frac];
    let value = f64::from_bits(value.to_bits() | (u64::from(neg) << 63));
    Some((value, start + end))
}

/// A number in the common formats, exactly as the standard parser reads it: [`swar_f64`], else
/// [`fast_f64`]; `None` for the standard parser.
#[inline(always)]
pub(crate) fn number(s: &[u8]) -> Option<(f64, usize)> {
    swar_f64(s).or_else(|| fast_f64(s))
}
