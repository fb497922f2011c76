//! Text that echoes a user's input back to them, made safe to show: a node id, path or value in
//! an error can hold anything a graph file can spell, and printed raw, `ESC ] 0 ; … BEL`
//! retitles the user's terminal, `ESC [ 2 J` clears it and a carriage return overwrites the
//! line. Every front end (CLI text and JSON, the editor's status line, Python's exceptions)
//! passes its messages through [`printable`] before showing them (JSON through the front-end
//! crate's `printable_json`).

use std::borrow::Cow;

/// A run of characters without whitespace longer than this is cut (a 100 kB node id would bury
/// the message that names it). It is Linux's longest path, so a path is shown whole unless the
/// characters around it (quotes, a colon) take it past the limit.
pub const MAX_RUN: usize = 4096;
/// What is kept of the start of a cut run.
const HEAD: usize = 160;
/// What is kept of its end: a path's file name, the quote and colon that close an id.
const TAIL: usize = 80;

/// `text` with every control character but newline and tab (C0, DEL, C1) and every bidirectional
/// override (the "Trojan Source" characters, which reorder what a terminal shows) written as a
/// Rust escape (`\u{1b}`), and every run of more than [`MAX_RUN`] characters without whitespace
/// cut to its first 160 and last 80 with a note of how many were left out between them. Borrows
/// when nothing changes.
pub fn printable(text: &str) -> Cow<'_, str> {
    let mut run = 0usize;
    let clean = text.chars().all(|c| {
        run = if space(c) { 0 } else { run + 1 };
        !hidden(c) && run <= MAX_RUN
    });
    if clean {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len().min(1 << 16));
    let mut rest = text;
    while !rest.is_empty() {
        let gap = rest.find(|c: char| !space(c)).unwrap_or(rest.len());
        out.push_str(&rest[..gap]);
        rest = &rest[gap..];
        let end = rest.find(space).unwrap_or(rest.len());
        let n = rest[..end].chars().count();
        let cut = n > MAX_RUN;
        for (i, c) in rest[..end].chars().enumerate() {
            if cut && i == HEAD {
                out.push_str(&format!("…[{} more characters]…", n - HEAD - TAIL));
            }
            if cut && (HEAD..n - TAIL).contains(&i) {
                continue;
            }
            if hidden(c) {
                out.extend(c.escape_unicode());
            } else {
                out.push(c);
            }
        }
        rest = &rest[end..];
    }
    Cow::Owned(out)
}

/// Whitespace shown as it is: a space, newline or tab (not a carriage return, form feed or the
/// C1 next-line, which move the cursor).
fn space(c: char) -> bool {
    c.is_whitespace() && !hidden(c)
}

/// Characters never shown raw: controls other than newline and tab, and the bidirectional
/// embeddings, overrides and isolates (U+202A–U+202E, U+2066–U+2069).
fn hidden(c: char) -> bool {
    (c.is_control() && c != '\n' && c != '\t') || ('\u{202a}'..='\u{202e}').contains(&c) || ('\u{2066}'..='\u{2069}').contains(&c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_plain_text_is_borrowed() {
        let hostile = "node 'a\u{1b}]0;PWNED\u{7}b\r\u{0}' and \u{1b}[2J\u{7f}\u{9b}\u{202e}x";
        let shown = printable(hostile);
        assert_eq!(shown, "node 'a\\u{1b}]0;PWNED\\u{7}b\\u{d}\\u{0}' and \\u{1b}[2J\\u{7f}\\u{9b}\\u{202e}x");
        assert!(!shown.chars().any(hidden));
        let plain = "error: g.ron: node 'blur': radius 3 is out of range\n\tsee `pyrograph nodes`";
        assert!(matches!(printable(plain), Cow::Borrowed(_)));
    }

    #[test]
    fn a_long_run_is_cut_and_the_rest_of_the_message_kept() {
        let id = "x".repeat(100_000);
        let message = format!("error: node '{id}': unknown node type 'nope'");
        let shown = printable(&message);
        assert!(shown.len() < 400, "{} bytes", shown.len());
        // The run is the id with its quotes and colon: 100,003 characters, 240 of them kept.
        assert!(shown.contains("…[99763 more characters]…"), "{shown}");
        assert!(shown.ends_with("xxx': unknown node type 'nope'"), "{shown}");
        // A run at the limit is kept whole.
        let edge = "y".repeat(MAX_RUN);
        assert_eq!(printable(&edge), edge.as_str());
    }

    #[test]
    fn a_deep_path_is_shown_whole_and_a_cut_one_keeps_its_file_name() {
        let deep = format!("/mnt/farm/{}/shot_010/fire.exr", "show/seq/department/version".repeat(40));
        assert!(deep.len() > 1000);
        let message = format!("cannot write {deep}: permission denied");
        assert_eq!(printable(&message), message.as_str());
        let absurd = format!("/{}fire_0042.exr", "d/".repeat(5000));
        let shown = printable(&absurd);
        assert!(shown.starts_with("/d/d/") && shown.ends_with("/d/d/d/fire_0042.exr"), "{shown}");
        assert!(shown.chars().count() < 300, "{shown}");
    }
}
