//! Bidirectional text (Unicode's algorithm, UAX #9, through the `unicode-bidi` crate): a line's
//! level runs in the order they are seen, left to right. A Hebrew or Arabic title reads right to
//! left while the numbers in it keep their own order: "שלום 2020 (2000)" is seen as
//! "(2000) 2020 םולש" (the word's letters right to left, the brackets mirrored).
//!
//! The runs keep their text in logical order; whoever shapes a run shapes it in its direction
//! (a right-to-left run's glyphs come out of the shaper right to left). [`mirrored`] gives the
//! mirror image of the brackets and signs a right-to-left run shows reversed, for those who lay
//! out a run's characters themselves.

use std::ops::Range;

use unicode_bidi::BidiInfo;

/// A level run of one direction: its byte range in the text, in logical order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Run {
    pub range: Range<usize>,
    pub rtl: bool,
}

/// The level runs of `text` in visual order (left to right), paragraph after paragraph. The
/// paragraph's direction is its first strong letter's (left to right where none is).
pub fn visual_runs(text: &str) -> Vec<Run> {
    if text.is_empty() {
        return Vec::new();
    }
    // Nothing before Hebrew (U+0590) is right to left or a direction control: most labels
    // ("-30 dB", "time (s)") are one run without the algorithm's cost.
    if text.chars().all(|c| u32::from(c) < 0x0590) {
        return vec![Run {
            range: 0..text.len(),
            rtl: false,
        }];
    }
    let info = BidiInfo::new(text, None);
    if !info.has_rtl() {
        return vec![Run {
            range: 0..text.len(),
            rtl: false,
        }];
    }
    let mut runs = Vec::new();
    for paragraph in &info.paragraphs {
        let (levels, level_runs) = info.visual_runs(paragraph, paragraph.range.clone());
        for range in level_runs {
            let rtl = levels[range.start].is_rtl();
            runs.push(Run { range, rtl });
        }
    }
    runs
}

/// `text` as it is seen, left to right: each right-to-left run's characters reversed and
/// mirrored. For tests and for a reader of the visual order; shaping goes by [`visual_runs`]
/// (combining marks stay after their letter there, not here).
pub fn visual_order(text: &str) -> String {
    let mut seen = String::with_capacity(text.len());
    for run in visual_runs(text) {
        let part = &text[run.range];
        if run.rtl {
            seen.extend(part.chars().rev().map(mirrored));
        } else {
            seen.push_str(part);
        }
    }
    seen
}

/// The mirror image of `c` where a right-to-left run shows it (Unicode's Bidi_Mirroring_Glyph,
/// the pairs a title is likely to hold); `c` itself otherwise.
pub fn mirrored(c: char) -> char {
    const PAIRS: [(char, char); 14] = [
        ('(', ')'),
        ('[', ']'),
        ('{', '}'),
        ('<', '>'),
        ('«', '»'),
        ('‹', '›'),
        ('≤', '≥'),
        ('⁅', '⁆'),
        ('⁽', '⁾'),
        ('₍', '₎'),
        ('⟨', '⟩'),
        ('〈', '〉'),
        ('《', '》'),
        ('「', '」'),
    ];
    for (open, close) in PAIRS {
        if c == open {
            return close;
        }
        if c == close {
            return open;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hebrew_title_reads_right_to_left_and_its_numbers_left_to_right() {
        // The picture drew "(0002) 0202" and boxes: the whole line was reversed.
        assert_eq!(visual_order("שלום 2020 (2000)"), "(2000) 2020 םולש");
        let runs = visual_runs("שלום 2020 (2000)");
        // Right to left overall: the last number is seen first, the word last.
        let first = runs.first().expect("runs");
        let last = runs.last().expect("runs");
        assert!(!first.rtl || first.range.start > 0, "{runs:?}");
        assert!(last.rtl && last.range.start == 0, "{runs:?}");
        // Each number is one left-to-right run, in its own order.
        let text = "שלום 2020 (2000)";
        let numbers: Vec<&str> = runs
            .iter()
            .filter(|r| !r.rtl)
            .map(|r| &text[r.range.clone()])
            .collect();
        assert_eq!(numbers, ["2000", "2020"]);
    }

    #[test]
    fn left_to_right_text_is_one_run_and_embedded_hebrew_is_reversed_in_place() {
        assert_eq!(
            visual_runs("Song (1984)"),
            [Run {
                range: 0..11,
                rtl: false
            }]
        );
        assert_eq!(visual_order("Song (1984)"), "Song (1984)");
        // A year right after a Hebrew word goes with it, brackets and all (UAX #9, rule N0):
        // browsers show the same.
        assert_eq!(visual_order("Best of שלום (1999)"), "Best of (1999) םולש");
        assert_eq!(visual_order("مرحبا 12"), "12 ابحرم");
        assert!(visual_runs("").is_empty());
    }
}
