//! Names and text on `.trk` lines: written bare when they read back as themselves, else in
//! double quotes; comments cut at a `#` outside quotes.
//!
//! A **name** (of a sequence, an object, a DOF, a meta key, the actor and joint of a
//! `held` line) is written bare when it is a plain word: not empty, and no whitespace, no
//! control character, no `#` and no `"`. Any other name is quoted: `"Ann Lee"`,
//! `"take#2"`, `" lead "`, `""`. Inside quotes, `\"` is a quote and `\\` a backslash;
//! `\n`, `\r`, `\t` and `\u{HEX}` stand for control characters, so that a quoted name
//! stays on its line. A quote opens only at the start of a word: `a"b` is a bare word.
//!
//! A **text** (a meta value, the rest of its line) is written bare unless it would not
//! read back: empty, with whitespace at either end, a `#`, a control character, or a
//! `"` at the start of a word. Read back, a text that does not start with a quote is the rest of the
//! line as it stands, inner spaces and all, as files were read before quoting. The name
//! of a `sequence` or `object` line is read as a text too, so `sequence Ann Lee` in an
//! older file still names `Ann Lee`.

use std::borrow::Cow;
use std::fmt::Write as _;

/// Whether `name` reads back bare as itself from a list of words.
fn is_plain_name(name: &str) -> bool {
    !name.is_empty()
        && !name
            .chars()
            .any(|c| c.is_whitespace() || c.is_control() || c == '#' || c == '"')
}

/// `name` as written on a line: bare when plain, else quoted.
pub(crate) fn name_word(name: &str) -> Cow<'_, str> {
    if is_plain_name(name) {
        Cow::Borrowed(name)
    } else {
        Cow::Owned(quote(name))
    }
}

/// `text` as written for the rest of a line: bare when it reads back as itself, else
/// quoted.
pub(crate) fn text_field(text: &str) -> Cow<'_, str> {
    // A `"` opening any word would be read as a quote by `strip_comment`, not only a
    // leading one (`a "b` read as a quote not closed).
    let bare = !text.is_empty()
        && text.trim() == text
        && !text.split_whitespace().any(|word| word.starts_with('"'))
        && !text.chars().any(|c| c.is_control() || c == '#');
    if bare {
        Cow::Borrowed(text)
    } else {
        Cow::Owned(quote(text))
    }
}

/// `s` in double quotes, escaped (see the module).
fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            // `writeln!` into a String cannot fail.
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `line` without its comment: the text before the first `#` outside a quoted word. An
/// error when a quote is not closed on the line.
pub(crate) fn strip_comment(line: &str) -> Result<&str, String> {
    let mut word_start = true;
    let mut quoted = false;
    let mut escaped = false;
    for (i, c) in line.char_indices() {
        if quoted {
            if escaped {
                escaped = false;
            } else if c == '\\' {
                escaped = true;
            } else if c == '"' {
                quoted = false;
            }
            continue;
        }
        if c == '#' {
            return Ok(&line[..i]);
        }
        quoted = c == '"' && word_start;
        word_start = c.is_whitespace();
    }
    if quoted {
        return Err(format!("a quoted name is not closed by `\"` in `{line}`"));
    }
    Ok(line)
}

/// The first word of `s` (leading whitespace skipped; a quoted one unquoted) and what
/// follows it, or `None` when `s` is blank. An error for a bad quoted word.
pub(crate) fn split_word(s: &str) -> Result<Option<(String, &str)>, String> {
    let s = s.trim_start();
    if s.is_empty() {
        return Ok(None);
    }
    let Some(inner) = s.strip_prefix('"') else {
        let end = s.find(char::is_whitespace).unwrap_or(s.len());
        return Ok(Some((s[..end].to_string(), &s[end..])));
    };
    let mut out = String::new();
    let mut chars = inner.char_indices();
    while let Some((i, c)) = chars.next() {
        match c {
            '"' => {
                let rest = &inner[i + 1..];
                if rest.starts_with(|c: char| !c.is_whitespace()) {
                    return Err(format!(
                        "expected a space after the closing quote of `{}`",
                        &s[..i + 2]
                    ));
                }
                return Ok(Some((out, rest)));
            }
            '\\' => out.push(unescape(&mut chars, inner)?),
            c => out.push(c),
        }
    }
    Err(format!("a quoted name is not closed by `\"` in `{s}`"))
}

/// The character an escape stands for, `chars` being just past its backslash in `inner`.
fn unescape(chars: &mut std::str::CharIndices<'_>, inner: &str) -> Result<char, String> {
    let unknown = |what: &str| {
        format!("unknown escape `\\{what}` in a quoted name (`\\\"`, `\\\\`, `\\n`, `\\r`, `\\t` or `\\u{{HEX}}`)")
    };
    let Some((at, c)) = chars.next() else {
        return Err(unknown(""));
    };
    Ok(match c {
        '"' => '"',
        '\\' => '\\',
        'n' => '\n',
        'r' => '\r',
        't' => '\t',
        'u' => {
            let hex = inner[at + 1..]
                .strip_prefix('{')
                .and_then(|h| h.split_once('}'))
                .map(|(h, _)| h);
            let c = hex
                .filter(|h| (1..=6).contains(&h.len()))
                .and_then(|h| u32::from_str_radix(h, 16).ok())
                .and_then(char::from_u32);
            let (Some(hex), Some(c)) = (hex, c) else {
                return Err(unknown("u"));
            };
            // Past the braces and the digits.
            for _ in 0..hex.len() + 2 {
                chars.next();
            }
            c
        }
        other => return Err(unknown(&other.to_string())),
    })
}

