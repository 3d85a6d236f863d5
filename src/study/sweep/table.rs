//! `sweep.csv` as text and as a table, through the `csv` crate: [`SweepTable`] (read,
//! columns, numbers, the varied keys, back to CSV), the merge of shard files and the
//! merged file's writing. It knows no column but `index` and runs nothing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context as _;

use super::{Col, GridFile, INDEX_COLUMN, Shard, file_name, read_grid};
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
        Self::read_rows(path, false).map(|(t, _)| t)
    }

    /// Reads a sweep file whose writer may have been killed mid-row: a last row without its
    /// newline is left out, and the second value says so.
    pub fn read_cut(path: &Path) -> anyhow::Result<(Self, bool)> {
        Self::read_rows(path, true)
    }

    fn read_rows(path: &Path, allow_cut: bool) -> anyhow::Result<(Self, bool)> {
        let bytes =
            std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let unterminated = allow_cut && bytes.last().is_some_and(|&b| b != b'\n');
        let mut reader = csv::ReaderBuilder::new()
            .flexible(true)
            .from_reader(bytes.as_slice());
        let header: Vec<String> = reader
            .headers()
            .with_context(|| format!("cannot read {}", path.display()))?
            .iter()
            .map(str::to_owned)
            .collect();
        anyhow::ensure!(!header.is_empty(), "{} is empty", path.display());
        let mut rows = Vec::new();
        let records: Vec<csv::StringRecord> = reader
            .records()
            .collect::<Result<_, _>>()
            .with_context(|| format!("cannot read {}", path.display()))?;
        let last = records.len();
        let mut cut = false;
        for (n, record) in records.into_iter().enumerate() {
            let row: Vec<String> = record.iter().map(str::to_owned).collect();
            // Every row is written with its newline at once: a last row without one is cut.
            if unterminated && n + 1 == last {
                cut = true;
                break;
            }
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
        Ok((Self { header, rows }, cut))
    }

    /// The index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The cells of the result column `col` parsed as numbers, as [`numbers`](Self::numbers).
    pub fn col(&self, col: Col) -> Option<Vec<f64>> {
        self.numbers(col.name())
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
        let end = self.column(Col::Links.name()).unwrap_or(self.header.len());
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

/// What a merge found missing: the shards not given (their `K` of `N`, read from the files'
/// names `sweep.K-of-N.csv`), the combinations below the largest index that no file holds,
/// and the files cut mid-row (their complete rows kept). A combination after the last one
/// any given shard ran cannot be seen: the files do not hold the grid's size.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Missing {
    /// `N`, and the shards `K` of it not given.
    pub shards: Option<(usize, Vec<usize>)>,
    /// Combinations no file holds.
    pub combinations: Vec<usize>,
    /// Each file cut mid-row, with its complete rows.
    pub cut: Vec<(PathBuf, usize)>,
}

impl Missing {
    /// Whether nothing is missing.
    pub fn is_empty(&self) -> bool {
        self.shards.as_ref().is_none_or(|(_, k)| k.is_empty())
            && self.combinations.is_empty()
            && self.cut.is_empty()
    }
}

impl std::fmt::Display for Missing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let list = |v: &[usize]| {
            v.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        };
        if let Some((n, ks)) = &self.shards
            && !ks.is_empty()
        {
            let names: Vec<String> = ks.iter().map(|&k| file_name(Shard { k, n: *n })).collect();
            writeln!(
                f,
                "missing, of the {n} shards: shard {} ({})",
                list(ks),
                names.join(", ")
            )?;
        }
        if !self.combinations.is_empty() {
            writeln!(
                f,
                "combinations in no file, by index: {}",
                list(&self.combinations)
            )?;
        }
        for (path, rows) in &self.cut {
            writeln!(
                f,
                "{} is cut mid-row after {rows} complete rows, which the merge takes",
                path.display()
            )?;
        }
        Ok(())
    }
}

/// `K` and `N` of a shard file's name, `sweep.K-of-N.csv`.
fn shard_of(path: &Path) -> Option<Shard> {
    let name = path.file_name()?.to_str()?;
    let (k, n) = name
        .strip_prefix("sweep.")?
        .strip_suffix(".csv")?
        .split_once("-of-")?;
    Some(Shard {
        k: k.parse().ok()?,
        n: n.parse().ok()?,
    })
}

