//! Command-line value parsers the tools share, so a bad number is refused where it is typed.

/// Longest time span a command takes, seconds (about 115 days): larger values are typing errors
/// and would overflow time arithmetic.
pub const MAX_SECONDS: f64 = 1e7;

/// A time span in seconds: finite, positive, at most [`MAX_SECONDS`] (`nan`, `inf`, `1e300` and
/// `0` are refused with a message naming the range).
pub fn seconds(text: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if v.is_finite() && v > 0.0 && v <= MAX_SECONDS {
        Ok(v)
    } else {
        Err(format!("{v} s is outside (0, {MAX_SECONDS}] s"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_sane_spans_pass() {
        assert_eq!(seconds("2.5"), Ok(2.5));
        for bad in ["nan", "inf", "-inf", "1e300", "0", "-1", "ten"] {
            assert!(seconds(bad).is_err(), "{bad}");
        }
    }
}
