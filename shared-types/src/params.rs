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
    /// What is wrong with a value that names something to use (a file, an address) and cannot
    /// be used, instead of lying outside a range: `cannot open: …`. `None` for a range.
    pub problem: Option<String>,
}

impl ParamError {
    /// `value: problem (expected allowed)`, for a value that cannot be used (`problem` set); the
    /// caller chooses how `value` is shown.
    pub fn unusable(value: &str, problem: &str, allowed: &str) -> String {
        format!("{value}: {problem} (expected {allowed})")
    }
}

impl std::fmt::Display for ParamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.problem {
            Some(problem) => write!(
                f,
                "config key `{}` = {}",
                self.key,
                ParamError::unusable(&self.value, problem, &self.allowed)
            ),
            None => write!(
                f,
                "config key `{}` = {} is out of range: allowed {}",
                self.key, self.value, self.allowed
            ),
        }
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
            problem: None,
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

    /// `lo <= hi` for two fields of the section.
    pub fn less_eq(&self, key_lo: &str, lo: f64, key_hi: &str, hi: f64) -> Result<(), ParamError> {
        if lo <= hi {
            Ok(())
        } else {
            Err(self.err(
                key_lo,
                lo.to_string(),
                format!("at most {}.{key_hi} = {hi}", self.prefix),
            ))
        }
    }
}

/// A number a range check can read: every integer and float type a parameter uses.
pub trait RangeValue: Copy {
    /// The value as `f64` (exact for every integer a parameter holds).
    fn range_value(self) -> f64;
}

macro_rules! range_value_as_f64 {
    ($($t:ty),*) => {
        $(impl RangeValue for $t {
            fn range_value(self) -> f64 {
                self as f64
            }
        })*
    };
}
range_value_as_f64!(f64, f32, u8, u16, u32, u64, usize, i8, i16, i32, i64);

/// Declares a parameter section once: each field with its doc, type, default and allowed range.
///
/// ```
/// hubtrack_types::params! {
///     /// Edge detection.
///     pub struct EdgeParams {
///         /// Upper Canny threshold.
///         pub canny_high: f64 = 200.0, closed(1.0, 1000.0);
///         /// Number of bins.
///         pub bins: u32 = 12, closed(1, 64);
///         /// Off when false (no range).
///         pub enabled: bool = true;
///     }
/// }
/// let p = EdgeParams::default();
/// assert_eq!(p.bins, 12);
/// assert!(p.check_ranges("detect.edges").is_ok());
/// let bad = EdgeParams { canny_high: 0.5, ..p };
/// assert_eq!(bad.check_ranges("detect.edges").unwrap_err().key, "detect.edges.canny_high");
/// ```
///
/// The struct gets `Debug, Clone, PartialEq, Serialize, Deserialize` (unknown keys denied,
/// missing keys defaulted), a [`Default`] with the declared values and `check_ranges(section)`,
/// which checks each declared range with the [`Check`] of the same name (`closed`, `open`,
/// `open_closed`, `zero_or_closed`). Constraints between fields and nested sections stay in the
/// section's own `validate`, which calls `check_ranges` first.
#[macro_export]
macro_rules! params {
    (
        $(#[$smeta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[$fmeta:meta])*
                $fvis:vis $field:ident : $ty:ty = $default:expr $(, $check:ident ( $lo:expr, $hi:expr ))? ;
            )*
        }
    ) => {
        $(#[$smeta])*
        #[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(deny_unknown_fields, default)]
        $vis struct $name {
            $( $(#[$fmeta])* $fvis $field: $ty, )*
        }

        impl Default for $name {
            fn default() -> Self {
                $name { $( $field: $default, )* }
            }
        }

        impl $name {
            /// The section's keys, as they are spelt in a config file.
            pub const KEYS: &'static [&'static str] = &[$(stringify!($field)),*];

            /// Checks every declared range; errors name `section.key` and the allowed range.
            pub fn check_ranges(&self, section: &str) -> Result<(), $crate::params::ParamError> {
                #[allow(unused_variables)]
                let check = $crate::params::Check::new(section);
                $($(
                    check.$check(
                        stringify!($field),
                        $crate::params::RangeValue::range_value(self.$field),
                        $crate::params::RangeValue::range_value($lo),
                        $crate::params::RangeValue::range_value($hi),
                    )?;
                )?)*
                Ok(())
            }
        }
    };
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
