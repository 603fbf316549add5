//! Valid ranges of numeric options, checked while the command line is parsed, so that NaN,
//! infinities, zero or negative values where they mean nothing never reach a computation. Every
//! numeric option names its range in its help text and goes through [`within`].

use std::fmt;
use std::str::FromStr;

/// An interval of valid values, closed at the top, open or closed at the bottom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    min: f64,
    min_open: bool,
    max: f64,
}

impl Range {
    /// `[min, max]`
    pub const fn closed(min: f64, max: f64) -> Self {
        Self {
            min,
            min_open: false,
            max,
        }
    }

    /// `(min, max]`: for quantities where the bottom value itself means nothing (a zero step).
    pub const fn above(min: f64, max: f64) -> Self {
        Self {
            min,
            min_open: true,
            max,
        }
    }

    pub fn contains(&self, v: f64) -> bool {
        let above_min = if self.min_open {
            v > self.min
        } else {
            v >= self.min
        };
        above_min && v <= self.max
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let open = if self.min_open { '(' } else { '[' };
        write!(f, "{open}{}, {}]", self.min, self.max)
    }
}

/// A clap value parser for a number that must be finite and inside `range`; the message names
/// the range so the user sees what to type instead.
pub fn within<T>(range: Range) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + Copy + Into<f64> + Send + Sync + 'static,
{
    move |text: &str| {
        let value: T = text
            .trim()
            .parse()
            .map_err(|_| format!("not a number; the valid range is {range}"))?;
        let x: f64 = value.into();
        if x.is_finite() && range.contains(x) {
            Ok(value)
        } else {
            Err(format!("outside the valid range {range}"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn nan_infinities_and_the_open_end_are_refused() {
        let positive = within::<f64>(Range::above(0.0, 10.0));
        for bad in [
            "nan", "NaN", "inf", "-inf", "0", "-1", "10.5", "1e300", "", "x",
        ] {
            assert!(positive(bad).is_err(), "{bad}");
        }
        assert_eq!(positive("10"), Ok(10.0));
        assert_eq!(positive(" 0.25 "), Ok(0.25));
        let closed = within::<f32>(Range::closed(0.0, 1.0));
        assert_eq!(closed("0"), Ok(0.0));
        assert!(closed("1.0001").is_err());
        let baud = within::<u32>(Range::closed(1200.0, 4e6));
        assert!(baud("0").is_err() && baud("-5").is_err() && baud("115200").is_ok());
    }

    #[test]
    fn the_message_names_the_range() {
        let e = within::<f64>(Range::above(0.0, 2.5))("nan").unwrap_err();
        assert!(e.contains("(0, 2.5]"), "{e}");
    }

    proptest! {
        /// Accepted exactly when finite and inside: the parser and `contains` agree everywhere.
        #[test]
        fn accepts_exactly_the_finite_values_inside(v in prop::num::f64::ANY, lo in -10.0f64..10.0, w in 0.0f64..10.0, open in any::<bool>()) {
            let range = if open { Range::above(lo, lo + w) } else { Range::closed(lo, lo + w) };
            let got = within::<f64>(range)(&format!("{v}"));
            prop_assert_eq!(got.is_ok(), v.is_finite() && range.contains(v));
        }
    }
}
