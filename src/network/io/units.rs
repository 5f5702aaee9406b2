//! Length units of polyline files, and how a DXF states its own: `$INSUNITS` (the drawing's
//! units, 0 = unitless), else `$MEASUREMENT` (0 imperial → inches, 1 metric → mm), else
//! millimetres, said as an assumption. Everything lamina computes is in millimetres.

use std::fmt;

/// A length unit a file may be drawn in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthUnit {
    Mm,
    Cm,
    M,
    In,
    Ft,
    /// Any other `$INSUNITS` value, by its code.
    Other(i16),
}

impl LengthUnit {
    /// The names `--units` takes.
    pub const NAMES: &'static str = "mm, cm, m, in, ft";

    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "mm" | "millimetre" | "millimeter" | "millimetres" | "millimeters" => Self::Mm,
            "cm" | "centimetre" | "centimeter" => Self::Cm,
            "m" | "metre" | "meter" | "metres" | "meters" => Self::M,
            "in" | "inch" | "inches" => Self::In,
            "ft" | "foot" | "feet" => Self::Ft,
            _ => return None,
        })
    }

    /// The unit of a `$INSUNITS` code, `None` for 0 (unitless) and codes DXF does not define.
    pub fn from_insunits(code: i16) -> Option<Self> {
        match code {
            1 => Some(Self::In),
            2 => Some(Self::Ft),
            4 => Some(Self::Mm),
            5 => Some(Self::Cm),
            6 => Some(Self::M),
            3 | 7..=24 => Some(Self::Other(code)),
            _ => None,
        }
    }

    /// Millimetres in one of this unit.
    pub fn mm(self) -> f64 {
        match self {
            Self::Mm => 1.0,
            Self::Cm => 10.0,
            Self::M => 1000.0,
            Self::In => 25.4,
            Self::Ft => 304.8,
            Self::Other(code) => match code {
                3 => 1_609_344.0,                   // mile
                7 => 1e6,                           // kilometre
                8 => 25.4e-6,                       // microinch
                9 => 25.4e-3,                       // mil
                10 => 914.4,                        // yard
                11 => 1e-7,                         // ångström
                12 => 1e-6,                         // nanometre
                13 => 1e-3,                         // micron
                14 => 100.0,                        // decimetre
                15 => 1e4,                          // decametre
                16 => 1e5,                          // hectometre
                17 => 1e12,                         // gigametre
                18 => 1.495_978_707e14,             // astronomical unit
                19 => 9.460_730_472_580_8e18,       // light year
                20 => 3.085_677_581_491_367e19,     // parsec
                21 => 1200.0 / 3937.0 * 1000.0,     // US survey foot
                22 => 100.0 / 3937.0 * 1000.0,      // US survey inch
                23 => 3600.0 / 3937.0 * 1000.0,     // US survey yard
                _ => 6_336_000.0 / 3937.0 * 1000.0, // US survey mile
            },
        }
    }

    pub fn name(self) -> String {
        match self {
            Self::Mm => "mm".into(),
            Self::Cm => "cm".into(),
            Self::M => "m".into(),
            Self::In => "in".into(),
            Self::Ft => "ft".into(),
            Self::Other(code) => match code {
                3 => "mi".into(),
                7 => "km".into(),
                8 => "µin".into(),
                9 => "mil".into(),
                10 => "yd".into(),
                11 => "Å".into(),
                12 => "nm".into(),
                13 => "µm".into(),
                14 => "dm".into(),
                15 => "dam".into(),
                16 => "hm".into(),
                17 => "Gm".into(),
                18 => "AU".into(),
                19 => "ly".into(),
                20 => "pc".into(),
                21 => "US survey ft".into(),
                22 => "US survey in".into(),
                23 => "US survey yd".into(),
                _ => "US survey mi".into(),
            },
        }
    }
}

impl serde::Serialize for LengthUnit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl fmt::Display for LengthUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// The unit a file was read in and where that came from.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SourceUnits {
    pub unit: LengthUnit,
    /// Millimetres per file unit: every coordinate was multiplied by this.
    pub scale_to_mm: f64,
    /// "$INSUNITS = 1", "$MEASUREMENT = 0", "--units", or "assumed (...)".
    pub from: String,
    /// True when nothing in the file or on the command line said the unit.
    pub assumed: bool,
}

impl SourceUnits {
    pub fn new(unit: LengthUnit, from: impl Into<String>, assumed: bool) -> Self {
        SourceUnits {
            unit,
            scale_to_mm: unit.mm(),
            from: from.into(),
            assumed,
        }
    }

    /// One line for a person: "in ($INSUNITS = 1), ×25.4 to mm".
    pub fn describe(&self) -> String {
        if self.scale_to_mm == 1.0 {
            format!("{} ({})", self.unit, self.from)
        } else {
            format!("{} ({}), ×{} to mm", self.unit, self.from, self.scale_to_mm)
        }
    }
}

/// Multiplies every point by the unit's millimetres; `Err(i)` names the first point that is no
/// longer finite (a coordinate too large for the unit).
pub(super) fn scale_to_mm(points: &mut [glam::DVec3], units: &SourceUnits) -> Result<(), usize> {
    if units.scale_to_mm == 1.0 {
        return Ok(());
    }
    for p in points.iter_mut() {
        *p *= units.scale_to_mm;
    }
    match points.iter().position(|p| !p.is_finite()) {
        Some(bad) => Err(bad),
        None => Ok(()),
    }
}

