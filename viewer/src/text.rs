//! A tiny built-in 5×7 bitmap font laid out as screen-space rectangles, for actor labels:
//! printable ASCII, the letters of Latin-1 but Ð, ð, Þ and þ (`é`, `ñ`, `ø`, `ß`…) and the caron and acute
//! letters of Central European names (`č`, `š`, `ž`, `ř`, `ń`…). Other characters are
//! drawn as `?`.
//!
//! An accented letter is its base glyph with a two-row mark composed over it (under it
//! for the cedilla): over a capital the mark takes the two rows of the label panel's
//! padding above the cell, over a small letter the two rows above its x-height, so that
//! no letter is squeezed and no line grows.

/// Glyph columns for ASCII 32 (space) to 126 (`~`); bit 0 is the top row.
const GLYPHS: [[u8; 5]; 95] = [
    [0x00, 0x00, 0x00, 0x00, 0x00], // space
    [0x00, 0x00, 0x5F, 0x00, 0x00], // !
    [0x00, 0x07, 0x00, 0x07, 0x00], // "
    [0x14, 0x7F, 0x14, 0x7F, 0x14], // #
    [0x24, 0x2A, 0x7F, 0x2A, 0x12], // $
    [0x23, 0x13, 0x08, 0x64, 0x62], // %
    [0x36, 0x49, 0x55, 0x22, 0x50], // &
    [0x00, 0x05, 0x03, 0x00, 0x00], // '
    [0x00, 0x1C, 0x22, 0x41, 0x00], // (
    [0x00, 0x41, 0x22, 0x1C, 0x00], // )
    [0x08, 0x2A, 0x1C, 0x2A, 0x08], // *
    [0x08, 0x08, 0x3E, 0x08, 0x08], // +
    [0x00, 0x50, 0x30, 0x00, 0x00], // ,
    [0x08, 0x08, 0x08, 0x08, 0x08], // -
    [0x00, 0x60, 0x60, 0x00, 0x00], // .
    [0x20, 0x10, 0x08, 0x04, 0x02], // /
    [0x3E, 0x51, 0x49, 0x45, 0x3E], // 0
    [0x00, 0x42, 0x7F, 0x40, 0x00], // 1
    [0x42, 0x61, 0x51, 0x49, 0x46], // 2
    [0x21, 0x41, 0x45, 0x4B, 0x31], // 3
    [0x18, 0x14, 0x12, 0x7F, 0x10], // 4
    [0x27, 0x45, 0x45, 0x45, 0x39], // 5
    [0x3C, 0x4A, 0x49, 0x49, 0x30], // 6
    [0x01, 0x71, 0x09, 0x05, 0x03], // 7
    [0x36, 0x49, 0x49, 0x49, 0x36], // 8
    [0x06, 0x49, 0x49, 0x29, 0x1E], // 9
    [0x00, 0x36, 0x36, 0x00, 0x00], // :
    [0x00, 0x56, 0x36, 0x00, 0x00], // ;
    [0x08, 0x14, 0x22, 0x41, 0x00], // <
    [0x14, 0x14, 0x14, 0x14, 0x14], // =
    [0x00, 0x41, 0x22, 0x14, 0x08], // >
    [0x02, 0x01, 0x51, 0x09, 0x06], // ?
    [0x32, 0x49, 0x79, 0x41, 0x3E], // @
    [0x7E, 0x11, 0x11, 0x11, 0x7E], // A
    [0x7F, 0x49, 0x49, 0x49, 0x36], // B
    [0x3E, 0x41, 0x41, 0x41, 0x22], // C
    [0x7F, 0x41, 0x41, 0x22, 0x1C], // D
    [0x7F, 0x49, 0x49, 0x49, 0x41], // E
    [0x7F, 0x09, 0x09, 0x09, 0x01], // F
    [0x3E, 0x41, 0x49, 0x49, 0x7A], // G
    [0x7F, 0x08, 0x08, 0x08, 0x7F], // H
    [0x00, 0x41, 0x7F, 0x41, 0x00], // I
    [0x20, 0x40, 0x41, 0x3F, 0x01], // J
    [0x7F, 0x08, 0x14, 0x22, 0x41], // K
    [0x7F, 0x40, 0x40, 0x40, 0x40], // L
    [0x7F, 0x02, 0x0C, 0x02, 0x7F], // M
    [0x7F, 0x04, 0x08, 0x10, 0x7F], // N
    [0x3E, 0x41, 0x41, 0x41, 0x3E], // O
    [0x7F, 0x09, 0x09, 0x09, 0x06], // P
    [0x3E, 0x41, 0x51, 0x21, 0x5E], // Q
    [0x7F, 0x09, 0x19, 0x29, 0x46], // R
    [0x46, 0x49, 0x49, 0x49, 0x31], // S
    [0x01, 0x01, 0x7F, 0x01, 0x01], // T
    [0x3F, 0x40, 0x40, 0x40, 0x3F], // U
    [0x1F, 0x20, 0x40, 0x20, 0x1F], // V
    [0x3F, 0x40, 0x38, 0x40, 0x3F], // W
    [0x63, 0x14, 0x08, 0x14, 0x63], // X
    [0x07, 0x08, 0x70, 0x08, 0x07], // Y
    [0x61, 0x51, 0x49, 0x45, 0x43], // Z
    [0x00, 0x7F, 0x41, 0x41, 0x00], // [
    [0x02, 0x04, 0x08, 0x10, 0x20], // backslash
    [0x00, 0x41, 0x41, 0x7F, 0x00], // ]
    [0x04, 0x02, 0x01, 0x02, 0x04], // ^
    [0x40, 0x40, 0x40, 0x40, 0x40], // _
    [0x00, 0x01, 0x02, 0x04, 0x00], // `
    [0x20, 0x54, 0x54, 0x54, 0x78], // a
    [0x7F, 0x48, 0x44, 0x44, 0x38], // b
    [0x38, 0x44, 0x44, 0x44, 0x20], // c
    [0x38, 0x44, 0x44, 0x48, 0x7F], // d
    [0x38, 0x54, 0x54, 0x54, 0x18], // e
    [0x08, 0x7E, 0x09, 0x01, 0x02], // f
    [0x0C, 0x52, 0x52, 0x52, 0x3E], // g
    [0x7F, 0x08, 0x04, 0x04, 0x78], // h
    [0x00, 0x44, 0x7D, 0x40, 0x00], // i
    [0x20, 0x40, 0x44, 0x3D, 0x00], // j
    [0x7F, 0x10, 0x28, 0x44, 0x00], // k
    [0x00, 0x41, 0x7F, 0x40, 0x00], // l
    [0x7C, 0x04, 0x18, 0x04, 0x78], // m
    [0x7C, 0x08, 0x04, 0x04, 0x78], // n
    [0x38, 0x44, 0x44, 0x44, 0x38], // o
    [0x7C, 0x14, 0x14, 0x14, 0x08], // p
    [0x08, 0x14, 0x14, 0x18, 0x7C], // q
    [0x7C, 0x08, 0x04, 0x04, 0x08], // r
    [0x48, 0x54, 0x54, 0x54, 0x20], // s
    [0x04, 0x3F, 0x44, 0x40, 0x20], // t
    [0x3C, 0x40, 0x40, 0x20, 0x7C], // u
    [0x1C, 0x20, 0x40, 0x20, 0x1C], // v
    [0x3C, 0x40, 0x30, 0x40, 0x3C], // w
    [0x44, 0x28, 0x10, 0x28, 0x44], // x
    [0x0C, 0x50, 0x50, 0x50, 0x3C], // y
    [0x44, 0x64, 0x54, 0x4C, 0x44], // z
    [0x00, 0x08, 0x36, 0x41, 0x00], // {
    [0x00, 0x00, 0x7F, 0x00, 0x00], // |
    [0x00, 0x41, 0x36, 0x08, 0x00], // }
    [0x08, 0x04, 0x08, 0x10, 0x08], // ~
];

