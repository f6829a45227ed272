//! Python's `repr` of a float: the shortest decimal that reads back to the same `f64` (the
//! digits from Ryū, which are CPython's `dtoa` mode 0 digits), laid out as CPython lays them
//! out: positional from 1e-4 up to 1e16 (`0.0001`, `123.0`), else with an exponent of a sign
//! and at least two digits (`1e-05`, `1.5e+300`); `-0.0`, `inf`, `-inf`, `nan`.

/// The decimal digits of a finite nonzero float's shortest round-trip text, without leading
/// or trailing zeros, and the position of the decimal point relative to them (the value is
/// `0.DIGITS * 10**point`, as CPython's `decpt`).
struct Shortest {
    digits: [u8; 24],
    count: usize,
    point: i32,
}

/// Splits ryu's text (`1.5e300`, `1e-7`, `0.0001`, `123.0`, no sign) into digits and point.
fn shortest(magnitude: f64) -> Shortest {
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(magnitude).as_bytes();
    let (mantissa, exponent) = match text.iter().position(|&c| c == b'e') {
        Some(at) => (&text[..at], parse_exponent(&text[at + 1..])),
        None => (text, 0),
    };
    let mut result = Shortest {
        digits: [0; 24],
        count: 0,
        point: 0,
    };
    let mut before_point = 0i32;
    let mut seen_point = false;
    let mut leading = true;
    for &c in mantissa {
        if c == b'.' {
            seen_point = true;
            continue;
        }
        if !seen_point {
            before_point += 1;
        }
        if leading && c == b'0' {
            // a leading zero moves the point left by one digit
            result.point -= 1;
            continue;
        }
        leading = false;
        if result.count < result.digits.len() {
            result.digits[result.count] = c;
            result.count += 1;
        }
    }
    while result.count > 1 && result.digits[result.count - 1] == b'0' {
        result.count -= 1;
    }
    result.point += before_point + exponent;
    result
}

fn parse_exponent(text: &[u8]) -> i32 {
    let (negative, digits) = match text.first() {
        Some(b'-') => (true, &text[1..]),
        _ => (false, text),
    };
    let magnitude = digits
        .iter()
        .fold(0i32, |total, &c| total * 10 + i32::from(c - b'0'));
    if negative {
        -magnitude
    } else {
        magnitude
    }
}

/// Appends Python's `repr(value)` to `out`.
pub fn write_repr(value: f64, out: &mut Vec<u8>) {
    if value.is_nan() {
        out.extend_from_slice(b"nan");
        return;
    }
    if value.is_sign_negative() {
        out.push(b'-');
    }
    let magnitude = value.abs();
    if magnitude.is_infinite() {
        out.extend_from_slice(b"inf");
        return;
    }
    if magnitude == 0.0 {
        out.extend_from_slice(b"0.0");
        return;
    }
    let mut buffer = ryu::Buffer::new();
    let text = buffer.format_finite(magnitude).as_bytes();
    if write_ryu_as_python(text, out) {
        return;
    }
    let found = shortest(magnitude);
    let digits = &found.digits[..found.count];
    let point = found.point;
    let count = found.count as i32;
    if point <= -4 || point > 16 {
        out.push(digits[0]);
        if digits.len() > 1 {
            out.push(b'.');
            out.extend_from_slice(&digits[1..]);
        }
        let exponent = point - 1;
        out.push(b'e');
        out.push(if exponent < 0 { b'-' } else { b'+' });
        let exponent = exponent.unsigned_abs();
        if exponent < 10 {
            out.push(b'0');
        }
        write_unsigned(u64::from(exponent), out);
    } else if point <= 0 {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', point.unsigned_abs() as usize));
        out.extend_from_slice(digits);
    } else if point >= count {
        out.extend_from_slice(digits);
        out.extend(std::iter::repeat_n(b'0', (point - count) as usize));
        out.extend_from_slice(b".0");
    } else {
        let split = point as usize;
        out.extend_from_slice(&digits[..split]);
        out.push(b'.');
        out.extend_from_slice(&digits[split..]);
    }
}