/// The DXF header's `$INSUNITS` and `$MEASUREMENT` values, when present. Reads the group codes
/// of an ASCII DXF up to the end of its HEADER section; for binary DXF, finds the variable names
/// and reads the 16-bit value that follows their group code.
pub fn dxf_header_units(bytes: &[u8]) -> (Option<i16>, Option<i16>) {
    if bytes.starts_with(b"AutoCAD Binary DXF") {
        return (
            binary_var(bytes, b"$INSUNITS"),
            binary_var(bytes, b"$MEASUREMENT"),
        );
    }
    let mut lines = bytes.split(|&b| b == b'\n').map(|l| l.trim_ascii());
    let (mut insunits, mut measurement) = (None, None);
    let mut want: Option<&[u8]> = None;
    let mut in_header = false;
    while let (Some(code), Some(value)) = (lines.next(), lines.next()) {
        match (code, value) {
            (b"2", b"HEADER") => in_header = true,
            (b"0", b"ENDSEC") if in_header => break,
            (b"0", b"SECTION") => {}
            (b"0", _) if !in_header => break,
            (b"9", name) => {
                want = Some(name);
                continue;
            }
            (b"70", v) => {
                let v = std::str::from_utf8(v)
                    .ok()
                    .and_then(|v| v.parse::<i16>().ok());
                match want {
                    Some(b"$INSUNITS") => insunits = v,
                    Some(b"$MEASUREMENT") => measurement = v,
                    _ => {}
                }
            }
            _ => {}
        }
        want = None;
    }
    (insunits, measurement)
}

/// Binary DXF: the variable name, its NUL, the 2-byte group code 70, then a little-endian i16.
fn binary_var(bytes: &[u8], name: &[u8]) -> Option<i16> {
    let header_end = bytes.len().min(1 << 20);
    let hay = &bytes[..header_end];
    let at = hay
        .windows(name.len() + 1)
        .position(|w| w[..name.len()] == *name && w[name.len()] == 0)?;
    let rest = &hay[at + name.len() + 1..];
    match rest {
        [70, 0, lo, hi, ..] => Some(i16::from_le_bytes([*lo, *hi])),
        _ => None,
    }
}

/// The unit a DXF is read in: `--units` when given, else its header, else millimetres.
pub fn dxf_units(bytes: &[u8], forced: Option<LengthUnit>) -> SourceUnits {
    if let Some(u) = forced {
        return SourceUnits::new(u, "--units", false);
    }
    let (insunits, measurement) = dxf_header_units(bytes);
    if let Some(u) = insunits.and_then(LengthUnit::from_insunits) {
        return SourceUnits::new(u, format!("$INSUNITS = {}", insunits.unwrap_or(0)), false);
    }
    match measurement {
        Some(0) => SourceUnits::new(LengthUnit::In, "$MEASUREMENT = 0 (imperial)", false),
        Some(1) => SourceUnits::new(LengthUnit::Mm, "$MEASUREMENT = 1 (metric)", false),
        _ => SourceUnits::new(
            LengthUnit::Mm,
            "assumed: no $INSUNITS or $MEASUREMENT in the file; --units to say otherwise",
            true,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(vars: &str) -> String {
        format!("  0\nSECTION\n  2\nHEADER\n{vars}  0\nENDSEC\n  0\nSECTION\n  2\nENTITIES\n  0\nENDSEC\n  0\nEOF\n")
    }

    #[test]
    fn insunits_wins_then_measurement_then_an_assumption() {
        let inch = header("  9\n$INSUNITS\n 70\n     1\n  9\n$MEASUREMENT\n 70\n     1\n");
        let u = dxf_units(inch.as_bytes(), None);
        assert_eq!(
            (u.unit, u.scale_to_mm, u.assumed),
            (LengthUnit::In, 25.4, false)
        );
        let unitless = header("  9\n$INSUNITS\n 70\n     0\n  9\n$MEASUREMENT\n 70\n     0\n");
        assert_eq!(dxf_units(unitless.as_bytes(), None).unit, LengthUnit::In);
        let metric = header("  9\n$MEASUREMENT\n 70\n     1\n");
        assert_eq!(dxf_units(metric.as_bytes(), None).unit, LengthUnit::Mm);
        let none = dxf_units(header("").as_bytes(), None);
        assert!(none.assumed && none.unit == LengthUnit::Mm);
        let forced = dxf_units(inch.as_bytes(), Some(LengthUnit::M));
        assert_eq!((forced.unit, forced.scale_to_mm), (LengthUnit::M, 1000.0));
    }

    #[test]
    fn binary_headers_are_read_too() {
        let mut b = b"AutoCAD Binary DXF\r\n\x1a\0".to_vec();
        b.extend_from_slice(b"\x09\x00$INSUNITS\0\x46\x00\x05\x00");
        assert_eq!(dxf_units(&b, None).unit, LengthUnit::Cm);
    }

    #[test]
    fn every_insunits_code_has_a_positive_scale() {
        for code in 1..=24 {
            let u = LengthUnit::from_insunits(code).expect("defined");
            assert!(u.mm() > 0.0 && u.mm().is_finite(), "{code}");
        }
        assert_eq!(LengthUnit::from_insunits(0), None);
        assert_eq!(LengthUnit::from_insunits(99), None);
    }
}