/// Font pixels per character cell, horizontally (5 + 1 spacing) and vertically (7 + 2).
pub(crate) const CELL: (u32, u32) = (6, 9);

/// A filled screen rectangle in pixels: x, y (top-left), width, height.
pub(crate) type Rect = [f32; 4];

/// Letters that are not an ASCII letter with a mark, drawn whole (same layout as
/// [`GLYPHS`]).
const WHOLE: [(char, [u8; 5]); 6] = [
    ('\u{c6}', [0x7E, 0x09, 0x7F, 0x49, 0x41]),  // Æ
    ('\u{e6}', [0x20, 0x54, 0x7C, 0x54, 0x58]),  // æ
    ('\u{d8}', [0x7E, 0x61, 0x59, 0x47, 0x3F]),  // Ø
    ('\u{f8}', [0x78, 0x64, 0x54, 0x4C, 0x3C]),  // ø
    ('\u{df}', [0x7E, 0x01, 0x49, 0x56, 0x20]),  // ß
    ('\u{131}', [0x00, 0x44, 0x7C, 0x40, 0x00]), // ı, the base of í, ì, î, ï
];

/// A diacritic composed with a base letter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mark {
    Grave,
    Acute,
    Circumflex,
    Tilde,
    Diaeresis,
    Ring,
    Caron,
    Cedilla,
}

