//! Lists of names in messages: a line a person reads, however large the model.

/// Names a message lists at most; the JSON's own fields (`bodies`, `joints`, ...) list them
/// all. A note on a whole robot (20 bodies, 40 joints) stays a line a person reads.
pub const NOTE_NAMES: usize = 12;

/// `names` joined with commas, at most [`NOTE_NAMES`] of them, then "and N more".
pub fn capped<S: AsRef<str>>(names: &[S]) -> String {
    let shown: Vec<&str> = names.iter().take(NOTE_NAMES).map(AsRef::as_ref).collect();
    if names.len() <= NOTE_NAMES {
        shown.join(", ")
    } else {
        format!("{} and {} more", shown.join(", "), names.len() - NOTE_NAMES)
    }
}

#[cfg(test)]
mod tests {
    use super::capped;

    #[test]
    fn twelve_names_then_a_count() {
        let names: Vec<String> = (1..=14).map(|i| i.to_string()).collect();
        assert_eq!(
            capped(&names[..12]),
            "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12"
        );
        assert_eq!(
            capped(&names),
            "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12 and 2 more"
        );
    }
}
