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

/// A finite number that `accept` takes; else an error quoting `text` with `what` it must be.
fn number(text: &str, accept: impl Fn(f64) -> bool, what: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && accept(v) => Ok(v),
        Ok(_) => Err(format!("{text:?}: {what}")),
        Err(e) => Err(format!("{text:?}: {e}")),
    }
}

/// A distance in metres: finite and positive.
pub fn metres(text: &str) -> Result<f64, String> {
    number(
        text,
        |v| v > 0.0,
        "a distance is a positive number of metres",
    )
}

/// A roll in degrees: finite, within ±180.
pub fn roll_deg(text: &str) -> Result<f64, String> {
    number(
        text,
        |v| v.abs() <= 180.0,
        "a roll is a number of degrees within ±180",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_distances_and_rolls_pass() {
        assert_eq!((metres("12.5"), roll_deg("-1.6")), (Ok(12.5), Ok(-1.6)));
        for bad in ["nan", "inf", "0", "-5", "ten"] {
            assert!(metres(bad).is_err(), "{bad}");
        }
        for bad in ["nan", "1e300", "181", "ten"] {
            assert!(roll_deg(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn only_sane_spans_pass() {
        assert_eq!(seconds("2.5"), Ok(2.5));
        for bad in ["nan", "inf", "-inf", "1e300", "0", "-1", "ten"] {
            assert!(seconds(bad).is_err(), "{bad}");
        }
    }
}