/// Files that are not shards of one sweep: different columns or grids, shards of
/// different splits, a combination in two files or outside its file's shard. Bad input,
/// not a failed merge.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct NotOneSweep(pub String);

/// A merge: the table, what is missing from it, and the grid its files state.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The rows of every file, sorted by `index`.
    pub table: SweepTable,
    /// What is missing (see [`Missing`]).
    pub missing: Missing,
    /// The grid the files' [`GridFile`]s state (`None`: no file had one).
    pub grid: Option<GridFile>,
}

/// Joins shard files into one table sorted by `index`, and says what is missing (see
/// [`Missing`]). Every file must have the same header; an index found twice is an error (a
/// shard run twice, or the same file given twice), as is an index that is not its file's
/// shard's or shard files of different `N` ([`NotOneSweep`]). A file's last row cut short
/// (its writer killed mid-row) is left out and reported. The grid's size comes from the
/// [`GridFile`]s beside the files, which must all state the same grid; for files without
/// one, the rows show it as the product of the values each varied key takes in them, so a
/// combination missing at the grid's end is found unless every row of some value is
/// missing too.
pub fn merge(inputs: &[PathBuf]) -> anyhow::Result<Merged> {
    anyhow::ensure!(!inputs.is_empty(), "nothing to merge");
    let not_one = |text: String| anyhow::Error::new(NotOneSweep(text));
    let mut merged: Option<SweepTable> = None;
    let mut seen: BTreeMap<usize, PathBuf> = BTreeMap::new();
    let mut missing = Missing::default();
    let mut shards: BTreeMap<usize, usize> = BTreeMap::new();
    let mut grid: Option<(GridFile, PathBuf)> = None;
    for path in inputs {
        let (t, cut) = SweepTable::read_cut(path)?;
        if cut {
            missing.cut.push((path.clone(), t.rows.len()));
        }
        agree_grid(path, &mut grid)?;
        let ic = t
            .column(INDEX_COLUMN)
            .with_context(|| format!("{}: no `{INDEX_COLUMN}` column", path.display()))?;
        if let Some(m) = &merged
            && m.header != t.header
        {
            return Err(not_one(format!(
                "{}: its columns differ from those of {} (not shards of one sweep)",
                path.display(),
                inputs[0].display()
            )));
        }
        let shard = shard_of(path);
        if let Some(s) = shard {
            shards.insert(s.k, s.n);
        }
        let size = grid.as_ref().map(|(g, _)| g.combinations);
        for r in &t.rows {
            let i: usize = r[ic].parse().with_context(|| {
                format!("{}: `{}` is not a combination index", path.display(), r[ic])
            })?;
            place(i, path, shard, size, &mut seen)?;
        }
        match &mut merged {
            None => merged = Some(t),
            Some(m) => m.rows.extend(t.rows),
        }
    }
    let ns: std::collections::BTreeSet<usize> = shards.values().copied().collect();
    if ns.len() > 1 {
        return Err(not_one(format!(
            "the files are shards of different splits (of {})",
            ns.iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", of ")
        )));
    }
    if let Some(&n) = ns.first() {
        let absent = (1..=n).filter(|k| !shards.contains_key(k)).collect();
        missing.shards = Some((n, absent));
    }
    let mut m = merged.expect("at least one input");
    let end = seen.keys().next_back().map_or(0, |&last| last + 1);
    let size = match &grid {
        Some((g, _)) => g.combinations,
        None => grid_size(&m).unwrap_or(0).max(end),
    };
    missing.combinations = (0..size).filter(|i| !seen.contains_key(i)).collect();
    let ic = m.column(INDEX_COLUMN).expect("checked above");
    m.rows
        .sort_by_key(|r| r[ic].parse::<usize>().unwrap_or(usize::MAX));
    Ok(Merged {
        table: m,
        missing,
        grid: grid.map(|(g, _)| g.for_shard(Shard::ALL)),
    })
}

/// Reads the grid stated beside the file `path`, if any, into `grid` (with the file that
/// stated it first); a grid that differs from it is not one sweep's.
fn agree_grid(path: &Path, grid: &mut Option<(GridFile, PathBuf)>) -> anyhow::Result<()> {
    let grid_path = GridFile::beside(path);
    if !grid_path.exists() {
        return Ok(());
    }
    let g = read_grid(&grid_path)?;
    match grid {
        Some((first, from)) if !first.same_grid(&g) => Err(NotOneSweep(format!(
            "{} and {} are of different grids ({}): not shards of one sweep",
            from.display(),
            path.display(),
            first.difference(&g)
        ))
        .into()),
        Some(_) => Ok(()),
        None => {
            *grid = Some((g, path.to_owned()));
            Ok(())
        }
    }
}

