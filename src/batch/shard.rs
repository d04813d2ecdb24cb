//! `--shard I/N`: a deterministic share of a batch's inputs, so that N processes (GNU parallel,
//! a Slurm job array) given the same inputs convert each map exactly once between them.

use crate::error::{Error, Result};

/// Share `index` of `count` (0 <= index < count).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Shard {
    /// Which share, I: from 0 to `count - 1`.
    pub index: usize,
    /// How many shares, N (at least 1).
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = Error;
    fn from_str(s: &str) -> Result<Shard> {
        let bad = |why: &str| Error::invalid(format!("shard '{s}': {why}"));
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| bad("write it I/N, e.g. 0/4 (share I of N, I from 0 to N-1)"))?;
        let parse = |v: &str| {
            v.trim()
                .parse::<usize>()
                .map_err(|_| bad("I and N are whole numbers"))
        };
        let (index, count) = (parse(i)?, parse(n)?);
        if count == 0 || index >= count {
            return Err(bad(&format!(
                "I must be from 0 to N-1 = {}",
                count.saturating_sub(1)
            )));
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// The share's items of a list in a fixed order (the batch sorts by output name): every
    /// N-th from the I-th, so the shares differ in size by at most one item.
    pub fn select<T>(&self, items: Vec<T>) -> Vec<T> {
        items
            .into_iter()
            .enumerate()
            .filter(|(i, _)| i % self.count == self.index)
            .map(|(_, t)| t)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shares_partition_the_items() {
        let items: Vec<usize> = (0..23).collect();
        let mut all: Vec<usize> = (0..4)
            .flat_map(|i| Shard { index: i, count: 4 }.select(items.clone()))
            .collect();
        all.sort();
        assert_eq!(all, items);
        assert_eq!(Shard { index: 3, count: 4 }.select(items).len(), 5);
    }

    #[test]
    fn parses_i_of_n_and_refuses_the_rest() {
        assert_eq!(
            "2/8".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 8 }
        );
        for bad in ["8/8", "1/0", "1", "-1/2", "a/b"] {
            let e = bad.parse::<Shard>().unwrap_err().to_string();
            assert!(e.contains(bad), "{e}");
        }
    }
}
