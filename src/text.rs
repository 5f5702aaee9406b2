//! Numbers and input text in messages, as a person reads them.

/// A number plain when moderate, in exponent form when huge or tiny: `1e308`, not 309 digits.
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_numbers_stay_short() {
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(8e-8), "8e-8");
        assert_eq!(num(1500.0), "1500");
        assert_eq!(num(0.05), "0.05");
        assert_eq!(num(f64::NAN), "NaN");
    }
}
