//! Lua string patterns whose matching would run away, refused before they run.
//!
//! The sandbox counts VM instructions (`runtime/lua/src/sandbox.rs`), but `string.find`,
//! `string.match`, `string.gmatch` and `string.gsub` match inside Lua's C library, where
//! no instruction is counted: `("a"):rep(40):find(("a*"):rep(40) .. "b")` backtracks
//! through some 10²² ways of sharing 40 letters among 40 repetitions, and the tick never
//! ends. So each of them first counts, on the subject and pattern it was given, how many
//! times Lua's matcher would try an item if every attempt failed (its worst case), and
//! refuses the call when that is more than [`PATTERN_STEPS`].
//!
//! The count follows the matcher (`lstrlib.c`, `match`): a single-character item tries
//! once; `*`, `-` and `+` try every length of the run of characters their class matches
//! there (greedy or lazy, failing they try them all), `?` both; anchors, captures,
//! frontiers and balances branch nowhere. Per start position, item by item from the
//! pattern's end, it needs one pass over the subject per item (prefix sums over the run
//! lengths), so it costs far less than the matching it guards. Where a count cannot be
//! known (a back-reference's length) it counts the item as ending the match there, which
//! undercounts nothing that branches.

use crate::args::err;
use crate::sandbox::Sandbox;
use mlua::{Function, Lua, MultiValue, Table, Value};
use std::sync::Arc;

/// The most item attempts a call may make in the worst case (about a tenth of a second of
/// matching): a hundred thousand characters searched with three repetitions that each
/// match little, or a few thousand with `.-` twice, pass.
pub const PATTERN_STEPS: f64 = 5e7;

/// One item of a pattern: what a single character must be, and how often.
#[derive(Clone, Debug, PartialEq)]
enum Item {
    /// One character of the class.
    One(Class),
    /// Any run of the class, longest (`*`) or shortest (`-`) first.
    Any(Class),
    /// A run of one or more (`+`).
    Some(Class),
    /// One or none (`?`).
    Maybe(Class),
    /// An item that does not branch but whose length is known only when matching (`%bxy`,
    /// which scans on to its closing character, or a back-reference): counted as ending
    /// wherever the rest costs most.
    Unknown {
        /// Whether it scans the subject to find its end (`%b`).
        scans: bool,
    },
    /// An item that matches no character and does not branch (`%f[set]`, the end anchor).
    Empty,
    /// A malformed item: Lua raises its error when the matcher reaches it, after trying
    /// everything before it.
    Malformed,
}

/// A character class.
#[derive(Clone, Debug, PartialEq)]
enum Class {
    /// Any character (`.`).
    Any,
    /// One character.
    Literal(u8),
    /// `%a`, `%d`, … (the letter; upper case negates).
    Escape(u8),
    /// `[set]`: its ranges and escapes, negated with `^`.
    Set {
        negated: bool,
        ranges: Vec<(u8, u8)>,
        escapes: Vec<u8>,
    },
}

impl Class {
    /// Whether character `c` is of the class (Lua's C locale).
    fn matches(&self, c: u8) -> bool {
        match self {
            Class::Any => true,
            Class::Literal(l) => c == *l,
            Class::Escape(e) => escape_matches(*e, c),
            Class::Set {
                negated,
                ranges,
                escapes,
            } => {
                let inside = ranges.iter().any(|&(lo, hi)| lo <= c && c <= hi)
                    || escapes.iter().any(|&e| escape_matches(e, c));
                inside != *negated
            }
        }
    }
}

/// Whether `c` is of the class `%e` (`%A` is everything `%a` is not; an escaped
/// non-letter is that character).
fn escape_matches(e: u8, c: u8) -> bool {
    let of = match e.to_ascii_lowercase() {
        b'a' => c.is_ascii_alphabetic(),
        b'c' => c.is_ascii_control(),
        b'd' => c.is_ascii_digit(),
        b'g' => c.is_ascii_graphic(),
        b'l' => c.is_ascii_lowercase(),
        b'p' => c.is_ascii_punctuation(),
        b's' => c.is_ascii_whitespace() || c == 0x0b,
        b'u' => c.is_ascii_uppercase(),
        b'w' => c.is_ascii_alphanumeric(),
        b'x' => c.is_ascii_hexdigit(),
        _ => return c == e,
    };
    if e.is_ascii_uppercase() {
        !of
    } else {
        of
    }
}

/// A pattern's items, and whether it is anchored at the start (`^`, which only `find`,
/// `match` and `gsub` read as an anchor: `gmatch` takes it as the character); a
/// malformed item ends the list.
fn parse(pattern: &[u8], anchors: bool) -> (Vec<Item>, bool) {
    let anchored = anchors && pattern.first() == Some(&b'^');
    let mut items = Vec::new();
    if parse_items(pattern, usize::from(anchored), &mut items).is_none() {
        items.push(Item::Malformed);
    }
    (items, anchored)
}