impl Mark {
    /// The mark's two rows per glyph column: bit 0 the upper row, bit 1 the lower one.
    fn rows(self) -> [u16; 5] {
        match self {
            Mark::Grave => [0, 1, 2, 0, 0],
            Mark::Acute => [0, 0, 2, 1, 0],
            Mark::Circumflex => [0, 2, 1, 2, 0],
            Mark::Tilde => [0, 2, 1, 2, 1],
            Mark::Diaeresis => [0, 2, 0, 2, 0],
            Mark::Ring => [0, 3, 1, 3, 0],
            Mark::Caron => [0, 1, 2, 1, 0],
            Mark::Cedilla => [0, 2, 1, 0, 0],
        }
    }
}

/// The base letter and mark of an accented letter the font composes, if `c` is one.
fn decompose(c: char) -> Option<(char, Mark)> {
    use Mark::*;
    let (base, mark) = match c {
        'À' => ('A', Grave),
        'Á' => ('A', Acute),
        'Â' => ('A', Circumflex),
        'Ã' => ('A', Tilde),
        'Ä' => ('A', Diaeresis),
        'Å' => ('A', Ring),
        'Ç' => ('C', Cedilla),
        'Ć' => ('C', Acute),
        'Č' => ('C', Caron),
        'È' => ('E', Grave),
        'É' => ('E', Acute),
        'Ê' => ('E', Circumflex),
        'Ë' => ('E', Diaeresis),
        'Ě' => ('E', Caron),
        'Ì' => ('I', Grave),
        'Í' => ('I', Acute),
        'Î' => ('I', Circumflex),
        'Ï' => ('I', Diaeresis),
        'Ñ' => ('N', Tilde),
        'Ń' => ('N', Acute),
        'Ň' => ('N', Caron),
        'Ò' => ('O', Grave),
        'Ó' => ('O', Acute),
        'Ô' => ('O', Circumflex),
        'Õ' => ('O', Tilde),
        'Ö' => ('O', Diaeresis),
        'Ř' => ('R', Caron),
        'Ś' => ('S', Acute),
        'Š' => ('S', Caron),
        'Ù' => ('U', Grave),
        'Ú' => ('U', Acute),
        'Û' => ('U', Circumflex),
        'Ü' => ('U', Diaeresis),
        'Ů' => ('U', Ring),
        'Ý' => ('Y', Acute),
        'Ź' => ('Z', Acute),
        'Ž' => ('Z', Caron),
        'à' => ('a', Grave),
        'á' => ('a', Acute),
        'â' => ('a', Circumflex),
        'ã' => ('a', Tilde),
        'ä' => ('a', Diaeresis),
        'å' => ('a', Ring),
        'ç' => ('c', Cedilla),
        'ć' => ('c', Acute),
        'č' => ('c', Caron),
        'è' => ('e', Grave),
        'é' => ('e', Acute),
        'ê' => ('e', Circumflex),
        'ë' => ('e', Diaeresis),
        'ě' => ('e', Caron),
        'ì' => ('ı', Grave),
        'í' => ('ı', Acute),
        'î' => ('ı', Circumflex),
        'ï' => ('ı', Diaeresis),
        'ñ' => ('n', Tilde),
        'ń' => ('n', Acute),
        'ň' => ('n', Caron),
        'ò' => ('o', Grave),
        'ó' => ('o', Acute),
        'ô' => ('o', Circumflex),
        'õ' => ('o', Tilde),
        'ö' => ('o', Diaeresis),
        'ř' => ('r', Caron),
        'ś' => ('s', Acute),
        'š' => ('s', Caron),
        'ù' => ('u', Grave),
        'ú' => ('u', Acute),
        'û' => ('u', Circumflex),
        'ü' => ('u', Diaeresis),
        'ů' => ('u', Ring),
        'ý' => ('y', Acute),
        'ÿ' => ('y', Diaeresis),
        'ź' => ('z', Acute),
        'ž' => ('z', Caron),
        _ => return None,
    };
    Some((base, mark))
}

/// Rows a glyph column may use: two above the cell (for the marks of capitals), the
/// seven of the cell and two below it (the cedilla).
const ROWS: u32 = 11;
/// The cell's top row in a glyph column of [`glyph`]: bits below it are above the cell.
const TOP: u32 = 2;

/// The columns of `c`'s glyph, bit `TOP + r` for cell row `r` (rows above the cell are
/// negative).
fn glyph(c: char) -> [u16; 5] {
    let cell = |bits: &[u8; 5]| bits.map(|b| u16::from(b) << TOP);
    let plain = |c: char| -> Option<&'static [u8; 5]> {
        match c as u32 {
            i @ 32..=126 => Some(&GLYPHS[(i - 32) as usize]),
            _ => WHOLE.iter().find(|(w, _)| *w == c).map(|(_, g)| g),
        }
    };
    if let Some((base, mark)) = decompose(c) {
        let mut columns = cell(plain(base).expect("every base letter has a glyph"));
        // Over a capital, the two rows above the cell; over a small letter, the two
        // above its x-height (row 2); the cedilla, the two below the cell.
        let at = match mark {
            Mark::Cedilla => TOP + 7,
            _ if base.is_ascii_uppercase() => 0,
            _ => TOP,
        };
        for (column, rows) in columns.iter_mut().zip(mark.rows()) {
            *column |= rows << at;
        }
        return columns;
    }
    cell(plain(c).unwrap_or(&GLYPHS[('?' as u32 - 32) as usize]))
}