/// Records combination `i`, read from `path` (of `shard`, in a grid of `size`), in `seen`:
/// one outside its file's shard or grid, or already seen, is not one sweep's.
fn place(
    i: usize,
    path: &Path,
    shard: Option<Shard>,
    size: Option<usize>,
    seen: &mut BTreeMap<usize, PathBuf>,
) -> Result<(), NotOneSweep> {
    let shown = path.display();
    if let Some(s) = shard
        && !s.contains(i)
    {
        return Err(NotOneSweep(format!(
            "{shown}: combination {i} is not in shard {} of {}",
            s.k, s.n
        )));
    }
    if let Some(n) = size
        && i >= n
    {
        return Err(NotOneSweep(format!(
            "{shown}: combination {i} is not in its grid of {n}"
        )));
    }
    if let Some(first) = seen.insert(i, path.to_owned()) {
        return Err(NotOneSweep(format!(
            "combination {i} is in both {} and {shown}",
            first.display()
        )));
    }
    Ok(())
}

/// The size of the grid `t`'s rows come from: the product over the varied keys' columns
/// (those between `index` and `links`) of the values its rows hold, a number however it is
/// spelt (`0.1`, `0.10`). `None` for a table without result columns, whose keys are not
/// known.
fn grid_size(t: &SweepTable) -> Option<usize> {
    let links = t.column(Col::Links.name())?;
    let value = |cell: &str| match cell.parse::<f64>() {
        Ok(v) => format!("{:x}", v.to_bits()),
        Err(_) => cell.to_owned(),
    };
    Some(
        (1..links)
            .map(|c| {
                t.rows
                    .iter()
                    .map(|r| value(&r[c]))
                    .collect::<std::collections::BTreeSet<_>>()
                    .len()
            })
            .product(),
    )
}

