//! Typo hints ("did you mean 'math.add'?") for names a user wrote: node types, expression
//! functions and variables.

/// The edit distance between `a` and `b` when it is at most `max`, for typo hints. Names whose
/// lengths differ by more than `max` are not compared at all, so a hostile name of millions of
/// characters costs a length check, not a quadratic table.
pub(crate) fn within_edits(a: &str, b: &str, max: usize) -> Option<usize> {
    if a.chars().count().abs_diff(b.chars().count()) > max {
        return None;
    }
    Some(edit_distance(a, b)).filter(|d| *d <= max)
}

/// Levenshtein distance; short names only (see [`within_edits`]), so the quadratic table is fine.
pub(crate) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}