/// Appends the items of `pattern` from byte `p` on to `items`; `None` at a malformed one.
fn parse_items(pattern: &[u8], mut p: usize, items: &mut Vec<Item>) -> Option<()> {
    while p < pattern.len() {
        let class = match pattern[p] {
            b'(' | b')' => {
                p += 1;
                continue;
            }
            b'$' if p + 1 == pattern.len() => {
                items.push(Item::Empty);
                break;
            }
            b'%' => {
                let e = *pattern.get(p + 1)?;
                match e {
                    b'b' => {
                        pattern.get(p + 3)?;
                        items.push(Item::Unknown { scans: true });
                        p += 4;
                        continue;
                    }
                    b'f' => {
                        if pattern.get(p + 2) != Some(&b'[') {
                            return None;
                        }
                        let (_, end) = set(pattern, p + 2)?;
                        items.push(Item::Empty);
                        p = end;
                        continue;
                    }
                    b'0'..=b'9' => {
                        items.push(Item::Unknown { scans: false });
                        p += 2;
                        continue;
                    }
                    _ => {
                        p += 2;
                        Class::Escape(e)
                    }
                }
            }
            b'[' => {
                let (class, end) = set(pattern, p)?;
                p = end;
                class
            }
            b'.' => {
                p += 1;
                Class::Any
            }
            c => {
                p += 1;
                Class::Literal(c)
            }
        };
        let item = match pattern.get(p) {
            Some(b'*') | Some(b'-') => Item::Any(class),
            Some(b'+') => Item::Some(class),
            Some(b'?') => Item::Maybe(class),
            _ => {
                items.push(Item::One(class));
                continue;
            }
        };
        p += 1;
        items.push(item);
    }
    Some(())
}

/// The set class starting at `pattern[open]` (`[`), and the index past its `]`.
fn set(pattern: &[u8], open: usize) -> Option<(Class, usize)> {
    let mut p = open + 1;
    let negated = pattern.get(p) == Some(&b'^');
    if negated {
        p += 1;
    }
    let (mut ranges, mut escapes) = (Vec::new(), Vec::new());
    let mut first = true;
    loop {
        let c = *pattern.get(p)?;
        if c == b']' && !first {
            return Some((
                Class::Set {
                    negated,
                    ranges,
                    escapes,
                },
                p + 1,
            ));
        }
        first = false;
        if c == b'%' {
            escapes.push(*pattern.get(p + 1)?);
            p += 2;
        } else if pattern.get(p + 1) == Some(&b'-')
            && pattern.get(p + 2).is_some_and(|&h| h != b']')
        {
            ranges.push((c, pattern[p + 2]));
            p += 3;
        } else {
            ranges.push((c, c));
            p += 1;
        }
    }
}

/// How many item attempts (and characters a balance scans) Lua's matcher makes in the
/// worst case matching `pattern` in `subject` from byte `init` on (each start position in
/// turn unless anchored, `anchors` saying whether a leading `^` anchors), up to `limit`
/// (the count stops growing there).
pub fn worst_attempts(
    subject: &[u8],
    pattern: &[u8],
    init: usize,
    anchors: bool,
    limit: f64,
) -> f64 {
    let (items, anchored) = parse(pattern, anchors);
    count(subject, (&items, anchored), init, limit)
}

