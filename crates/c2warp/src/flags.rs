//! Numeric flags: read as numbers (negative ones too, so `--vertices -1` is a value,
//! not an unknown flag) and checked against their range when the command line is
//! parsed, so that a bad value gets one line naming the flag and its range.

use std::fmt::Display;
use std::ops::RangeInclusive;

/// A whole number in `range`: the value parser of a count flag.
pub fn count(
    range: RangeInclusive<usize>,
) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let wanted = || {
            format!(
                "expected a whole number from {} to {}",
                grouped(*range.start()),
                grouped(*range.end())
            )
        };
        let value: usize = text.trim().parse().map_err(|_| wanted())?;
        if range.contains(&value) {
            Ok(value)
        } else {
            Err(wanted())
        }
    }
}

/// A mesh density: the rule and the message of a rig file's `density`.
pub fn density(text: &str) -> Result<usize, String> {
    let value: usize = text.trim().parse().map_err(|_| {
        format!(
            "expected a whole number of vertices from {} to {}",
            grouped(*project::DENSITY_RANGE.start()),
            grouped(*project::DENSITY_RANGE.end())
        )
    })?;
    project::validate_density(value).map_err(|e| e.to_string())?;
    Ok(value)
}

/// A finite number in `range` (with `above_start`, strictly above its start): the
/// value parser of a measure (pixels, seconds, frames per second).
pub fn number(
    range: RangeInclusive<f64>,
    above_start: bool,
    unit: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let (start, end) = (*range.start(), *range.end());
        let wanted = || {
            let from = if above_start { "above" } else { "from" };
            format!(
                "expected a number {from} {} to {}{unit}",
                shown(start),
                shown(end)
            )
        };
        let value: f64 = text.trim().parse().map_err(|_| wanted())?;
        let low_ok = if above_start {
            value > start
        } else {
            value >= start
        };
        if value.is_finite() && low_ok && value <= end {
            Ok(value)
        } else {
            Err(wanted())
        }
    }
}

/// `n` with thousands separated by commas, as the messages write counts.
fn grouped(n: impl Display) -> String {
    let text = n.to_string();
    let (sign, digits) = match text.strip_prefix('-') {
        Some(digits) => ("-", digits),
        None => ("", text.as_str()),
    };
    let mut out = String::from(sign);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `x` as the messages write measures: whole ones grouped by thousands.
fn shown(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        grouped(x as i64)
    } else {
        x.to_string()
    }
}

/// A command-line error about a flag's value as one line (clap writes the possible
/// values, a tip and a hint on more lines); `None` for other errors, which clap
/// writes with the usage.
pub fn value_error_line(error: &clap::Error) -> Option<String> {
    use clap::error::ErrorKind;
    if !matches!(
        error.kind(),
        ErrorKind::ValueValidation | ErrorKind::InvalidValue
    ) {
        return None;
    }
    let text = error.render().to_string();
    let line = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("For more information"))
        .collect::<Vec<_>>()
        .join(" ");
    (!line.is_empty()).then_some(line)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_numbers_name_their_range() {
        let vertices = count(3..=1000);
        assert_eq!(vertices("16"), Ok(16));
        for bad in ["-1", "2", "1001", "1e3", "ten", ""] {
            assert_eq!(
                vertices(bad),
                Err("expected a whole number from 3 to 1,000".to_owned()),
                "{bad}"
            );
        }
        let fps = number(0.0..=240.0, true, " frames per second");
        assert_eq!(fps("12.5"), Ok(12.5));
        for bad in ["0", "-5", "241", "NaN", "inf", "x"] {
            assert_eq!(
                fps(bad),
                Err("expected a number above 0 to 240 frames per second".to_owned())
            );
        }
        let offset = number(0.0..=10_000.0, false, " px");
        assert_eq!(offset("0"), Ok(0.0));
        assert!(offset("1e9").is_err() && offset("-5").is_err());
        assert_eq!(grouped(4_000_000), "4,000,000");
        assert_eq!(grouped(16), "16");
    }
}
