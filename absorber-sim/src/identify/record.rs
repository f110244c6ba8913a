//! A measured record: CSV columns read into a time series (time, one signal).

use super::MAX_SAMPLES;
use crate::csvio;
use anyhow::{bail, Context, Result};
use std::path::Path;

/// A record: uniform time step and the chosen column.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Time step \[s\].
    pub dt: f64,
    /// Start time \[s\].
    pub t0: f64,
    /// Samples.
    pub x: Vec<f64>,
}

/// Reads column `column` and time column `time` of a CSV (comment lines `#`, then a header row
/// of names, then numbers), line by line (the file is never held whole). Errors name the file,
/// line and column; a record longer than [`MAX_SAMPLES`] is refused when its row is reached.
pub fn read_csv(path: &Path, time: &str, column: &str) -> Result<Record> {
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot read `{}`", path.display()))?;
    parse(file, time, column).with_context(|| format!("`{}`", path.display()))
}

/// As [`read_csv`], from text.
pub fn parse_csv(text: &str, time: &str, column: &str) -> Result<Record> {
    parse(text.as_bytes(), time, column)
}

fn parse(source: impl std::io::Read, time: &str, column: &str) -> Result<Record> {
    // The separator from the first content line (comma, semicolon, tab or spaces, as the
    // excitation record's): the lines up to it are read ahead, the rest streams.
    use std::io::{BufRead, Read};
    let mut source = std::io::BufReader::new(source);
    let mut head = Vec::new();
    loop {
        let start = head.len();
        if source.read_until(b'\n', &mut head)? == 0 {
            break;
        }
        let line = String::from_utf8_lossy(&head[start..]);
        let line = line.trim_start_matches('\u{feff}').trim();
        if !line.is_empty() && !line.starts_with('#') {
            break;
        }
    }
    let separator = csvio::detect_separator(&String::from_utf8_lossy(&head));
    let mut rows = csvio::Rows::new(head.as_slice().chain(source), separator);
    let Some(header) = rows.next_row()? else {
        bail!("no header row (expected column names, e.g. `t,{column}`)");
    };
    let names: Vec<String> = header.cells().iter().map(|c| c.to_string()).collect();
    let find = |name: &str, what: &str| {
        names.iter().position(|n| *n == name).ok_or_else(|| {
            anyhow::anyhow!(
                "invalid value for `{what}`: no column `{name}` (columns: {})",
                names.join(", ")
            )
        })
    };
    let (it, ix) = (find(time, "--time-column")?, find(column, "--column")?);
    let (mut t, mut x) = (Vec::new(), Vec::new());
    while let Some(row) = rows.next_row()? {
        if x.len() == MAX_SAMPLES {
            bail!(
                "line {}: the record is longer than {MAX_SAMPLES} samples, the most `identify` reads (it holds the record and its spectra in memory); decimate it or cut it to the decay",
                row.line()
            );
        }
        t.push(row.number(it, time)?);
        x.push(row.number(ix, column)?);
    }
    if x.len() < 64 {
        bail!("too short: {} samples (at least 64)", x.len());
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    if dt.is_nan() || dt <= 0.0 {
        bail!("invalid time column `{time}`: not increasing");
    }
    for (k, w) in t.windows(2).enumerate() {
        if ((w[1] - w[0]) / dt - 1.0).abs() > 1e-3 {
            bail!(
                "invalid time column `{time}`: not uniformly sampled (step {:.6e} s after row {}, mean {dt:.6e} s); resample the record",
                w[1] - w[0],
                k + 1
            );
        }
    }
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
        bail!(
            "invalid value for `--column`: `{column}` is constant ({lo}): no response to identify"
        );
    }
    Ok(Record { dt, t0: t[0], x })
}
