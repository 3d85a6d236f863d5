//! The grid of a sweep: `--vary KEY=V1,V2,...` ([`Vary`]), their product
//! ([`grid`]), the scene of every combination, validated before any run, and the shards
//! (`--shard K/N`) with their file names, and the grid as its files state it
//! ([`GridFile`]). It runs nothing and writes nothing.

use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::scene::overrides::{Override, OverrideSyntaxError, scene_with_overrides};
use crate::scene::{Scene, SceneError};

pub use super::vary::Vary;

/// `--shard K/N`: the K-th (1-based) of N slices of the grid; combination `i` belongs to
/// shard `i mod N + 1`, so slices are interleaved and of nearly equal cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This slice, 1..=`n`.
    pub k: usize,
    /// Number of slices.
    pub n: usize,
}

impl Shard {
    /// The whole grid.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Whether combination `index` belongs to this shard.
    pub fn contains(self, index: usize) -> bool {
        index % self.n == self.k - 1
    }
}

impl FromStr for Shard {
    type Err = OverrideSyntaxError;

    fn from_str(arg: &str) -> Result<Self, Self::Err> {
        let fail = || OverrideSyntaxError {
            arg: arg.to_owned(),
            rule: "expected K/N with 1 <= K <= N, e.g. 3/8".into(),
        };
        let (k, n) = arg.split_once('/').ok_or_else(fail)?;
        let k: usize = k.trim().parse().map_err(|_| fail())?;
        let n: usize = n.trim().parse().map_err(|_| fail())?;
        if k == 0 || k > n {
            return Err(fail());
        }
        Ok(Self { k, n })
    }
}

/// One point of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Combination {
    /// Place in the full grid (0-based).
    pub index: usize,
    /// One override per varied key, in `--vary` order.
    pub overrides: Vec<Override>,
}

/// The product grid of `varies`, last key fastest. No keys give one empty combination
/// (the scene as it is).
pub fn grid(varies: &[Vary]) -> Vec<Combination> {
    let mut combos: Vec<Vec<Override>> = vec![Vec::new()];
    for v in varies {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                v.values.iter().map(move |setting| {
                    let mut c = c.clone();
                    c.extend(setting.iter().cloned());
                    c
                })
            })
            .collect();
    }
    combos
        .into_iter()
        .enumerate()
        .map(|(index, overrides)| Combination { index, overrides })
        .collect()
}

/// A bad combination: names it and carries the scene's own error.
#[derive(Debug, thiserror::Error)]
#[error("combination {index} ({settings}): {source}")]
pub struct CombinationError {
    /// Place in the grid.
    pub index: usize,
    /// Its overrides, `k=v k=v`.
    pub settings: String,
    /// The scene's error.
    pub source: SceneError,
}

/// Builds and validates the scene of every combination, so that a bad value stops the
/// sweep before any run starts.
pub fn scenes(
    text: &str,
    name: &str,
    combos: &[Combination],
) -> Result<Vec<Scene>, CombinationError> {
    combos
        .iter()
        .map(|c| {
            scene_with_overrides(text, name, &c.overrides).map_err(|source| CombinationError {
                index: c.index,
                settings: settings(&c.overrides),
                source,
            })
        })
        .collect()
}
pub(super) fn settings(overrides: &[Override]) -> String {
    overrides
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

/// The file name of a shard's output: `sweep.csv`, or `sweep.K-of-N.csv`.
pub fn file_name(shard: Shard) -> String {
    if shard == Shard::ALL {
        "sweep.csv".into()
    } else {
        format!("sweep.{}-of-{}.csv", shard.k, shard.n)
    }
}

/// The grid a sweep's file belongs to, written beside it (`sweep.csv` ->
/// `sweep.grid.json`, `sweep.2-of-4.csv` -> `sweep.2-of-4.grid.json`) before its first row:
/// what a merge needs and the rows cannot show, the grid's size (a combination missing at
/// its end, or a whole shard's block, is named) and whether two files are of one sweep.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct GridFile {
    /// The scene's name.
    pub scene: String,
    /// FNV-1a of the scene's text before the grid's overrides, in hex.
    pub scene_fnv1a: String,
    /// Each varied key and its values as given, in `--vary` order.
    pub vary: Vec<(String, Vec<String>)>,
    /// Combinations in the whole grid.
    pub combinations: usize,
    /// This file's shard, `[K, N]` (`None`: the whole grid, or a merge).
    pub shard: Option<[usize; 2]>,
}

impl GridFile {
    /// The grid of `varies` over the scene `name` of text `text`, for `shard`'s file.
    pub fn new(text: &str, name: &str, varies: &[Vary], shard: Shard) -> Self {
        Self {
            scene: name.to_owned(),
            scene_fnv1a: format!("{:016x}", crate::output::folder::fnv1a(text.as_bytes())),
            vary: varies
                .iter()
                .map(|v| (v.name(), v.values.iter().map(|s| Vary::raw(s)).collect()))
                .collect(),
            combinations: varies.iter().map(|v| v.values.len()).product(),
            shard: None,
        }
        .for_shard(shard)
    }

