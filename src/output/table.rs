//! A table built once and rendered as Markdown or as aligned plain text, in the manner of
//! hyperfine's exporters: the paradox table, the spins, the forces and torques, and the
//! hard cases all go through it. It holds strings; it computes nothing.

/// A header and rows of cells, already formatted.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Table {
    /// Column titles.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with these column titles.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        Self {
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn push<S: Into<String>>(&mut self, row: impl IntoIterator<Item = S>) {
        self.rows.push(row.into_iter().map(Into::into).collect());
    }

    /// As a Markdown table, one line each for the header, the rule and every row.
    pub fn markdown(&self) -> String {
        let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
        let mut o = line(&self.header);
        o.push('|');
        o.push_str(&"---|".repeat(self.header.len()));
        o.push('\n');
        for row in &self.rows {
            o.push_str(&line(row));
        }
        o
    }

    /// As plain text, each line led by `indent`, each column as wide as its widest cell,
    /// two spaces apart: numbers aligned right, words (the first column, and any column with
    /// a cell that does not start with a number) left.
    pub fn text(&self, indent: &str) -> String {
        let widths: Vec<usize> = (0..self.header.len())
            .map(|c| {
                std::iter::once(&self.header)
                    .chain(&self.rows)
                    .filter_map(|r| r.get(c))
                    .map(|s| s.chars().count())
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let left: Vec<bool> = (0..self.header.len())
            .map(|c| {
                c == 0
                    || !self
                        .rows
                        .iter()
                        .all(|r| r.get(c).is_none_or(|s| numeric(s)))
            })
            .collect();
        let line = |cells: &[String]| {
            let padded: Vec<String> = cells
                .iter()
                .zip(&widths)
                .enumerate()
                .map(|(c, (s, &w))| {
                    if left[c] {
                        format!("{s:<w$}")
                    } else {
                        format!("{s:>w$}")
                    }
                })
                .collect();
            format!("{indent}{}\n", padded.join("  "))
        };
        let mut o = line(&self.header);
        for row in &self.rows {
            o.push_str(&line(row));
        }
        o
    }
}

/// Whether a cell reads as a number: its first word parses as one, or it is a dash.
fn numeric(cell: &str) -> bool {
    let first = cell.split_whitespace().next().unwrap_or("");
    first == "-" || first.trim_end_matches('%').parse::<f64>().is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Table {
        let mut t = Table::new(["r", "sim s", "eq.7 s"]);
        t.push(["0.5R", "2.0734", "2.2341"]);
        t.push(["2b", "2.2602", "-"]);
        t
    }

    #[test]
    fn markdown_has_a_rule_under_the_header() {
        assert_eq!(
            sample().markdown(),
            "| r | sim s | eq.7 s |\n|---|---|---|\n| 0.5R | 2.0734 | 2.2341 |\n| 2b | 2.2602 | - |\n"
        );
    }

    #[test]
    fn text_aligns_words_left_and_numbers_right() {
        let mut t = Table::new(["case", "outcome", "wall s"]);
        t.push(["yoga", "completed", "0.07"]);
        t.push(["coarse-step", "stopped", "-"]);
        assert_eq!(
            t.text(""),
            "case         outcome    wall s\nyoga         completed    0.07\ncoarse-step  stopped         -\n"
        );
    }

    #[test]
    fn text_aligns_the_first_column_left_and_the_rest_right() {
        assert_eq!(
            sample().text("  "),
            "  r      sim s  eq.7 s\n  0.5R  2.0734  2.2341\n  2b    2.2602       -\n"
        );
    }
}
