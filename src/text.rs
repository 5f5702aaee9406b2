//! Numbers and input text in messages, as a person reads them.

/// A number plain when moderate, in exponent form when huge or tiny: `1e308`, not 309 digits.
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A figure to three significant digits for people: plain between 0.001 and 100,000
/// (`53.4`, `0.00849`), else in exponent form (`8.49e-5`, `1.23e6`).
pub fn sig3(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if (1e-3..1e5).contains(&v.abs()) {
        // Digits after the point for three significant ones, from the rounded value's size.
        let rounded: f64 = format!("{v:.2e}").parse().unwrap_or(v);
        let magnitude = rounded.abs().log10().floor() as i32;
        let places = (2 - magnitude).max(0) as usize;
        format!("{rounded:.places$}")
    } else {
        format!("{v:.2e}")
    }
}

/// Text from an input file made safe to print in a one-line message: control characters
/// (escape sequences, NUL, CR, line breaks, DEL) are shown escaped, as `\u{1b}`, `\0`, `\n`;
/// everything else, quotes and non-ASCII letters included, is kept.
pub fn printable(s: &str) -> std::borrow::Cow<'_, str> {
    if !s.chars().any(char::is_control) {
        return std::borrow::Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if c.is_control() {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// Text for HTML and SVG, in element content and in quoted attributes.
pub fn html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_keep_three_significant_digits() {
        assert_eq!(sig3(53.35), "53.4");
        assert_eq!(sig3(8.493210529416308e-5), "8.49e-5");
        assert_eq!(sig3(0.01), "0.0100");
        assert_eq!(sig3(999.96), "1000");
        assert_eq!(sig3(0.0084936), "0.00849");
        assert_eq!(sig3(-2.5), "-2.50");
        assert_eq!(sig3(123456.0), "1.23e5");
        assert_eq!(sig3(0.0), "0");
    }

    #[test]
    fn control_characters_are_shown_escaped() {
        assert_eq!(printable("a \u{1b}[31mred\u{7}"), "a \\u{1b}[31mred\\u{7}");
        assert_eq!(printable("x\0y\r\nz"), "x\\0y\\r\\nz");
        assert_eq!(printable("`naïve` \"q\""), "`naïve` \"q\"");
    }

    #[test]
    fn huge_and_tiny_numbers_stay_short() {
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(8e-8), "8e-8");
        assert_eq!(num(1500.0), "1500");
        assert_eq!(num(0.05), "0.05");
        assert_eq!(num(f64::NAN), "NaN");
    }
}