    /// The same grid, for `shard`'s file.
    pub fn for_shard(self, shard: Shard) -> Self {
        Self {
            shard: (shard != Shard::ALL).then_some([shard.k, shard.n]),
            ..self
        }
    }

    /// Where the grid of the sweep file `csv` is written.
    pub fn beside(csv: &Path) -> PathBuf {
        let name = csv.file_name().unwrap_or_default().to_string_lossy();
        let stem = name.strip_suffix(".csv").unwrap_or(&name);
        csv.with_file_name(format!("{stem}.grid.json"))
    }

    /// Whether `other` is the same grid (its shard aside).
    pub fn same_grid(&self, other: &GridFile) -> bool {
        (
            &self.scene,
            &self.scene_fnv1a,
            &self.vary,
            self.combinations,
        ) == (
            &other.scene,
            &other.scene_fnv1a,
            &other.vary,
            other.combinations,
        )
    }

    /// What differs from `other`, in words (empty if the grids are the same).
    pub fn difference(&self, other: &GridFile) -> String {
        if self.scene != other.scene {
            format!("scene {} against {}", self.scene, other.scene)
        } else if self.scene_fnv1a != other.scene_fnv1a {
            format!("scene {}'s text differs", self.scene)
        } else if self.vary != other.vary {
            let show = |g: &GridFile| {
                g.vary
                    .iter()
                    .map(|(k, v)| format!("{k}={}", v.join(",")))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            format!("--vary {} against {}", show(self), show(other))
        } else if self.combinations != other.combinations {
            format!(
                "{} combinations against {}",
                self.combinations, other.combinations
            )
        } else {
            String::new()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vary(arg: &str) -> Vary {
        arg.parse().unwrap()
    }

    #[test]
    fn a_grid_file_sits_beside_its_csv_and_compares_grids_not_shards() {
        assert_eq!(
            GridFile::beside(Path::new("d/sweep.2-of-4.csv")),
            Path::new("d/sweep.2-of-4.grid.json")
        );
        assert_eq!(
            GridFile::beside(Path::new("sweep.csv")),
            Path::new("sweep.grid.json")
        );
        let v = [vary("a.b=1,2,3"), vary("c.d=x,y")];
        let one = GridFile::new("t", "s", &v, Shard { k: 1, n: 2 });
        let two = GridFile::new("t", "s", &v, Shard { k: 2, n: 2 });
        assert_eq!(one.combinations, 6);
        assert!(one.same_grid(&two) && one.difference(&two).is_empty());
        let other = GridFile::new("t", "s", &v[..1], Shard::ALL);
        assert!(!one.same_grid(&other));
        assert!(
            one.difference(&other)
                .contains("--vary a.b=1,2,3 c.d=x,y against a.b=1,2,3")
        );
        let text = GridFile::new("u", "s", &v, Shard::ALL);
        assert!(one.difference(&text).contains("text differs"));
    }

    #[test]
    fn keys_varied_together_take_their_values_together_in_the_product() {
        let g = grid(&[vary("a:b=1:x,2:y"), vary("c=7,8")]);
        let s: Vec<String> = g.iter().map(|c| settings(&c.overrides)).collect();
        assert_eq!(
            s,
            ["a=1 b=x c=7", "a=1 b=x c=8", "a=2 b=y c=7", "a=2 b=y c=8"]
        );
        let file = GridFile::new("t", "s", &[vary("a:b=1:x,2:y")], Shard::ALL);
        assert_eq!(
            file.vary,
            [("a:b".to_owned(), vec!["1:x".to_owned(), "2:y".to_owned()])]
        );
        assert_eq!(file.combinations, 2);
    }

    #[test]
    fn grid_is_the_product_last_key_fastest() {
        let g = grid(&[vary("a=1,2"), vary("b=x,y,z")]);
        assert_eq!(g.len(), 6);
        let s: Vec<String> = g.iter().map(|c| settings(&c.overrides)).collect();
        assert_eq!(s[0], "a=1 b=x");
        assert_eq!(s[1], "a=1 b=y");
        assert_eq!(s[3], "a=2 b=x");
        assert_eq!(s[5], "a=2 b=z");
        assert!(g.iter().enumerate().all(|(i, c)| c.index == i));
        assert_eq!(grid(&[]).len(), 1);
    }

    #[test]
    fn shards_partition_the_grid() {
        for n in 1..=7 {
            for len in [0, 1, 5, 6, 7, 23] {
                let mut count = vec![0; len];
                for k in 1..=n {
                    let s: Shard = format!("{k}/{n}").parse().unwrap();
                    for (i, c) in count.iter_mut().enumerate() {
                        if s.contains(i) {
                            *c += 1;
                        }
                    }
                }
                assert!(
                    count.iter().all(|&c| c == 1),
                    "n = {n}, len = {len}: {count:?}"
                );
            }
        }
        for bad in ["0/3", "4/3", "3", "a/b", "1/0"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
