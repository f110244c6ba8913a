//! Reading the user's CSV files: an excitation record, a measured decay, a load table.
//!
//! One reader for all of them, on the `csv` crate (RFC 4180 quoting; one row in memory at a
//! time, so a record of any length streams through). The house conventions on top: lines whose
//! first cell starts with `#` and blank lines are skipped, a UTF-8 byte-order mark (spreadsheet
//! exports) is ignored, cells are trimmed, and rows may differ in length (each caller says which
//! cells it needs). Errors name the line (1-based, as an editor shows it) and the column.

use anyhow::{bail, Result};
use std::io::{BufRead, BufReader, Read};

/// The separator of a record typed or exported by hand: `,` if the first content line has one,
/// else `;`, else a tab, else runs of spaces (`b' '`: empty cells are then dropped).
pub fn detect_separator(text: &str) -> u8 {
    let first = text
        .lines()
        .map(|l| l.trim_start_matches('\u{feff}').trim())
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or_default();
    [b',', b';', b'\t']
        .into_iter()
        .find(|&c| first.as_bytes().contains(&c))
        .unwrap_or(b' ')
}

/// The content rows of a CSV source, one at a time.
pub struct Rows<R: Read> {
    reader: csv::Reader<MarkEmpty<BufReader<R>>>,
    record: csv::StringRecord,
    /// Runs of spaces separate the cells: empty cells are dropped.
    spaces: bool,
    first: bool,
}

/// The source with each empty line written as `#` (a comment line): the csv crate skips empty
/// lines into the position of the record after them, which would then name the wrong line.
/// (An empty line inside a quoted cell would gain the `#`: the files read here hold numbers.)
pub struct MarkEmpty<R> {
    inner: R,
    line: Vec<u8>,
    at: usize,
}

impl<R: BufRead> Read for MarkEmpty<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.at == self.line.len() {
            self.line.clear();
            self.at = 0;
            if self.inner.read_until(b'\n', &mut self.line)? == 0 {
                return Ok(0);
            }
            if self.line == b"\n" || self.line == b"\r\n" {
                self.line.insert(0, b'#');
            }
        }
        let n = buf.len().min(self.line.len() - self.at);
        buf[..n].copy_from_slice(&self.line[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

/// One content row: its line and its trimmed cells.
#[derive(Debug)]
pub struct Row<'a> {
    line: u64,
    cells: Vec<&'a str>,
}

impl<R: Read> Rows<R> {
    /// Rows of `source` with cells separated by `separator` (`b','`, or [`detect_separator`]).
    pub fn new(source: R, separator: u8) -> Self {
        let reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .delimiter(separator)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(MarkEmpty {
                inner: BufReader::new(source),
                line: Vec::new(),
                at: 0,
            });
        Self {
            reader,
            record: csv::StringRecord::new(),
            spaces: separator == b' ',
            first: true,
        }
    }

    /// The next content row, `None` at the end. A source that cannot be read (I/O, bytes that
    /// are not UTF-8) is an error naming the line.
    pub fn next_row(&mut self) -> Result<Option<Row<'_>>> {
        loop {
            match self.reader.read_record(&mut self.record) {
                Ok(true) => {}
                Ok(false) => return Ok(None),
                Err(e) => {
                    let line = e.position().map_or(0, csv::Position::line);
                    bail!("line {line}: cannot read ({e})");
                }
            }
            let line = self.record.position().map_or(0, csv::Position::line);
            let first = std::mem::take(&mut self.first);
            let skip = {
                let c = cells_of(&self.record, first, self.spaces);
                c.first().is_none_or(|c| c.starts_with('#')) || c.iter().all(|c| c.is_empty())
            };
            if skip {
                continue;
            }
            let cells = cells_of(&self.record, first, self.spaces);
            return Ok(Some(Row { line, cells }));
        }
    }
}

