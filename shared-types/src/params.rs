//! Validation of algorithm parameters, shared by the stage libraries so that every config error
//! names its full key and allowed range the same way.

/// A parameter outside its allowed range.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamError {
    /// Full dotted key path, e.g. `track.filter.damping`.
    pub key: String,
    /// The value given.
    pub value: String,
    /// The allowed range or set.
    pub allowed: String,
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "config key `{}` = {} is out of range: allowed {}",
            self.key, self.value, self.allowed
        )
    }
}

impl std::error::Error for ParamError {}

/// Range checks of one config section; errors carry `<prefix>.<key>`.
pub struct Check<'a> {
    prefix: &'a str,
}

impl<'a> Check<'a> {
    /// Checks for the section `prefix` (e.g. `detect.thesis`).
    pub fn new(prefix: &'a str) -> Check<'a> {
        Check { prefix }
    }

    fn err(&self, key: &str, value: String, allowed: String) -> ParamError {
        ParamError {
            key: format!("{}.{}", self.prefix, key),
            value,
            allowed,
        }
    }

    /// `lo <= v <= hi`, finite.
    pub fn closed(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ParamError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(())
        } else {
            Err(self.err(key, v.to_string(), format!("[{lo}, {hi}]")))
        }
    }

    /// `lo < v <= hi`, finite.
    pub fn open_closed(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ParamError> {
        if v.is_finite() && v > lo && v <= hi {
            Ok(())
        } else {
            Err(self.err(key, v.to_string(), format!("({lo}, {hi}]")))
        }
    }

    /// `lo < v < hi`, finite.
    pub fn open(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ParamError> {
        if v.is_finite() && v > lo && v < hi {
            Ok(())
        } else {
            Err(self.err(key, v.to_string(), format!("({lo}, {hi})")))
        }
    }

    /// `v == 0` (the feature off) or `lo <= v <= hi`, finite.
    pub fn zero_or_closed(&self, key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ParamError> {
        if v == 0.0 || (v.is_finite() && v >= lo && v <= hi) {
            Ok(())
        } else {
            Err(self.err(key, v.to_string(), format!("0 (off) or [{lo}, {hi}]")))
        }
    }

    /// Integer in `[lo, hi]`.
    pub fn count(&self, key: &str, v: u32, lo: u32, hi: u32) -> Result<(), ParamError> {
        if v >= lo && v <= hi {
            Ok(())
        } else {
            Err(self.err(key, v.to_string(), format!("[{lo}, {hi}]")))
        }
    }

    /// `lo < hi` for two keys of the section.
    pub fn less(&self, key_lo: &str, lo: f64, key_hi: &str, hi: f64) -> Result<(), ParamError> {
        if lo < hi {
            Ok(())
        } else {
            Err(self.err(
                key_lo,
                lo.to_string(),
                format!("less than {}.{key_hi} = {hi}", self.prefix),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_full_key_and_range() {
        let c = Check::new("track.filter");
        let e = c.open_closed("damping", 3.0, 0.0, 1.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "config key `track.filter.damping` = 3 is out of range: allowed (0, 1]"
        );
        assert!(c.closed("x", f64::NAN, 0.0, 1.0).is_err());
        assert!(c
            .less("lo", 2.0, "hi", 1.0)
            .unwrap_err()
            .allowed
            .contains("track.filter.hi"));
        let e = c.zero_or_closed("tol", 0.5, 1.0, 10.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "config key `track.filter.tol` = 0.5 is out of range: allowed 0 (off) or [1, 10]"
        );
        assert!(
            c.zero_or_closed("tol", 0.0, 1.0, 10.0).is_ok()
                && c.zero_or_closed("tol", 1.5, 1.0, 10.0).is_ok()
        );
        assert!(c.zero_or_closed("tol", f64::NAN, 1.0, 10.0).is_err());
    }
}
