//! Frame sets: the grammar of `render --frames` and `job --frames`, which is also what an Open
//! Job Description `CHUNK[INT]` task parameter expands to in `{{Task.Param.Frame}}`.
//!
//! `12` · `0-99` · `0-99:2` or `0-99x2` (every second frame, OpenJD's and Deadline's/Houdini's
//! spellings) · lists of those, `1,5,9-12`. A set prints in canonical form (`a`, `a-b`, `a-b:s`
//! joined by commas, with `:` for steps), which parses back to the same set.

use std::fmt;
use std::str::FromStr;

/// One term of a frame set: `start..=end` every `step` frames (`end` is on the grid).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: usize,
    /// Last frame (`start + k·step` for some k).
    pub end: usize,
    /// Distance between frames, at least 1.
    pub step: usize,
}

impl FrameRange {
    /// The frames of the range, in order.
    pub fn iter(&self) -> impl Iterator<Item = usize> + use<> {
        (self.start..=self.end).step_by(self.step)
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        (self.end - self.start) / self.step + 1
    }

    /// Never: a range has at least its first frame.
    pub fn is_empty(&self) -> bool {
        false
    }
}

impl fmt::Display for FrameRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.start == self.end, self.step) {
            (true, _) => write!(f, "{}", self.start),
            (false, 1) => write!(f, "{}-{}", self.start, self.end),
            (false, s) => write!(f, "{}-{}:{s}", self.start, self.end),
        }
    }
}

/// An ordered list of frame ranges, as written; frames listed twice are written once.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameSet {
    ranges: Vec<FrameRange>,
}

impl FrameSet {
    /// The inclusive range `start..=end`.
    ///
    /// # Panics
    /// When `start > end`; parse text with [`FrameSet::from_str`] to get an error instead.
    pub fn range(start: usize, end: usize) -> FrameSet {
        assert!(start <= end, "frame range {start}-{end} is reversed");
        FrameSet { ranges: vec![FrameRange { start, end, step: 1 }] }
    }

    /// The ranges as written.
    pub fn ranges(&self) -> &[FrameRange] {
        &self.ranges
    }

    /// Every frame, ascending, each once.
    pub fn frames(&self) -> Vec<usize> {
        let mut all: Vec<usize> = self.ranges.iter().flat_map(FrameRange::iter).collect();
        all.sort_unstable();
        all.dedup();
        all
    }

    /// The first (lowest) frame.
    pub fn first(&self) -> usize {
        self.ranges.iter().map(|r| r.start).min().unwrap_or(0)
    }

    /// The last (highest) frame.
    pub fn last(&self) -> usize {
        self.ranges.iter().map(|r| r.end).max().unwrap_or(0)
    }

    /// Whether `frame` is in the set.
    pub fn contains(&self, frame: usize) -> bool {
        self.ranges.iter().any(|r| frame >= r.start && frame <= r.end && (frame - r.start).is_multiple_of(r.step))
    }

    /// The frames cut into consecutive chunks of at most `size` frames (as a farm's tasks), each
    /// a set of its own; together they hold every frame exactly once.
    pub fn chunks(&self, size: usize) -> Vec<FrameSet> {
        let size = size.max(1);
        self.frames().chunks(size).map(FrameSet::from_frames).collect()
    }

    /// The set of exactly these frames (in any order, repeats allowed), in its shortest form;
    /// `None` when there are none.
    pub fn from_list(frames: &[usize]) -> Option<FrameSet> {
        let mut sorted = frames.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        (!sorted.is_empty()).then(|| FrameSet::from_frames(&sorted))
    }

    /// The smallest set of ranges holding exactly `frames` (ascending, distinct, non-empty).
    fn from_frames(frames: &[usize]) -> FrameSet {
        let mut ranges: Vec<FrameRange> = Vec::new();
        let mut i = 0;
        while i < frames.len() {
            let start = frames[i];
            let step = frames.get(i + 1).map_or(1, |n| n - start);
            let mut j = i;
            while j + 1 < frames.len() && frames[j + 1] - frames[j] == step {
                j += 1;
            }
            // A stepped run of two frames reads better as two frames ("4,9", not "4-9:5").
            if j == i + 1 && step > 1 {
                j = i;
            }
            ranges.push(FrameRange { start, end: frames[j], step: if j == i { 1 } else { step } });
            i = j + 1;
        }
        FrameSet { ranges }
    }
}

impl fmt::Display for FrameSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, r) in self.ranges.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            write!(f, "{r}")?;
        }
        Ok(())
    }
}

impl FromStr for FrameSet {
    type Err = String;

    fn from_str(text: &str) -> Result<FrameSet, String> {
        let mut ranges = Vec::new();
        for term in text.split(',') {
            let term = term.trim();
            if term.is_empty() {
                return Err(format!("frames \"{text}\": an empty entry; write e.g. 0-99, 12 or 1,5,9-12"));
            }
            ranges.push(parse_term(term)?);
        }
        Ok(FrameSet { ranges })
    }
}

fn number(t: &str, term: &str) -> Result<usize, String> {
    t.trim().parse::<usize>().map_err(|_| format!("frames \"{term}\": '{}' is not a frame number", t.trim()))
}