/// The cells of `record`: the byte-order mark off the `first` record's first cell; empty
/// cells dropped where runs of `spaces` separate them.
fn cells_of(record: &csv::StringRecord, first: bool, spaces: bool) -> Vec<&str> {
    let mut cells: Vec<&str> = record.iter().collect();
    if first {
        if let Some(c) = cells.first_mut() {
            *c = c.trim_start_matches('\u{feff}').trim_start();
        }
    }
    if spaces {
        cells.retain(|c| !c.is_empty());
    }
    cells
}

impl<'a> Row<'a> {
    /// The row's line in the file (1-based).
    pub fn line(&self) -> u64 {
        self.line
    }

    /// The trimmed cells.
    pub fn cells(&self) -> &[&'a str] {
        &self.cells
    }

    /// Cell `i` (0-based) as a finite number; `name` names the column in the error.
    pub fn number(&self, i: usize, name: &str) -> Result<f64> {
        let line = self.line;
        let Some(c) = self.cells.get(i) else {
            bail!(
                "line {line}: no value for column `{name}` (column {})",
                i + 1
            );
        };
        let Ok(v) = c.parse::<f64>() else {
            bail!(
                "line {line}: `{name}` = `{c}` (column {}) is not a number",
                i + 1
            );
        };
        if !v.is_finite() {
            bail!(
                "line {line}: `{name}` = {v} (column {}) is not finite",
                i + 1
            );
        }
        Ok(v)
    }

    /// All cells as numbers, or `None` if one is not a number (a header row).
    pub fn numbers(&self) -> Option<Vec<f64>> {
        self.cells.iter().map(|c| c.parse().ok()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(text: &str, sep: u8) -> Vec<(u64, Vec<String>)> {
        let mut r = Rows::new(text.as_bytes(), sep);
        let mut out = Vec::new();
        while let Some(row) = r.next_row().expect("readable") {
            out.push((
                row.line(),
                row.cells().iter().map(|c| c.to_string()).collect(),
            ));
        }
        out
    }

    /// Comments, blank lines, a byte-order mark, padding and quoting (a quote opens a cell only
    /// right after the separator, as RFC 4180 has it); the lines as an editor numbers them.
    #[test]
    fn rows_skip_comments_and_keep_line_numbers() {
        let text = "\u{feff}# exported\n\n t ,\"a,b\"\n  # note\n0, 1\n   \n2,3,4\n";
        assert_eq!(
            rows(text, b','),
            vec![
                (3, vec!["t".into(), "a,b".into()]),
                (5, vec!["0".into(), "1".into()]),
                (7, vec!["2".into(), "3".into(), "4".into()]),
            ]
        );
    }

    #[test]
    fn separators_are_detected() {
        assert_eq!(detect_separator("# c\nt;a\n"), b';');
        assert_eq!(detect_separator("0\t1\n"), b'\t');
        assert_eq!(detect_separator("0   1\n"), b' ');
        assert_eq!(detect_separator("0, 1\n"), b',');
        assert_eq!(
            rows("0   1\n 2 3 \n", b' '),
            vec![
                (1, vec!["0".into(), "1".into()]),
                (2, vec!["2".into(), "3".into()])
            ]
        );
    }

    #[test]
    fn numbers_name_line_and_column() {
        let mut r = Rows::new("0,x,inf\n".as_bytes(), b',');
        let row = r.next_row().expect("readable").expect("a row");
        assert_eq!(row.number(0, "t").expect("a number"), 0.0);
        let e = row.number(1, "a").unwrap_err().to_string();
        assert_eq!(e, "line 1: `a` = `x` (column 2) is not a number");
        let e = row.number(2, "b").unwrap_err().to_string();
        assert_eq!(e, "line 1: `b` = inf (column 3) is not finite");
        let e = row.number(3, "c").unwrap_err().to_string();
        assert_eq!(e, "line 1: no value for column `c` (column 4)");
        let mut r = Rows::new(&b"0,1\n\xff,2\n"[..], b',');
        r.next_row().expect("first row readable");
        let e = r.next_row().unwrap_err().to_string();
        assert!(e.starts_with("line 2: cannot read"), "{e}");
    }
}
