//! User text written into output files, escaped for the format it lands in.
//!
//! Every piece of text ftsmc did not make itself — a path, a command line,
//! a scenario or parameter name — goes through one of these functions
//! before it is written into a TOML comment, a Markdown table, an SVG
//! document or a shell-style command line, so that no input can end a
//! comment, add a TOML key, a table column or an XML element. Structured
//! formats go through their own serializers, which escape by construction:
//! TOML values through the `toml` crate, JSON through `serde_json`, CSV
//! through the `csv` crate (RFC 4180 quoting). A test feeds arbitrary
//! strings through every writer and parses the result back
//! (`crates/ftsmc-cli/tests/injection.rs`).
//!
//! Hand-written rather than a crate: each function is a few lines of
//! character mapping, and the formats' rules are cited on each.

/// `c` written as visible text: `\n`, `\r`, `\t`, `\u{1b}` (Rust's
/// `escape_debug` form), for control characters (Unicode category Cc:
/// U+0000–U+001F, U+007F–U+009F) and the Unicode line and paragraph
/// separators (U+2028, U+2029), which some readers take for line ends.
fn push_visible(out: &mut String, c: char) {
    if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}') {
        out.extend(c.escape_default());
    } else {
        out.push(c);
    }
}

/// Text for a TOML comment (`# …` up to the end of the line): control
/// characters and line separators are written as visible escapes, so the
/// comment cannot end early. TOML 1.0 forbids control characters other than
/// tab in comments; tab is escaped too (it would be invisible). A backslash
/// is kept as is (a comment is not parsed).
pub fn toml_comment(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        push_visible(&mut out, c);
    }
    out
}

/// Text of a Markdown table cell (GitHub-flavoured Markdown): `|` becomes
/// `\|` and `\` becomes `\\` (so the cell keeps its column), a `<` that
/// could open raw HTML (followed by a letter, `/`, `!` or `?`: CommonMark
/// 0.31, section 6.6) becomes `&lt;` and an `&` that could start an entity
/// (followed by a letter or `#`, section 2.5) becomes `&amp;`, so no tag or
/// entity reaches the renderer; control characters and line separators
/// become visible escapes (a newline would end the row). Every other
/// character is kept, so `FTAFTSMC < PID` reads as written on a console and
/// in a rendered page.
pub fn markdown_cell(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        let next = chars.peek().copied();
        match c {
            '|' => out.push_str("\\|"),
            '\\' => out.push_str("\\\\"),
            '<' if next.is_some_and(|n| n.is_ascii_alphabetic() || matches!(n, '/' | '!' | '?')) => {
                out.push_str("&lt;")
            }
            '&' if next.is_some_and(|n| n.is_ascii_alphabetic() || n == '#') => out.push_str("&amp;"),
            c => push_visible(&mut out, c),
        }
    }
    out
}

/// Text for XML character data or a double-quoted attribute value (SVG):
/// `&`, `<`, `>`, `"` as their entities (`'` needs none there); characters XML 1.0 does not allow at
/// all (control characters other than tab, newline and carriage return, and
/// U+FFFE, U+FFFF; section 2.2 of the XML 1.0 recommendation), and the
/// other control characters, as visible escapes (`\u{1b}`), so the result
/// is always well-formed and one line.
pub fn xml_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\u{FFFE}' | '\u{FFFF}' => out.extend(c.escape_default()),
            c => push_visible(&mut out, c),
        }
    }
    out
}

/// One argument of a command line as a POSIX shell word that reads back as
/// the same argument: unchanged when it holds only `A–Z a–z 0–9` and
/// `_ - . / , : = + @ %` (and is not empty); single-quoted (`'it'\''s'`)
/// when it has other printable characters; ANSI-C quoted (`$'a\nb'`, bash,
/// zsh, ksh, POSIX.1-2024 sh) when it has control characters or line
/// separators, so the word is always one line.
pub fn shell_word(arg: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./,:=+@%".contains(c);
    if !arg.is_empty() && arg.chars().all(plain) {
        return arg.to_string();
    }
    if !arg.chars().any(|c| c.is_control() || matches!(c, '\u{2028}' | '\u{2029}')) {
        return format!("'{}'", arg.replace('\'', "'\\''"));
    }
    let mut out = String::from("$'");
    for c in arg.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\'' => out.push_str("\\'"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}') => {
                // `\u{…}` is Rust's form; shells read `\uXXXX` / `\UXXXXXXXX`.
                out.push_str(&format!("\\U{:08x}", u32::from(c)));
            }
            c => out.push(c),
        }
    }
    out.push('\'');
    out
}

/// A command line (`args[0]` the program) as one line of shell words
/// ([`shell_word`] each, separated by spaces).
pub fn command_line<S: AsRef<str>>(args: &[S]) -> String {
    args.iter().map(|a| shell_word(a.as_ref())).collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_newline_cannot_end_a_toml_comment() {
        let text = format!("# {}\n", toml_comment("x\nseed = 4242\n#\r\u{2028}\t\u{0}"));
        assert_eq!(text.lines().count(), 1, "{text:?}");
        let parsed: toml::Table = toml::from_str(&text).unwrap();
        assert!(parsed.is_empty());
    }

    #[test]
    fn markdown_cells_keep_their_column() {
        assert_eq!(markdown_cell("a|b\\|c\n<b>&x &#1"), "a\\|b\\\\\\|c\\n&lt;b>&amp;x &amp;#1");
        // A comparison is not markup: kept as written.
        assert_eq!(markdown_cell("FTAFTSMC < PID < SE(3) & more"), "FTAFTSMC < PID < SE(3) & more");
        assert_eq!(markdown_cell("ISE z (m²·s)"), "ISE z (m²·s)");
    }

    #[test]
    fn xml_text_escapes_markup_and_forbidden_characters() {
        assert_eq!(xml_text("]]><a href=\"x\">&\u{1b}"), "]]&gt;&lt;a href=&quot;x&quot;&gt;&amp;\\u{1b}");
    }

    #[test]
    fn shell_words_are_one_line_and_plain_arguments_unchanged() {
        assert_eq!(
            command_line(&["ftsmc", "tune", "scenarios/a.toml", "--budget", "5"]),
            "ftsmc tune scenarios/a.toml --budget 5"
        );
        assert_eq!(shell_word("it's here"), "'it'\\''s here'");
        assert_eq!(shell_word(""), "''");
        assert_eq!(shell_word("x\nseed = 4242\n#.toml"), "$'x\\nseed = 4242\\n#.toml'");
        assert_eq!(shell_word("a\u{1b}'\\"), "$'a\\U0000001b\\'\\\\'");
    }
}
