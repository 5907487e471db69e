//! Command-line values that are a student's depth: one of the velocity-net depths the
//! kernel compiles (`AnyModel::VELOCITY_HIDDEN_LAYERS`).

use diffbsdf::AnyModel;

/// Parses a student depth (`fit --student-layers`, `curve --student-layers`); a number the
/// kernel has no compiled shape for is an error that lists the depths it has.
pub fn parse_student_layers(s: &str) -> Result<u8, String> {
    let compiled = AnyModel::VELOCITY_HIDDEN_LAYERS;
    let v: u8 = s
        .trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a layer count: {e}"))?;
    if compiled.contains(&v) {
        Ok(v)
    } else {
        let list: Vec<String> = compiled.iter().map(u8::to_string).collect();
        Err(format!(
            "the kernel compiles velocity nets of {} hidden layers, not {v}",
            list.join(" or ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::parse_student_layers;
    use diffbsdf::AnyModel;

    #[test]
    fn only_the_compiled_depths_are_accepted() {
        for d in AnyModel::VELOCITY_HIDDEN_LAYERS {
            assert_eq!(parse_student_layers(&d.to_string()), Ok(d));
        }
        for bad in ["0", "2", "5", "-3", "x", ""] {
            assert!(parse_student_layers(bad).is_err(), "{bad} was accepted");
        }
    }
}
