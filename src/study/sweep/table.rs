//! `sweep.csv` as text and as a table, through the `csv` crate: [`SweepTable`] (read,
//! columns, numbers, the varied keys, back to CSV), the merge of shard files and the
//! merged file's writing. It knows no column but `index` and runs nothing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::{INDEX_COLUMN, Shard, file_name};
use crate::output::write_atomic;

/// One CSV line (no line break) of `cells`, quoted where a cell needs it (the `csv`
/// crate, RFC 4180).
pub fn csv_line(cells: &[String]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(cells)
        .expect("writing to memory cannot fail");
    let mut bytes = w.into_inner().expect("writing to memory cannot fail");
    bytes.pop(); // the record's line break
    String::from_utf8(bytes).expect("UTF-8 cells make a UTF-8 line")
}

/// A sweep file in memory: header and rows of cells.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepTable {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl SweepTable {
    /// Reads a sweep (or any header-first) CSV file; a row of the wrong length is an error.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .from_path(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let header: Vec<String> = reader
            .headers()
            .with_context(|| format!("cannot read {}", path.display()))?
            .iter()
            .map(str::to_owned)
            .collect();
        anyhow::ensure!(!header.is_empty(), "{} is empty", path.display());
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.with_context(|| format!("cannot read {}", path.display()))?;
            let row: Vec<String> = record.iter().map(str::to_owned).collect();
            anyhow::ensure!(
                row.len() == header.len(),
                "{} line {}: {} cells, the header has {}",
                path.display(),
                record.position().map_or(0, csv::Position::line),
                row.len(),
                header.len()
            );
            rows.push(row);
        }
        Ok(Self { header, rows })
    }

    /// The index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The cells of column `name` parsed as numbers (`NaN` where empty or not a number).
    pub fn numbers(&self, name: &str) -> Option<Vec<f64>> {
        let c = self.column(name)?;
        Some(
            self.rows
                .iter()
                .map(|r| r[c].parse().unwrap_or(f64::NAN))
                .collect(),
        )
    }

    /// The varied keys: the columns between `index` and `links`.
    pub fn varied_keys(&self) -> Vec<String> {
        let end = self.column("links").unwrap_or(self.header.len());
        self.header
            .iter()
            .take(end)
            .skip(1)
            .cloned()
            .collect::<Vec<_>>()
    }

    /// The text of the table as CSV.
    pub fn to_csv(&self) -> String {
        let mut s = csv_line(&self.header);
        s.push('\n');
        for r in &self.rows {
            s.push_str(&csv_line(r));
            s.push('\n');
        }
        s
    }
}

/// Joins shard files into one table sorted by `index`. Every file must have the same
/// header; an index found twice is an error (a shard run twice, or the same file given
/// twice).
pub fn merge(inputs: &[PathBuf]) -> anyhow::Result<SweepTable> {
    anyhow::ensure!(!inputs.is_empty(), "nothing to merge");
    let mut merged: Option<SweepTable> = None;
    let mut seen: BTreeMap<usize, PathBuf> = BTreeMap::new();
    for path in inputs {
        let t = SweepTable::read(path)?;
        let ic = t
            .column(INDEX_COLUMN)
            .with_context(|| format!("{}: no `{INDEX_COLUMN}` column", path.display()))?;
        if let Some(m) = &merged {
            anyhow::ensure!(
                m.header == t.header,
                "{}: its columns differ from those of {} (not shards of one sweep)",
                path.display(),
                inputs[0].display()
            );
        }
        for r in &t.rows {
            let i: usize = r[ic].parse().with_context(|| {
                format!("{}: `{}` is not a combination index", path.display(), r[ic])
            })?;
            if let Some(first) = seen.insert(i, path.clone()) {
                anyhow::bail!(
                    "combination {i} is in both {} and {}",
                    first.display(),
                    path.display()
                );
            }
        }
        match &mut merged {
            None => merged = Some(t),
            Some(m) => m.rows.extend(t.rows),
        }
    }
    let mut m = merged.expect("at least one input");
    let ic = m.column(INDEX_COLUMN).expect("checked above");
    m.rows
        .sort_by_key(|r| r[ic].parse::<usize>().unwrap_or(usize::MAX));
    Ok(m)
}
/// Writes a merged table to `dir/sweep.csv` (atomically) and returns the path.
pub fn write_merged(table: &SweepTable, dir: &Path) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let path = dir.join(file_name(Shard::ALL));
    write_atomic(&path, table.to_csv().as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_cells_round_trip() {
        let cells: Vec<String> = ["a", "b,c", "say \"hi\"", "", "failed: x, y"]
            .iter()
            .map(|s| (*s).to_owned())
            .collect();
        let line = csv_line(&cells);
        assert_eq!(line, "a,\"b,c\",\"say \"\"hi\"\"\",,\"failed: x, y\"");
        let dir = tempfile::tempdir().unwrap();
        let p = write(dir.path(), "t.csv", &format!("{line}\n{line}\n"));
        assert_eq!(SweepTable::read(&p).unwrap().rows, [cells]);
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn merge_sorts_by_index_and_refuses_mismatches() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let a = write(d, "a.csv", "index,k,status\n2,x,ok\n0,y,\"failed: a, b\"\n");
        let b = write(d, "b.csv", "index,k,status\n1,z,ok\n");
        let m = merge(&[a.clone(), b.clone()]).unwrap();
        let idx: Vec<&str> = m.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(idx, ["0", "1", "2"]);
        assert_eq!(m.rows[0][2], "failed: a, b");
        let out = write_merged(&m, &d.join("out")).unwrap();
        assert_eq!(SweepTable::read(&out).unwrap(), m);

        let other = write(d, "c.csv", "index,j,status\n3,z,ok\n");
        let e = merge(&[a.clone(), other]).unwrap_err().to_string();
        assert!(e.contains("its columns differ"), "{e}");
        let e = merge(&[a.clone(), b, a]).unwrap_err().to_string();
        assert!(e.contains("combination 2 is in both"), "{e}");
        let short = write(d, "d.csv", "index,k,status\n4,z\n");
        let e = merge(&[short]).unwrap_err().to_string();
        assert!(e.contains("line 2: 2 cells, the header has 3"), "{e}");
    }
}
