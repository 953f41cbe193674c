//! `--shard K/N`: a batch job's share of a list of work (a study's clips, `bake`'s models), so
//! that any scheduler (a Slurm job array, GNU parallel, a CI matrix) can spread it over
//! machines. Item `i` (0-based, in the list's own order) belongs to shard `i mod N + 1`:
//! deterministic, independent of the machine and of what the other shards did, and the shards'
//! sizes differ by at most one.

use std::fmt;
use std::str::FromStr;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// 1-based: Slurm's `$SLURM_ARRAY_TASK_ID` with `--array=1-N`, GNU parallel's `{}` over
    /// `seq N`.
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Whether item `i` of the list is this shard's.
    pub fn takes(&self, i: usize) -> bool {
        i % self.count == self.index - 1
    }

    /// The items of `items` that are this shard's, in their order.
    pub fn share<T: Clone>(&self, items: &[T]) -> Vec<T> {
        items
            .iter()
            .enumerate()
            .filter(|(i, _)| self.takes(*i))
            .map(|(_, t)| t.clone())
            .collect()
    }

    /// `shards/2-of-8.json`'s stem.
    pub fn file_stem(&self) -> String {
        format!("{}-of-{}", self.index, self.count)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("shard '{s}' is not K/N with 1 ≤ K ≤ N (e.g. 2/8)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_split_a_list_into_disjoint_shares_that_cover_it() {
        let items: Vec<usize> = (0..11).collect();
        let mut seen = Vec::new();
        for k in 1..=4 {
            let share = Shard { index: k, count: 4 }.share(&items);
            assert!((2..=3).contains(&share.len()), "{share:?}");
            seen.extend(share);
        }
        seen.sort();
        assert_eq!(seen, items);
        assert_eq!("2/4".parse::<Shard>().unwrap().share(&items), [1, 5, 9]);
    }

    #[test]
    fn a_shard_out_of_its_range_is_refused() {
        for bad in ["0/4", "5/4", "1/0", "3", "a/b", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        assert_eq!("1/1".parse::<Shard>().unwrap().to_string(), "1/1");
    }
}
