//! Edits of a robot file's text by byte ranges: what the URDF and MJCF writers use to give
//! the file back as it was but for what they replace.

/// Replacements of byte ranges of one text, applied in order of position; an edit that
/// overlaps an earlier one is dropped.
#[derive(Debug, Default)]
pub(crate) struct Edits {
    list: Vec<(usize, usize, String)>,
}

impl Edits {
    /// Replaces `start..end` by `new` (an insertion when they are equal).
    pub(crate) fn replace(&mut self, start: usize, end: usize, new: String) {
        self.list.push((start, end, new));
    }

    /// Replaces the element at `start..end` of `text` by `new`, taking whole lines when only
    /// blanks stand beside it (so that removing it leaves no empty line).
    pub(crate) fn replace_lines(&mut self, text: &str, start: usize, end: usize, new: String) {
        self.replace(line_start(text, start), line_end(text, end), new);
    }

    /// The text with every edit made.
    pub(crate) fn apply(mut self, text: &str) -> String {
        self.list.sort_by_key(|e| (e.0, e.1));
        let mut out = String::with_capacity(text.len());
        let mut pos = 0;
        for (s, e, new) in self.list {
            if s < pos {
                continue;
            }
            out.push_str(&text[pos..s]);
            out.push_str(&new);
            pos = e;
        }
        out.push_str(&text[pos..]);
        out
    }
}

/// The start of the line of `at` when only blanks precede it there, else `at`.
pub(crate) fn line_start(text: &str, at: usize) -> usize {
    let s = text[..at].rfind('\n').map_or(0, |p| p + 1);
    if text[s..at].chars().all(|c| c == ' ' || c == '\t') {
        s
    } else {
        at
    }
}

/// Just past the end of the line of `at` (its newline included) when only blanks follow it
/// there, else `at`.
pub(crate) fn line_end(text: &str, at: usize) -> usize {
    let rest = &text[at..];
    let blank = rest.len() - rest.trim_start_matches([' ', '\t']).len();
    if rest[blank..].starts_with('\n') {
        at + blank + 1
    } else if rest[blank..].starts_with("\r\n") {
        at + blank + 2
    } else {
        at
    }
}

/// The blanks before `at` on its line, when only blanks precede it there.
pub(crate) fn indent_at(text: &str, at: usize) -> &str {
    &text[line_start(text, at)..at]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_lines_go() {
        let text = "<a>\n  <b/>\n  <c/>\n</a>\n";
        let b = text.find("<b/>").unwrap_or(0);
        let mut e = Edits::default();
        e.replace_lines(text, b, b + 4, String::new());
        assert_eq!(e.apply(text), "<a>\n  <c/>\n</a>\n");
        assert_eq!(indent_at(text, b), "  ");
    }
}
