//! Command-line values that are shares of a whole: a number in [0, 1].

/// Parses a share in [0, 1] (`--target-share`, `--grazing-share`, `--refine-grazing`);
/// anything else, NaN included, is an error that names the range.
pub fn parse_share(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a number: {e}"))?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("`{s}` is not a share: give a number from 0 to 1"))
    }
}

#[cfg(test)]
mod tests {
    use super::parse_share;

    #[test]
    fn shares_are_numbers_from_zero_to_one() {
        assert_eq!(parse_share("0"), Ok(0.0));
        assert_eq!(parse_share("0.5"), Ok(0.5));
        assert_eq!(parse_share("1"), Ok(1.0));
        for bad in ["-0.1", "1.5", "NaN", "inf", "half", ""] {
            assert!(parse_share(bad).is_err(), "{bad} was accepted");
        }
    }
}