/// [`worst_attempts`] of the parsed pattern `items` (`anchored` or not).
fn count(subject: &[u8], (items, anchored): (&[Item], bool), init: usize, limit: f64) -> f64 {
    let n = subject.len();
    let branches = |item: &Item| {
        matches!(
            item,
            Item::Any(_) | Item::Some(_) | Item::Maybe(_) | Item::Unknown { scans: true }
        )
    };
    if !items.iter().any(branches) {
        // Each start tries each item at most once (none scans).
        let starts = if anchored {
            1
        } else {
            (n + 1).saturating_sub(init)
        };
        return (starts as f64 * (items.len() + 1) as f64).min(limit);
    }
    // after[p]: attempts for the items after the current one, from position p (row by row
    // from the pattern's end); prefix sums of it for the runs.
    let mut after = vec![1.0f64; n + 2];
    let mut now = vec![0.0f64; n + 2];
    let mut sums = vec![0.0f64; n + 3];
    // The run of `class` starting at each position (computed from the end).
    let mut run = vec![0usize; n + 1];
    let mut most = vec![0.0f64; n + 2];
    for item in items.iter().rev() {
        let class = match item {
            Item::One(c) | Item::Any(c) | Item::Some(c) | Item::Maybe(c) => Some(c),
            Item::Unknown { .. } | Item::Empty | Item::Malformed => None,
        };
        if let Some(class) = class {
            run[n] = 0;
            for p in (0..n).rev() {
                run[p] = if class.matches(subject[p]) {
                    run[p + 1] + 1
                } else {
                    0
                };
            }
        }
        sums[0] = 0.0;
        for p in 0..=n {
            sums[p + 1] = (sums[p] + after[p]).min(limit);
        }
        // The most the rest costs from p or later (for an item of unknown length).
        if matches!(item, Item::Unknown { .. }) {
            most[n + 1] = 0.0;
            for p in (0..=n).rev() {
                most[p] = most[p + 1].max(after[p]);
            }
        }
        // Attempts at positions p..=p+len of the next items (a sum that reached the limit
        // stays there: its difference would undercount).
        let span = |p: usize, len: usize| {
            if sums[p + len + 1] >= limit {
                limit
            } else {
                sums[p + len + 1] - sums[p]
            }
        };
        for p in 0..=n {
            let r = if p < n { run[p] } else { 0 };
            now[p] = 1.0
                + match item {
                    Item::One(_) if r > 0 => after[p + 1],
                    Item::One(_) => 0.0,
                    Item::Any(_) => span(p, r),
                    Item::Some(_) if r > 0 => span(p + 1, r - 1),
                    Item::Some(_) => 0.0,
                    Item::Maybe(_) if r > 0 => after[p] + after[p + 1],
                    Item::Maybe(_) => after[p],
                    Item::Empty => after[p],
                    Item::Unknown { scans } => most[p] + if *scans { (n - p) as f64 } else { 0.0 },
                    Item::Malformed => 0.0,
                };
            now[p] = now[p].min(limit);
        }
        std::mem::swap(&mut after, &mut now);
    }
    let starts = if anchored {
        init..=init.min(n)
    } else {
        init.min(n)..=n
    };
    starts.fold(0.0, |total, p| (total + after[p]).min(limit))
}

/// Wraps `string.find`, `string.match`, `string.gmatch` and `string.gsub` of `lua` so
/// that a call whose matching could run away is refused, naming how far, and each call
/// charges its subject's length to `sandbox`'s instruction budget (a loop of passes over
/// a long string is C work the budget's hook does not see).
pub(crate) fn guard(lua: &Lua, sandbox: &Arc<Sandbox>) -> mlua::Result<()> {
    let string: Table = lua.globals().get("string")?;
    for name in ["find", "match", "gmatch", "gsub"] {
        let original: Function = string.get(name)?;
        let method = format!("string.{name}");
        let sandbox = sandbox.clone();
        let guarded = lua.create_function(move |lua, args: MultiValue| {
            let work = check(&method, &args)?;
            if let Some(limit) = sandbox.charge(lua, work) {
                return Err(mlua::Error::runtime(limit));
            }
            original.call::<MultiValue>(args)
        })?;
        string.set(name, guarded)?;
    }
    Ok(())
}