fn parse_term(term: &str) -> Result<FrameRange, String> {
    let (span, step) = match term.split_once(':').or_else(|| term.split_once('x')) {
        Some((span, step)) => (span, Some(number(step, term)?)),
        None => (term, None),
    };
    let (start, end) = match span.split_once('-') {
        Some((a, b)) => (number(a, term)?, number(b, term)?),
        None if step.is_some() => return Err(format!("frames \"{term}\": a step needs a range, as in 0-99:2")),
        None => {
            let f = number(span, term)?;
            (f, f)
        }
    };
    if start > end {
        return Err(format!("frames \"{term}\" is empty: the first frame is after the last (write {end}-{start})"));
    }
    let step = step.unwrap_or(1);
    if step == 0 {
        return Err(format!("frames \"{term}\": the step must be at least 1"));
    }
    // The last frame on the grid, so the range prints back as it iterates.
    Ok(FrameRange { start, end: start + (end - start) / step * step, step })
}

/// Frame numbers for a message: the first twelve, then how many more ("0, 1, … 11 and 8 more").
pub fn list_for_message(frames: &[usize]) -> String {
    let listed: Vec<String> = frames.iter().take(12).map(|f| f.to_string()).collect();
    let more = if frames.len() > listed.len() { format!(" and {} more", frames.len() - listed.len()) } else { String::new() };
    format!("{}{more}", listed.join(", "))
}

#[cfg(test)]
mod tests {
    #[test]
    fn message_lists_stop_after_twelve_frames() {
        assert_eq!(list_for_message(&[3, 17]), "3, 17");
        let many: Vec<usize> = (0..20).collect();
        assert_eq!(list_for_message(&many), "0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11 and 8 more");
    }

    use super::*;
    use proptest::prelude::*;

    fn frames(text: &str) -> Vec<usize> {
        text.parse::<FrameSet>().unwrap().frames()
    }

    #[test]
    fn parses_every_form() {
        assert_eq!(frames("12"), [12]);
        assert_eq!(frames("3-6"), [3, 4, 5, 6]);
        assert_eq!(frames("0-9:3"), [0, 3, 6, 9]);
        assert_eq!(frames("0-10x4"), [0, 4, 8]);
        assert_eq!(frames("1,5,9-12"), [1, 5, 9, 10, 11, 12]);
        assert_eq!(frames(" 7 , 2-3 "), [2, 3, 7]);
        assert_eq!(frames("4-6,5-8"), [4, 5, 6, 7, 8], "overlaps are written once");
    }

    #[test]
    fn prints_canonically() {
        assert_eq!("0-10x4".parse::<FrameSet>().unwrap().to_string(), "0-8:4");
        assert_eq!("1, 5,9-12".parse::<FrameSet>().unwrap().to_string(), "1,5,9-12");
        assert_eq!("7-7".parse::<FrameSet>().unwrap().to_string(), "7");
    }

    #[test]
    fn refuses_bad_text_with_the_reason() {
        let err = |t: &str| t.parse::<FrameSet>().unwrap_err();
        assert!(err("9-3").contains("the first frame is after the last"), "{}", err("9-3"));
        assert!(err("").contains("empty entry"));
        assert!(err("1,,2").contains("empty entry"));
        assert!(err("a-3").contains("'a' is not a frame number"));
        assert!(err("0-9:0").contains("at least 1"));
        assert!(err("5:2").contains("needs a range"));
        assert!(err("-3").contains("'' is not a frame number"));
    }

    #[test]
    fn chunks_of_an_open_jd_shape() {
        let set: FrameSet = "0-47".parse().unwrap();
        let chunks: Vec<String> = set.chunks(8).iter().map(ToString::to_string).collect();
        assert_eq!(chunks, ["0-7", "8-15", "16-23", "24-31", "32-39", "40-47"]);
        let odd: FrameSet = "0-20:2,3".parse().unwrap();
        assert_eq!(odd.chunks(4).iter().map(ToString::to_string).collect::<Vec<_>>(), ["0,2-4", "6-12:2", "14-20:2"]);
    }

    fn arb_set() -> impl Strategy<Value = FrameSet> {
        prop::collection::vec((0usize..500, 0usize..60, 1usize..6), 1..6).prop_map(|terms| FrameSet {
            ranges: terms
                .into_iter()
                .map(|(start, n, step)| FrameRange { start, end: start + n / step * step, step })
                .map(|r| if r.start == r.end { FrameRange { step: 1, ..r } } else { r })
                .collect(),
        })
    }

    proptest! {
        #[test]
        fn parse_after_print_is_the_identity(set in arb_set()) {
            let text = set.to_string();
            prop_assert_eq!(text.parse::<FrameSet>().unwrap(), set);
        }

        #[test]
        fn chunks_cover_the_frames_exactly_once(set in arb_set(), size in 1usize..40) {
            let chunks = set.chunks(size);
            let joined: Vec<usize> = chunks.iter().flat_map(FrameSet::frames).collect();
            prop_assert_eq!(&joined, &set.frames());
            prop_assert!(chunks.iter().all(|c| c.frames().len() <= size));
            // Each chunk survives the trip through its text, as a farm task receives it.
            for c in &chunks {
                prop_assert_eq!(c.to_string().parse::<FrameSet>().unwrap().frames(), c.frames());
            }
        }

        #[test]
        fn from_list_holds_exactly_the_frames(list in prop::collection::vec(0usize..300, 1..50)) {
            let set = FrameSet::from_list(&list).unwrap();
            let mut want = list.clone();
            want.sort_unstable();
            want.dedup();
            prop_assert_eq!(set.frames(), want);
        }

        #[test]
        fn contains_agrees_with_frames(set in arb_set(), probe in 0usize..600) {
            prop_assert_eq!(set.contains(probe), set.frames().contains(&probe));
        }
    }
}