/// Appends ryu's text of a positive float as Python's when only its layout differs in the
/// usual ways: positional from 1e-4 up (ryu's from 1e-5: `0.0000ddd` is left out), and an
/// exponent of a sign and at least two digits. `false` (nothing appended) for the rest: a
/// `0.0000` start, or a mantissa ending in a zero that Python's digits would not have.
fn write_ryu_as_python(text: &[u8], out: &mut Vec<u8>) -> bool {
    match text.iter().position(|&c| c == b'e') {
        None => {
            let len = text.len();
            let stray_zero = len >= 2 && text[len - 1] == b'0' && text[len - 2] != b'.';
            if text.starts_with(b"0.0000") || stray_zero {
                return false;
            }
            out.extend_from_slice(text);
            true
        }
        Some(at) => {
            let (mantissa, exponent) = (&text[..at], &text[at + 1..]);
            if mantissa.last() == Some(&b'0') {
                return false;
            }
            out.extend_from_slice(mantissa);
            out.push(b'e');
            let digits = match exponent.first() {
                Some(b'-') => {
                    out.push(b'-');
                    &exponent[1..]
                }
                _ => {
                    out.push(b'+');
                    exponent
                }
            };
            if digits.len() < 2 {
                out.push(b'0');
            }
            out.extend_from_slice(digits);
            true
        }
    }
}

/// Appends the decimal digits of `value`.
pub fn write_unsigned(mut value: u64, out: &mut Vec<u8>) {
    let mut digits = [0u8; 20];
    let mut start = digits.len();
    loop {
        start -= 1;
        digits[start] = b'0' + (value % 10) as u8;
        value /= 10;
        if value == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[start..]);
}

/// Appends the decimal text of `value` (as Python's `str` of an int).
pub fn write_signed(value: i64, out: &mut Vec<u8>) {
    if value < 0 {
        out.push(b'-');
    }
    write_unsigned(value.unsigned_abs(), out);
}

/// Python's `repr(value)` as a `String` (for tests and messages).
pub fn repr(value: f64) -> String {
    let mut out = Vec::with_capacity(26);
    write_repr(value, &mut out);
    // only ASCII is ever written
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::repr;

    #[test]
    fn python_layout() {
        let cases: &[(f64, &str)] = &[
            (0.0, "0.0"),
            (-0.0, "-0.0"),
            (1.0, "1.0"),
            (-1.5, "-1.5"),
            (0.1, "0.1"),
            (0.0001, "0.0001"),
            (0.00001, "1e-05"),
            (0.000123, "0.000123"),
            (0.0000123, "1.23e-05"),
            (1e15, "1000000000000000.0"),
            (1e16, "1e+16"),
            (1.5e16, "1.5e+16"),
            (123456789012345680.0, "1.2345678901234568e+17"),
            (1e22, "1e+22"),
            (1e100, "1e+100"),
            (5e-324, "5e-324"),
            (2.2250738585072014e-308, "2.2250738585072014e-308"),
            (1.7976931348623157e308, "1.7976931348623157e+308"),
            (f64::INFINITY, "inf"),
            (f64::NEG_INFINITY, "-inf"),
            (f64::NAN, "nan"),
            (123.456, "123.456"),
            (9007199254740993.0, "9007199254740992.0"),
            (0.30000000000000004, "0.30000000000000004"),
            (1e-10, "1e-10"),
            (f64::from(0.1f32), "0.10000000149011612"),
        ];
        for &(value, text) in cases {
            assert_eq!(repr(value), text, "{value:e}");
        }
    }

    #[test]
    fn round_trip() {
        let mut state = 0x1234_5678_9abc_def0u64;
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let value = f64::from_bits(state);
            if value.is_finite() {
                let parsed: f64 = repr(value).parse().unwrap_or(f64::NAN);
                assert_eq!(parsed.to_bits(), value.to_bits());
            }
        }
    }
}