/// Writes a merge to `dir/sweep.csv` (atomically), with the grid its files stated beside it
/// (`sweep.grid.json`, see [`GridFile`]), and returns the CSV's path.
pub fn write_merged(merged: &Merged, dir: &Path) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let path = dir.join(file_name(Shard::ALL));
    let grid_path = GridFile::beside(&path);
    match &merged.grid {
        Some(g) => {
            let text = serde_json::to_string_pretty(g).context("cannot write the grid")?;
            write_atomic(&grid_path, text.as_bytes())?;
        }
        None => crate::output::remove_stale(&grid_path)?,
    }
    write_atomic(&path, merged.table.to_csv().as_bytes())?;
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
        let merged = merge(&[a.clone(), b.clone()]).unwrap();
        let (m, missing) = (&merged.table, &merged.missing);
        assert!(missing.is_empty(), "{missing}");
        let idx: Vec<&str> = m.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(idx, ["0", "1", "2"]);
        assert_eq!(m.rows[0][2], "failed: a, b");
        let out = write_merged(&merged, &d.join("out")).unwrap();
        assert_eq!(&SweepTable::read(&out).unwrap(), m);

        let other = write(d, "c.csv", "index,j,status\n3,z,ok\n");
        let e = merge(&[a.clone(), other]).unwrap_err().to_string();
        assert!(e.contains("its columns differ"), "{e}");
        let e = merge(&[a.clone(), b, a]).unwrap_err().to_string();
        assert!(e.contains("combination 2 is in both"), "{e}");
        let short = write(d, "d.csv", "index,k,status\n4,z\n");
        let e = merge(&[short]).unwrap_err().to_string();
        assert!(e.contains("line 2: 2 cells, the header has 3"), "{e}");
    }

    #[test]
    fn merge_names_missing_shards_gaps_and_cut_files() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let one = write(d, "sweep.1-of-3.csv", "index,k,status\n0,a,ok\n3,b,ok\n");
        let three = write(d, "sweep.3-of-3.csv", "index,k,status\n2,c,ok\n5,d,o");
        let Merged {
            table: m, missing, ..
        } = merge(&[one.clone(), three.clone()]).unwrap();
        assert_eq!(m.rows.len(), 3);
        assert_eq!(missing.shards, Some((3, vec![2])));
        assert_eq!(missing.combinations, [1]);
        assert_eq!(missing.cut, [(three.clone(), 1)]);
        let text = missing.to_string();
        assert!(
            text.contains("missing, of the 3 shards: shard 2 (sweep.2-of-3.csv)"),
            "{text}"
        );
        assert!(
            text.contains("is cut mid-row after 1 complete rows, which the merge takes"),
            "{text}"
        );
        // A task killed between rows leaves a file that ends with a whole row: the last
        // combinations are missing, and the grid's size, shown by the other rows, says so.
        let head = "index,a,b,links,status\n";
        let one = write(
            d,
            "sweep.1-of-2.csv",
            &format!("{head}0,1,x,9,ok\n2,1,z,9,ok\n"),
        );
        let two = write(
            d,
            "sweep.2-of-2.csv",
            &format!("{head}1,1,y,9,ok\n3,2,x,9,ok\n"),
        );
        let missing = merge(&[one, two]).unwrap().missing;
        assert_eq!(missing.combinations, [4, 5]);
        // A value spelt two ways is one value: nothing missing.
        let one = write(
            d,
            "sweep.1-of-2.csv",
            &format!("{head}0,1,x,9,ok\n2,1.0,z,9,ok\n"),
        );
        let two = write(d, "sweep.2-of-2.csv", &format!("{head}1,1,y,9,ok\n"));
        let missing = merge(&[one, two]).unwrap().missing;
        assert!(missing.is_empty(), "{missing}");
        let one = write(d, "sweep.1-of-3.csv", "index,k,status\n0,a,ok\n3,b,ok\n");
        // An index that is not its file's shard's.
        let wrong = write(d, "sweep.2-of-3.csv", "index,k,status\n2,e,ok\n");
        let e = merge(&[one, wrong]).unwrap_err().to_string();
        assert!(e.contains("combination 2 is not in shard 2 of 3"), "{e}");
    }

    #[test]
    fn the_grid_beside_the_files_names_a_missing_block_and_refuses_another_grid() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let vary = |arg: &str| arg.parse::<super::super::Vary>().unwrap();
        let v = [vary("a=1,2,3"), vary("b=x,y")];
        let grid = |k, n| GridFile::new("text", "s", &v, Shard { k, n });
        let put = |name: &str, g: &GridFile, rows: &str| {
            let csv = write(d, name, &format!("index,a,b,links,status\n{rows}"));
            let text = serde_json::to_string(g).unwrap();
            std::fs::write(GridFile::beside(&csv), text).unwrap();
            csv
        };
        // Shard 1 of 2 ran its first rows only; shard 2 holds every row of a = 1 and 2.
        // The rows show a 2 x 2 grid, nothing missing; the grid file says 3 x 2.
        let one = put("sweep.1-of-2.csv", &grid(1, 2), "0,1,x,9,ok\n2,2,x,9,ok\n");
        let two = put("sweep.2-of-2.csv", &grid(2, 2), "1,1,y,9,ok\n3,2,y,9,ok\n");
        let merged = merge(&[one.clone(), two.clone()]).unwrap();
        assert_eq!(merged.missing.combinations, [4, 5]);
        assert_eq!(merged.grid, Some(grid(1, 1)));
        let out = write_merged(&merged, &d.join("out")).unwrap();
        assert_eq!(read_grid(&GridFile::beside(&out)).unwrap(), grid(1, 1));
        // Without the grid files the merge can only infer the grid from the rows.
        std::fs::remove_file(GridFile::beside(&one)).unwrap();
        std::fs::remove_file(GridFile::beside(&two)).unwrap();
        assert!(merge(&[one.clone(), two]).unwrap().missing.is_empty());
        // A file of another grid is not a shard of this sweep.
        let one = put("sweep.1-of-2.csv", &grid(1, 2), "0,1,x,9,ok\n");
        let other = GridFile::new("text", "s", &v[..1], Shard { k: 2, n: 2 });
        let two = put("sweep.2-of-2.csv", &other, "1,1,y,9,ok\n");
        let e = merge(&[one, two]).unwrap_err();
        assert!(e.downcast_ref::<NotOneSweep>().is_some(), "{e}");
        assert!(
            e.to_string()
                .contains("are of different grids (--vary a=1,2,3 b=x,y against a=1,2,3)"),
            "{e}"
        );
    }
}