/// Refuses the call of `method` with `args` (subject, pattern, init, plain) if its
/// matching could take more than [`PATTERN_STEPS`] attempts; else the work to charge to
/// the budget: the subject's length, which the call passes over at least, or a tenth of
/// its worst case if more (so that a loop of calls each just under the bound is stopped).
fn check(method: &str, args: &MultiValue) -> mlua::Result<u64> {
    let text = |v: Option<&Value>| match v {
        Some(Value::String(s)) => Some(s.as_bytes().to_vec()),
        Some(Value::Integer(i)) => Some(i.to_string().into_bytes()),
        Some(Value::Number(x)) => Some(x.to_string().into_bytes()),
        _ => None,
    };
    let (Some(subject), Some(pattern)) = (text(args.front()), text(args.get(1))) else {
        // Lua says what is wrong with them.
        return Ok(0);
    };
    let length = subject.len() as u64;
    // Lua's truth: anything but nil and false.
    let plain = method == "string.find"
        && args
            .get(3)
            .is_some_and(|v| !matches!(v, Value::Nil | Value::Boolean(false)));
    if plain {
        return Ok(length);
    }
    // `init` (find and match): 1-based, negative from the end.
    let n = subject.len() as i64;
    let init = match args.get(2) {
        Some(Value::Integer(i)) if method != "string.gsub" && method != "string.gmatch" => *i,
        Some(Value::Number(x)) if method != "string.gsub" && method != "string.gmatch" => *x as i64,
        _ => 1,
    };
    let init = if init > 0 {
        init - 1
    } else if init < 0 {
        (n + init).max(0)
    } else {
        0
    };
    // The count itself takes a pass over the subject per item.
    let (items, anchored) = parse(&pattern, method != "string.gmatch");
    if items.len() as f64 * (subject.len() as f64 + 1.0) > PATTERN_STEPS {
        return Err(err(
            method,
            format!(
                "a pattern of {} items on a {}-byte string is more than a script may \
                 match in one call ({PATTERN_STEPS:e} steps)",
                items.len(),
                subject.len()
            ),
        ));
    }
    let limit = PATTERN_STEPS * 10.0;
    let attempts = count(&subject, (&items, anchored), init as usize, limit);
    if attempts > PATTERN_STEPS {
        return Err(err(
            method,
            format!(
                "the pattern could take {} steps on a {}-byte string, more than a script \
                 may ({PATTERN_STEPS:e}): its repetitions (`*`, `-`, `+`, `?`) can share \
                 the same characters in too many ways; anchor it, or repeat less",
                if attempts >= PATTERN_STEPS * 10.0 {
                    format!("over {:e}", PATTERN_STEPS * 10.0)
                } else {
                    format!("{attempts:.1e}")
                },
                subject.len()
            ),
        ));
    }
    Ok(length.max((attempts / 10.0) as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attempts(subject: &str, pattern: &str) -> f64 {
        worst_attempts(subject.as_bytes(), pattern.as_bytes(), 0, true, 1e30)
    }

    #[test]
    fn a_literal_tries_each_start_and_a_repetition_each_length() {
        // Without repetitions, each of the 4 starts tries the item and the end at most.
        assert_eq!(attempts("abc", "b"), 4.0 * 2.0);
        // "^a*" on "aaa": the star, then the end after each of its 4 lengths.
        assert_eq!(attempts("aaa", "^a*"), 1.0 + 4.0);
        // "a*b" on "aaaa": at start p the run is 4 − p, each length then tries `b`.
        // Σ over starts 0..=4 of (1 + (run + 1)) = (1+5)+(1+4)+(1+3)+(1+2)+(1+1).
        assert_eq!(attempts("aaaa", "a*b"), 20.0);
    }

    #[test]
    fn many_repetitions_of_one_class_are_counted_in_the_astronomical_ways_they_share_it() {
        let subject = "a".repeat(40);
        let pattern = format!("{}b", "a*".repeat(40));
        assert!(attempts(&subject, &pattern) > 1e20);
        // Anchored and with other classes between, the same number of stars is cheap.
        assert!(attempts("key = value; other = thing", "^%s*(%w+)%s*=%s*(%w+)") < 1e3);
        let long = "x".repeat(10_000) + " ";
        assert!(attempts(&long, "^%s*(.-)%s*$") < 1e9);
    }

    #[test]
    fn sets_escapes_captures_and_anchors_parse_as_lua_reads_them() {
        let (items, anchored) = parse(b"^([%a_][%w_]*)%s*=%f[%w]%b()%1.?$", true);
        assert!(anchored);
        assert_eq!(items.len(), 9, "{items:?}");
        assert!(matches!(items[1], Item::Any(Class::Set { .. })));
        assert_eq!(items[2], Item::Any(Class::Escape(b's')));
        assert_eq!(items[4], Item::Empty); // %f
        assert_eq!(items[5], Item::Unknown { scans: true }); // %b()
        assert_eq!(items[6], Item::Unknown { scans: false }); // %1
        assert_eq!(items[7], Item::Maybe(Class::Any));
        assert_eq!(items[8], Item::Empty); // $
                                           // A set with `]` first, a range and an escape.
        let (class, end) = set(b"[]a-c%d]x", 0).unwrap();
        assert_eq!(end, 8);
        for (c, yes) in [(b']', true), (b'b', true), (b'7', true), (b'x', false)] {
            assert_eq!(class.matches(c), yes, "{}", c as char);
        }
        // Malformed: Lua raises its error only when the matcher gets there.
        assert_eq!(parse(b"a*[abc", true).0.last(), Some(&Item::Malformed));
        // gmatch reads a leading `^` as the character.
        let caret = vec![
            Item::One(Class::Literal(b'^')),
            Item::One(Class::Literal(b'a')),
        ];
        assert_eq!(parse(b"^a", false), (caret, false));
    }

    #[test]
    fn what_follows_a_malformed_item_a_balance_or_a_back_reference_is_still_counted() {
        let stars = "a*".repeat(30);
        let letters = "a".repeat(30);
        // The repetitions before a malformed item are tried before Lua reaches it.
        assert!(attempts(&letters, &format!("{stars}b%")) > 1e15);
        // After a balance or a back-reference, the rest is counted where it costs most.
        assert!(attempts(&format!("(){letters}"), &format!("%b(){stars}b")) > 1e15);
        assert!(attempts(&letters, &format!("(a)%1{stars}b")) > 1e15);
        // A balance scans on to its closing character: that is counted too.
        assert!(attempts(&"(".repeat(10_000), "%b()") > 1e7);
        // gmatch does not anchor: every start is tried.
        let caret = format!("^{letters}");
        let pattern = format!("^{stars}b");
        assert!(worst_attempts(caret.as_bytes(), pattern.as_bytes(), 0, false, 1e30) > 1e15);
    }
}
