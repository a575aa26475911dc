//! The URI of a buffer file beside a `.gltf`: its file name percent-encoded as RFC 3986
//! asks, and decoded back when read.
//!
//! glTF URIs are URIs (RFC 3986), so a reader decodes them: a `.bin` named `G%20v1.bin`
//! written verbatim is looked for as `G v1.bin`, and in `take#2.bin` the `#` starts a
//! fragment. Every byte of the name's UTF-8 but the unreserved characters (letters,
//! digits, `-`, `.`, `_`, `~`) is written as `%XX`.

use std::fmt::Write as _;

/// `name` (a file name, no `/`) as a relative URI reference.
pub(crate) fn encode(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for &b in name.as_bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_' | b'~') {
            out.push(b as char);
        } else {
            // Writing into a String cannot fail.
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

/// The path a relative URI reference names: every `%XX` decoded. An error for a `%` not
/// followed by two hex digits, or bytes that are not UTF-8.
pub(crate) fn decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] != b'%' {
            out.push(bytes[i]);
            i += 1;
            continue;
        }
        let byte = bytes
            .get(i + 1..i + 3)
            .and_then(|hex| std::str::from_utf8(hex).ok())
            .and_then(|hex| u8::from_str_radix(hex, 16).ok())
            .ok_or_else(|| format!("URI `{uri}`: `%` not followed by two hex digits"))?;
        out.push(byte);
        i += 3;
    }
    String::from_utf8(out).map_err(|_| format!("URI `{uri}` does not decode to UTF-8 text"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn reserved_characters_spaces_and_non_ascii_are_encoded() {
        assert_eq!(encode("walk.bin"), "walk.bin");
        assert_eq!(encode("a-b_c~d.0.bin"), "a-b_c~d.0.bin");
        assert_eq!(encode("G%20v1.bin"), "G%2520v1.bin");
        assert_eq!(encode("G.take#2.bin"), "G.take%232.bin");
        assert_eq!(encode("cup é.bin"), "cup%20%C3%A9.bin");
        assert_eq!(encode("a?b&c+d:e@f.bin"), "a%3Fb%26c%2Bd%3Ae%40f.bin");
    }

    #[test]
    fn decoding_undoes_encoding_and_refuses_bad_escapes() {
        assert_eq!(decode("G%2520v1.bin").unwrap(), "G%20v1.bin");
        assert_eq!(decode("cup%20%c3%a9.bin").unwrap(), "cup é.bin");
        // Characters a loose writer left unencoded are taken as they are.
        assert_eq!(decode("my file#2.bin").unwrap(), "my file#2.bin");
        for bad in ["50%.bin", "a%2", "a%zz.bin", "%C3.bin"] {
            assert!(decode(bad).is_err(), "{bad}");
        }
    }

    proptest! {
        #[test]
        fn any_name_round_trips(name in any::<String>()) {
            let uri = encode(&name);
            prop_assert!(uri.bytes().all(|b| b.is_ascii_alphanumeric() || b"-._~%".contains(&b)));
            prop_assert_eq!(decode(&uri).unwrap(), name);
        }
    }
}