/// Every word of `s` (see [`split_word`]).
pub(crate) fn words(mut s: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    while let Some((word, rest)) = split_word(s)? {
        out.push(word);
        s = rest;
    }
    Ok(out)
}

/// The rest of a line as one text: a quoted word alone, or else the trimmed text as it
/// stands (see the module).
pub(crate) fn text(s: &str) -> Result<String, String> {
    let s = s.trim();
    if !s.starts_with('"') {
        return Ok(s.to_string());
    }
    match words(s)?.as_slice() {
        [one] => Ok(one.clone()),
        _ => Err(format!(
            "expected one quoted text, found `{s}` (more follows the closing quote)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Names that are not plain words, and some that are.
    const NAMES: &[&str] = &[
        "cup",
        "cup é",
        "my cup",
        "Ann Lee",
        "take#2",
        " lead ",
        "lead",
        "",
        "say \"hi\"",
        "back\\slash",
        "tab\there",
        "new\nline",
        "bell\u{7}",
        "nbsp\u{a0}x",
        "\"",
        "a\"b",
        "a \"b",
        "#",
        "ünïcødé",
    ];

    proptest! {
        #[test]
        fn any_name_and_any_text_read_back(s in any::<String>()) {
            let name = name_word(&s);
            let line = format!("w {name} {name}#");
            prop_assert_eq!(words(strip_comment(&line).unwrap()).unwrap(), ["w", &s, &s]);
            let text_line = format!("{}#", text_field(&s));
            prop_assert_eq!(text(strip_comment(&text_line).unwrap()).unwrap(), s.clone());
            prop_assert!(!name.contains(['\n', '\r']) && !text_line.contains(['\n', '\r']));
        }
    }

    #[test]
    fn every_name_reads_back_as_one_word_and_plain_ones_stay_bare() {
        for &name in NAMES {
            let written = name_word(name);
            let line = format!("held 0 1 {written} {written} # a comment");
            let code = strip_comment(&line).unwrap();
            assert_eq!(
                words(code).unwrap(),
                ["held", "0", "1", name, name],
                "{name:?} written as {written}"
            );
            assert!(!written.contains('\n'), "{written}");
        }
        assert_eq!(name_word("r_wrist"), "r_wrist");
        assert_eq!(name_word("ünïcødé"), "ünïcødé");
        assert_eq!(name_word("Ann Lee"), "\"Ann Lee\"");
        assert_eq!(name_word("take#2"), "\"take#2\"");
        assert_eq!(name_word(""), "\"\"");
        assert_eq!(name_word("say \"hi\""), r#""say \"hi\"""#);
        assert_eq!(name_word("bell\u{7}"), r#""bell\u{7}""#);
    }

    #[test]
    fn every_text_reads_back_and_ordinary_ones_stay_bare() {
        for &value in NAMES.iter().chain(&["troupe run", "  two  spaces inside "]) {
            let written = text_field(value);
            let line = format!("{written}   # a comment");
            assert_eq!(
                text(strip_comment(&line).unwrap()).unwrap(),
                value,
                "{value:?} written as {written}"
            );
        }
        assert_eq!(text_field("troupe run"), "troupe run");
        assert_eq!(text_field("a  b"), "a  b");
        assert_eq!(text_field("/maps/my#1.map"), "\"/maps/my#1.map\"");
        // Older files: a text not starting with a quote is the rest of the line.
        assert_eq!(text("  Ann  Lee ").unwrap(), "Ann  Lee");
        assert_eq!(text("a\"b c").unwrap(), "a\"b c");
    }

    #[test]
    fn comments_start_at_a_hash_outside_quotes() {
        assert_eq!(strip_comment("track x # note").unwrap(), "track x ");
        assert_eq!(
            strip_comment("object \"a # b\" # c").unwrap(),
            "object \"a # b\" "
        );
        assert_eq!(
            strip_comment(r#"object "a \" # b""#).unwrap(),
            r#"object "a \" # b""#
        );
        // A quote inside a word is a character, not the start of a quoted word.
        assert_eq!(
            strip_comment("sequence a\"b # c").unwrap(),
            "sequence a\"b "
        );
        assert_eq!(strip_comment("0 1").unwrap(), "0 1");
    }

    #[test]
    fn bad_quoting_is_an_error() {
        for (line, needle) in [
            ("object \"cup", "not closed"),
            ("object \"cup\\\"", "not closed"),
            ("object \"cup\"x", "space after the closing quote"),
            ("object \"a\\qb\"", "unknown escape `\\q`"),
            ("object \"a\\u{110000}\"", "unknown escape `\\u`"),
            ("object \"a\\u{}\"", "unknown escape `\\u`"),
            ("object \"a\\u41\"", "unknown escape `\\u`"),
        ] {
            let err = strip_comment(line).and_then(words).expect_err(line);
            assert!(err.contains(needle), "{line}: {err}");
        }
        assert!(text("\"a\" b").unwrap_err().contains("more follows"));
    }
}