/// The rectangles that draw `text` with its top-left corner at `(x, y)`, each font
/// pixel `scale` screen pixels; vertical runs of a glyph column are merged.
pub(crate) fn layout(text: &str, x: f32, y: f32, scale: f32, out: &mut Vec<Rect>) {
    for (i, c) in text.chars().enumerate() {
        let gx = x + (i as u32 * CELL.0) as f32 * scale;
        for (col, bits) in glyph(c).iter().enumerate() {
            let mut row = 0;
            while row < ROWS {
                if bits >> row & 1 == 0 {
                    row += 1;
                    continue;
                }
                let start = row;
                while row < ROWS && bits >> row & 1 == 1 {
                    row += 1;
                }
                out.push([
                    gx + col as f32 * scale,
                    y + (start as f32 - TOP as f32) * scale,
                    scale,
                    (row - start) as f32 * scale,
                ]);
            }
        }
    }
}

/// Width and height in screen pixels of `text` at `scale`: the cells' (marks above
/// capitals and cedillas fall in the label panel's padding).
pub(crate) fn size(text: &str, scale: f32) -> (f32, f32) {
    let n = text.chars().count() as u32;
    (
        (n * CELL.0).saturating_sub(1) as f32 * scale,
        (CELL.1 - 2) as f32 * scale,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_lay_out_as_merged_column_runs() {
        let mut r = Vec::new();
        layout("I", 10.0, 20.0, 2.0, &mut r);
        // `I`: a full-height stem plus the top and bottom serifs on each side.
        assert_eq!(r.len(), 5);
        assert!(r.contains(&[14.0, 20.0, 2.0, 14.0]));
        r.clear();
        layout(" ", 0.0, 0.0, 1.0, &mut r);
        assert!(r.is_empty());
        layout("\u{2603}", 0.0, 0.0, 1.0, &mut r);
        let mut question = Vec::new();
        layout("?", 0.0, 0.0, 1.0, &mut question);
        assert_eq!(r, question, "a character the font lacks draws as ?");
        assert_eq!(size("ab", 2.0), (22.0, 14.0));
    }

    /// The pixels of `text` drawn at scale 1 from (0, 0), as (column, row).
    fn pixels(text: &str) -> std::collections::BTreeSet<(i32, i32)> {
        let mut rects = Vec::new();
        layout(text, 0.0, 0.0, 1.0, &mut rects);
        rects
            .iter()
            .flat_map(|r| (0..r[3] as i32).map(move |dy| (r[0] as i32, r[1] as i32 + dy)))
            .collect()
    }

    #[test]
    fn accented_letters_are_their_base_letter_with_a_mark() {
        for (accented, base) in [("é", "e"), ("Ö", "O"), ("ñ", "n"), ("Č", "C"), ("ç", "c")] {
            let (a, b) = (pixels(accented), pixels(base));
            assert!(a.is_superset(&b), "{accented} holds {base}");
            assert!(a.len() > b.len(), "{accented} has a mark");
            assert_ne!(a, pixels("?"), "{accented} is not drawn as ?");
        }
        // Marks sit above a small letter's x-height, in the two rows above a capital,
        // and a cedilla under the cell.
        assert!(pixels("é")
            .difference(&pixels("e"))
            .all(|&(_, y)| (0..2).contains(&y)));
        assert!(pixels("É")
            .difference(&pixels("E"))
            .all(|&(_, y)| (-2..0).contains(&y)));
        assert!(pixels("Ç")
            .difference(&pixels("C"))
            .all(|&(_, y)| (7..9).contains(&y)));
        // Marks tell letters apart, and í has no dot under its accent.
        let marks = ["è", "é", "ê", "ë", "ě"].map(pixels);
        for (i, a) in marks.iter().enumerate() {
            assert!(marks[i + 1..].iter().all(|b| a != b), "{i}");
        }
        assert!(pixels("i").contains(&(2, 0)) && !pixels("í").contains(&(2, 0)));
        // Every letter the font composes has its base glyph.
        for c in '\u{c0}'..='\u{17f}' {
            glyph(c);
        }
        for whole in ["Æ", "æ", "Ø", "ø", "ß"] {
            assert_ne!(pixels(whole), pixels("?"), "{whole}");
        }
    }
}
